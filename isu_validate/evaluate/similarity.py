"""Embedding similarity (F_emb) and BERTScore between two captions, on all-MiniLM-L6-v2.

F_emb: cosine of the two sentence embeddings (mean-pooled and normalised, as the model is published).
A zero vector has no direction: its cosine with anything is defined as 0.

BERTScore (Zhang et al. 2020): token embeddings of layer ``BERT_LAYER`` (6, the last
of MiniLM-L6), [CLS]/[SEP] dropped, L2-normalised; precision = mean over caption
tokens of the best cosine to a reference token, recall the reverse, F1 their harmonic
mean.  No idf weighting, not rescaled with a baseline (so values sit high, ~0.6-1.0).
We compute it on the shared model rather than through torchmetrics, which reloads the
model on every call; a test checks the two agree.
Inputs longer than the model's window are truncated (256 tokens for F_emb, 512 for
BERTScore); ``truncated`` says so.
"""
from __future__ import annotations

import numpy as np

from .models import minilm, torch_threads

BERT_LAYER = 6
BERT_MAX_TOKENS = 512
SETTINGS = {"f_emb": "cosine of all-MiniLM-L6-v2 sentence embeddings (max 256 tokens)",
            "f_bert": f"BERTScore F1, all-MiniLM-L6-v2 layer {BERT_LAYER}, no idf, unrescaled "
                      f"(max {BERT_MAX_TOKENS} tokens)"}


def cosine(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, dtype=np.float64).ravel(), np.asarray(b, dtype=np.float64).ravel()
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0.0 or nb == 0.0 or not np.isfinite(na * nb):
        return 0.0
    return float(np.clip(a @ b / (na * nb), -1.0, 1.0))


def embed(texts: list[str]) -> np.ndarray:
    return minilm().embed(texts)


def f_emb(caption: str, reference: str) -> float:
    if not caption.strip() or not reference.strip():
        return 0.0
    a, b = embed([caption, reference])
    return cosine(a, b)


def is_truncated(text: str, limit: int | None = None) -> bool:
    model = minilm()
    return model.token_count(text) > (limit or model.max_seq_length)


def _token_embeddings(text: str):
    import torch

    model = minilm()
    encoded = model.tokenizer(text, return_tensors="pt", truncation=True, max_length=BERT_MAX_TOKENS)
    with torch.inference_mode(), torch_threads():
        out = model.model(**encoded, output_hidden_states=True)
    tokens = out.hidden_states[BERT_LAYER][0, 1:-1]  # drop [CLS] and [SEP]
    return torch.nn.functional.normalize(tokens, dim=-1)


def bertscore(caption: str, reference: str) -> dict[str, float]:
    """{"precision", "recall", "f1"}; all 0 when either side has no tokens."""
    zero = {"precision": 0.0, "recall": 0.0, "f1": 0.0}
    if not caption.strip() or not reference.strip():
        return zero
    cand, ref = _token_embeddings(caption), _token_embeddings(reference)
    if len(cand) == 0 or len(ref) == 0:
        return zero
    sim = cand @ ref.T
    precision, recall = float(sim.max(dim=1).values.mean()), float(sim.max(dim=0).values.mean())
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return {"precision": precision, "recall": recall, "f1": f1}
