"""BLEU and METEOR between a SUT caption and the reference caption (nltk).

Settings that change the numbers (reported next to them in ``SETTINGS``):
- tokens: lower-cased Unicode word runs (apostrophes and hyphens inside words kept),
  punctuation dropped; no nltk tokenizer models are needed.
- BLEU: sentence BLEU, 4-gram, uniform weights, Chen & Cherry smoothing method 1
  (epsilon 0.1 for empty n-gram counts), nltk's brevity penalty.
- METEOR: nltk ``meteor_score`` (alpha 0.9, beta 3, gamma 0.5) with exact, Porter-stem
  and WordNet 3.0 synonym matching.  As nltk implements it, the synonym stage compares
  against Porter-stemmed leftovers, so a synonym whose stem differs from the word
  ("automobile" -> "automobil") is not found: nltk's behaviour, kept for comparability.
An empty caption scores 0 on both.
"""
from __future__ import annotations

import re
import threading

SETTINGS = {"tokens": "lowercase word runs, punctuation dropped",
            "bleu": "sentence BLEU-4, uniform weights, smoothing Chen-Cherry method1 (epsilon 0.1)",
            "meteor": "nltk meteor_score alpha=0.9 beta=3 gamma=0.5, WordNet 3.0 synonyms"}

_WORD = re.compile(r"[^\W_]+(?:['’-][^\W_]+)*")
_lock = threading.Lock()
_wordnet_ready = False


def tokens(text: str | None) -> list[str]:
    return _WORD.findall((text or "").lower())


def bleu(hypothesis: str, reference: str) -> float:
    from nltk.translate.bleu_score import SmoothingFunction, sentence_bleu

    hyp, ref = tokens(hypothesis), tokens(reference)
    if not hyp or not ref:
        return 0.0
    return float(sentence_bleu([ref], hyp, smoothing_function=SmoothingFunction().method1))


def meteor(hypothesis: str, reference: str) -> float:
    hyp, ref = tokens(hypothesis), tokens(reference)
    if not hyp or not ref:
        return 0.0
    _ensure_wordnet()
    from nltk.translate.meteor_score import meteor_score

    return float(meteor_score([ref], hyp))


def _ensure_wordnet() -> None:
    """Point nltk at the project's WordNet copy, making it first if setup has not run yet."""
    global _wordnet_ready
    if _wordnet_ready:
        return
    with _lock:
        if _wordnet_ready:
            return
        import nltk

        from ..setup_data import default_nltk_data, install_wordnet, wordnet_ready

        root = default_nltk_data()
        if not wordnet_ready(root):
            install_wordnet(root)  # raises FileNotFoundError naming the apt packages and the command
        if str(root) not in nltk.data.path:
            nltk.data.path.insert(0, str(root))
        _wordnet_ready = True
