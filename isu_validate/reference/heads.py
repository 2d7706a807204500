"""One linear classifier per predicted feature on the backbone's features.

Stored as plain arrays (``heads.npz`` + ``heads.json``), so loading needs neither
scikit-learn nor pickle: standardise, clip, multiply, softmax.

Why clip: the heads learn from renders, and a real photograph moves some backbone channels far
beyond anything the renders ever did (4-5% of real photos' standardised values lie past 5 standard
deviations; the renders' own held-out scenes 0.5%). Unclipped, those channels carry the
answer: a linear head extrapolates, and State Farm's drivers with both hands on the wheel read as
"phone" with log-odds up to 21. Clipped at ``CLIP_SIGMA`` training standard deviations, a channel
counts at most as much as the renders taught it to (docs/MODELS.md, "Reference ISU heads").
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputNotFound

REGULARISATION_C = 0.05   # inverse L2 strength of every head's logistic regression
CLIP_SIGMA = 3.0          # standardised features are clipped to +-3 training standard deviations


def standardise(features: np.ndarray, mean: np.ndarray, scale: np.ndarray, clip: float | None) -> np.ndarray:
    """(features - mean) / scale, clipped to +-clip (None: unclipped); fitting and reading both go through here."""
    z = (features - mean) / scale
    return z if clip is None else np.clip(z, -clip, clip)


@dataclass
class Head:
    feature: str
    classes: list[str]
    mean: np.ndarray      # (D,) feature standardisation
    scale: np.ndarray     # (D,)
    weight: np.ndarray    # (C, D); a single-class head has C = 1 and always answers that class
    bias: np.ndarray      # (C,)
    clip: float | None = CLIP_SIGMA   # None: a model fitted before clipping (heads.json without clip_sigma)

    def standardise(self, features: np.ndarray) -> np.ndarray:
        return standardise(features, self.mean, self.scale, self.clip)

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        if len(self.classes) == 1:
            return np.ones((len(features), 1))
        z = self.standardise(features) @ self.weight.T + self.bias
        if z.shape[1] == 1:  # binary logistic regression stores one row
            z = np.concatenate([-z, z], axis=1) / 2
        z -= z.max(axis=1, keepdims=True)
        p = np.exp(z)
        return p / p.sum(axis=1, keepdims=True)

    def predict(self, features: np.ndarray) -> list[str]:
        return [self.classes[i] for i in self.probabilities(features).argmax(axis=1)]


def fit_head(feature: str, X: np.ndarray, y: list[str], C: float = REGULARISATION_C, seed: int = 0) -> Head:
    """L2-regularised multinomial logistic regression on standardised features, clipped as they will be read."""
    from sklearn.linear_model import LogisticRegression

    classes = sorted(set(y))
    mean = X.mean(axis=0)
    scale = X.std(axis=0)
    scale[scale < 1e-6] = 1.0  # constant features (dead channels) must not divide by zero
    if len(classes) == 1:
        return Head(feature, classes, mean, scale, np.zeros((1, X.shape[1])), np.zeros(1))
    model = LogisticRegression(C=C, max_iter=2000, random_state=seed)
    model.fit(standardise(X, mean, scale, CLIP_SIGMA), y)
    return Head(feature, [str(c) for c in model.classes_], mean, scale, model.coef_, model.intercept_)


WINDOW_PREFIX = "window."   # window heads' arrays in heads.npz (``windows.py``)


def save_heads(heads: list[Head], folder: Path, meta: dict, window_heads: list[Head] = ()) -> None:
    """Whole-frame heads and any window heads (``windows.py``) in one ``heads.npz``, their classes in ``heads.json``."""
    folder.mkdir(parents=True, exist_ok=True)
    arrays = {}
    for prefix, group in (("", heads), (WINDOW_PREFIX, window_heads)):
        for h in group:
            for part in ("mean", "scale", "weight", "bias"):
                arrays[f"{prefix}{h.feature}.{part}"] = getattr(h, part).astype(np.float32)
    np.savez_compressed(folder / "heads.npz", **arrays)
    clips = {h.clip for h in [*heads, *window_heads]}
    if len(clips) > 1:
        raise ValueError(f"heads clipped differently ({sorted(clips, key=str)}) cannot share one model folder")
    clip = {"clip_sigma": clips.pop()} if heads and None not in clips else {}
    windows = {"window_heads": {h.feature: h.classes for h in window_heads}} if window_heads else {}
    (folder / "heads.json").write_text(json.dumps(
        dict(meta, **clip, heads={h.feature: h.classes for h in heads}, **windows), indent=2))


def load_heads(folder: Path) -> tuple[list[Head], dict]:
    """The whole-frame heads and the model's meta (``load_window_heads`` reads the window heads)."""
    meta, arrays = _read(folder)
    return _heads(meta["heads"], arrays, "", meta), meta


def load_window_heads(folder: Path, meta: dict) -> list[Head]:
    """The model's window heads (none for a model without them)."""
    if not meta.get("window_heads"):
        return []
    return _heads(meta["window_heads"], _read(folder)[1], WINDOW_PREFIX, meta)


def _read(folder: Path) -> tuple[dict, dict]:
    meta_path, array_path = folder / "heads.json", folder / "heads.npz"
    if not meta_path.exists() or not array_path.exists():
        raise InputNotFound(f"no trained reference ISU in {folder} (heads.json/heads.npz missing); "
                                "train one with `isu-validate reference train`")
    meta = json.loads(meta_path.read_text())
    with np.load(array_path) as arrays:
        return meta, {k: arrays[k] for k in arrays.files}


def _heads(classes_by_feature: dict, arrays: dict, prefix: str, meta: dict) -> list[Head]:
    parts = ("mean", "scale", "weight", "bias")
    clip = meta.get("clip_sigma")
    return [Head(f, classes, *(arrays[f"{prefix}{f}.{p}"].astype(np.float64) for p in parts), clip=clip)
            for f, classes in classes_by_feature.items()]
