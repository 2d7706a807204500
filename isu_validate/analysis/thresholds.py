"""The thresholds at which failure rates are reported, and the comparison that makes a
failure: the same as the run's oracle (``isu_validate.evaluate.oracles``).

VQA fails when F_qa < t (1.0 = every answer right); captioning when F_emb <= t.
"""
from __future__ import annotations

from ..errors import InputError

try:  # the evaluation package owns the oracle; use its thresholds when it is there
    from ..evaluate.oracles import DEFAULT_THRESHOLD as _DEFAULT_THRESHOLD
    from ..evaluate.oracles import FAILURE_THRESHOLDS as _EVALUATE_THRESHOLDS
except ImportError:  # evaluate/ not built: the paper's thresholds (RQ1 table) and oracle defaults
    _EVALUATE_THRESHOLDS = {"vqa": (1.0, 0.9, 0.8, 0.7, 0.6, 0.5), "vc": (0.8, 0.7, 0.6, 0.5)}
    _DEFAULT_THRESHOLD = {"vqa": 1.0, "vc": 0.65}

FAILURE_THRESHOLDS: dict[str, tuple[float, ...]] = {
    mode: tuple(sorted((float(t) for t in values), reverse=True))
    for mode, values in dict(_EVALUATE_THRESHOLDS).items()}

# the oracle threshold of a run that did not set one
DEFAULT_THRESHOLD: dict[str, float] = {mode: float(t) for mode, t in dict(_DEFAULT_THRESHOLD).items()}
# the fitness each mode's thresholds apply to; `primary` when a record lacks it
METRIC_KEYS = {"vqa": "f_qa", "vc": "f_emb"}
# how a value compares with the threshold to fail (as the oracles of isu_validate.evaluate)
FAIL_RULES = {"vqa": "<", "vc": "<="}


def thresholds_for(mode: str) -> tuple[float, ...]:
    if mode not in FAILURE_THRESHOLDS:
        raise InputError(f"unknown mode {mode!r} in run.json; expected one of {', '.join(FAILURE_THRESHOLDS)}")
    return FAILURE_THRESHOLDS[mode]


def fails_at(mode: str, value: float | None, threshold: float) -> bool:
    """Whether a test with this fitness fails at ``threshold`` (None: no verdict, never fails)."""
    if value is None:
        return False
    return value <= threshold if FAIL_RULES.get(mode) == "<=" else value < threshold
