"""When a response counts as a failure: thresholds and oracles, kept apart from the metrics.

VQA: failing when F_qa < threshold (default 1.0: any weighted mistake).
Captioning: the paper's experiments use the single oracle F_emb <= 0.65; its
conjunction oracle fails a caption when *every* given metric is at or below its own
threshold.  We ship no default per-metric thresholds for the conjunction (the
numbers must come from the study being reproduced); pass them explicitly.
"""
from __future__ import annotations

from typing import Mapping

from ..errors import InputError

# Thresholds at which reports give failure rates (RQ1).
FAILURE_THRESHOLDS: dict[str, list[float]] = {
    "vqa": [1.0, 0.9, 0.8, 0.7, 0.6, 0.5],
    "vc": [0.8, 0.7, 0.6, 0.5],
}
DEFAULT_THRESHOLD = {"vqa": 1.0, "vc": 0.65}
CAPTION_METRICS = ("f_emb", "f_bleu", "f_meteor", "f_bert")
ORACLES = {"vqa": ("below",), "vc": ("emb", "conjunction")}


def check_threshold(value: object, what: str = "threshold") -> float:
    """Every fitness the oracles compare lies in 0..1: a threshold outside it (``--threshold 7``)
    would fail every test or none, so it is refused."""
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"the {what} must be a number in 0..1, got {value!r}") from None
    if not 0.0 <= number <= 1.0:  # NaN fails too
        raise InputError(f"the {what} must lie in 0..1 (the fitness it is compared with does), got {value!r}; "
                         "e.g. 0.8 fails a VQA response below 80% weighted correct")
    return number


def vqa_failed(f_qa: float, threshold: float) -> bool:
    return f_qa < threshold


def emb_failed(fitness: Mapping[str, float], threshold: float) -> bool:
    return fitness["f_emb"] <= threshold


def conjunction_failed(fitness: Mapping[str, float], thresholds: Mapping[str, float]) -> bool:
    return all(fitness[name] <= limit for name, limit in thresholds.items())


def check_conjunction(thresholds: object) -> dict[str, float]:
    example = "{'f_emb': 0.65, 'f_bleu': 0.1, 'f_meteor': 0.3, 'f_bert': 0.7}"
    if not isinstance(thresholds, Mapping) or not thresholds:
        raise InputError(f"the conjunction oracle needs a threshold per metric, e.g. {example}")
    unknown = sorted(set(thresholds) - set(CAPTION_METRICS))
    if unknown:
        raise InputError(f"unknown caption metric(s) {unknown} in the conjunction thresholds; "
                         f"known: {', '.join(CAPTION_METRICS)}")
    return {k: check_threshold(v, f"{k} threshold") for k, v in thresholds.items()}
