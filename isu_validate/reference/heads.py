"""One linear classifier per predicted feature on the backbone's features.

Stored as plain arrays (``heads.npz`` + ``heads.json``), so loading needs neither
scikit-learn nor pickle: standardise, multiply, softmax.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputNotFound


@dataclass
class Head:
    feature: str
    classes: list[str]
    mean: np.ndarray      # (D,) feature standardisation
    scale: np.ndarray     # (D,)
    weight: np.ndarray    # (C, D); a single-class head has C = 1 and always answers that class
    bias: np.ndarray      # (C,)

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        if len(self.classes) == 1:
            return np.ones((len(features), 1))
        z = ((features - self.mean) / self.scale) @ self.weight.T + self.bias
        if z.shape[1] == 1:  # binary logistic regression stores one row
            z = np.concatenate([-z, z], axis=1) / 2
        z -= z.max(axis=1, keepdims=True)
        p = np.exp(z)
        return p / p.sum(axis=1, keepdims=True)

    def predict(self, features: np.ndarray) -> list[str]:
        return [self.classes[i] for i in self.probabilities(features).argmax(axis=1)]


def fit_head(feature: str, X: np.ndarray, y: list[str], C: float = 0.05, seed: int = 0) -> Head:
    """L2-regularised multinomial logistic regression on standardised features."""
    from sklearn.linear_model import LogisticRegression

    classes = sorted(set(y))
    mean = X.mean(axis=0)
    scale = X.std(axis=0)
    scale[scale < 1e-6] = 1.0  # constant features (dead channels) must not divide by zero
    if len(classes) == 1:
        return Head(feature, classes, mean, scale, np.zeros((1, X.shape[1])), np.zeros(1))
    model = LogisticRegression(C=C, max_iter=2000, random_state=seed)
    model.fit((X - mean) / scale, y)
    return Head(feature, [str(c) for c in model.classes_], mean, scale, model.coef_, model.intercept_)


def save_heads(heads: list[Head], folder: Path, meta: dict) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    arrays = {}
    for h in heads:
        for part in ("mean", "scale", "weight", "bias"):
            arrays[f"{h.feature}.{part}"] = getattr(h, part).astype(np.float32)
    np.savez_compressed(folder / "heads.npz", **arrays)
    (folder / "heads.json").write_text(json.dumps(
        dict(meta, heads={h.feature: h.classes for h in heads}), indent=2))


def load_heads(folder: Path) -> tuple[list[Head], dict]:
    meta_path, array_path = folder / "heads.json", folder / "heads.npz"
    if not meta_path.exists() or not array_path.exists():
        raise InputNotFound(f"no trained reference ISU in {folder} (heads.json/heads.npz missing); "
                                "train one with `isu-validate reference train`")
    meta = json.loads(meta_path.read_text())
    with np.load(array_path) as arrays:
        heads = [Head(f, classes, *(arrays[f"{f}.{p}"].astype(np.float64) for p in ("mean", "scale", "weight", "bias")))
                 for f, classes in meta["heads"].items()]
    return heads, meta
