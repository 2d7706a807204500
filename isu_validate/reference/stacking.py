"""A window feature's frame probability: its best window's log-odds, alone or stacked with a detector's score.

Alone (``reference train --windows``): a Platt fit of the training frames' answers on their best window's log-odds.
With a detector (``--detector``, ``detector.py``): a logistic fit on two log-odds per frame, the best window's and
the detector's (stacking). Either way the window's log-odds are *out of fold*: a head's log-odds on frames it was
fitted on are far surer than on frames it never saw. A stacker fitted on them trusts the head blindly (measured with
the whole-frame head as the second input: held-out phone AUC 0.70-0.85 fitted in-sample, 0.91-0.95 out of fold), and
a head calibrated alone on them sets its threshold where frames it never saw seldom reach. So the training frames
are split into folds (``Folds``: by viewpoint when the renders come through several rigs, else ``FOLDS`` by frame),
and each frame is scored by a window head fitted without its fold. The detector was never fitted on the renders, so
its scores need no folds.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

FOLDS = 5


@dataclass(frozen=True)
class Stacking:
    """P(YES) = sigmoid(window * best window's log-odds + detector * detector's log-odds + intercept)."""
    window: float
    detector: float
    intercept: float

    @classmethod
    def from_meta(cls, value) -> "Stacking":
        """A stored calibration: {window, detector, intercept}, or a window head's own [slope, intercept]."""
        if isinstance(value, dict):
            return cls(float(value["window"]), float(value["detector"]), float(value["intercept"]))
        slope, intercept = value
        return cls(float(slope), 0.0, float(intercept))

    def describe(self) -> dict | list:
        """As stored: a window head alone keeps its [slope, intercept] (models before stacking read the same)."""
        if self.detector == 0.0:
            return [self.window, self.intercept]
        return {"window": self.window, "detector": self.detector, "intercept": self.intercept}

    def probability(self, window: float, detector: float = 0.0) -> float:
        z = self.window * window + self.detector * detector + self.intercept
        return float(1.0 / (1.0 + np.exp(-z)))


def fit_stacking(feature: str, window: np.ndarray, detector: np.ndarray | None, truth: np.ndarray) -> Stacking:
    """The window's calibration (``detector`` None) or its stacking with the detector, from the training frames'
    log-odds (``truth``: True where the answer is YES)."""
    from sklearn.linear_model import LogisticRegression

    if len(set(truth.tolist())) < 2:
        raise InputError(f"--windows {feature}: the training renders answer it one way only; use a larger --n")
    X = window[:, None] if detector is None else np.c_[window, detector]
    fit = LogisticRegression(C=1e6, max_iter=1000).fit(X, truth)
    return Stacking(float(fit.coef_[0, 0]), float(fit.coef_[0, 1]) if detector is not None else 0.0,
                    float(fit.intercept_[0]))


def folds(n: int, seed: int) -> np.ndarray:
    """Each training frame's fold (0..FOLDS-1), balanced in size and drawn from its own seeded stream."""
    return np.random.default_rng([seed, FOLDS]).permutation(n) % FOLDS


@dataclass(frozen=True, eq=False)   # it holds an array: no field-by-field ==
class Folds:
    """The calibration's folds: each training frame's fold, and the viewpoint each fold is (() when folds are by
    frame)."""
    of: np.ndarray
    viewpoints: tuple[str, ...] = ()

    @classmethod
    def plan(cls, viewpoints: list[str | None], seed: int) -> "Folds":
        """By viewpoint when every frame names one and there are two or more; else ``FOLDS`` by frame."""
        names = sorted({v for v in viewpoints if v})
        if len(names) >= 2 and all(viewpoints):
            return cls(np.array([names.index(v) for v in viewpoints]), tuple(names))
        return cls(folds(len(viewpoints), seed))

    def __len__(self) -> int:
        return len(self.viewpoints) or FOLDS

    def describe(self) -> str:
        """As the card and heads.json record it."""
        if self.viewpoints:
            return "by viewpoint: " + ", ".join(self.viewpoints)
        return f"{FOLDS} by frame"
