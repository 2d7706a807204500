"""VQA fitness: weighted exact match over the scene's active predicted features.

F_qa = sum of the weights of correctly answered questions / sum of the weights of all
asked questions, so all-correct is 1.0 whatever the weights add up to (the public
ISU-Test code's weights sum to 1.5 against a 1.0 threshold; ours mean what they say).
Only the scene's active predicted features are scored: an answer about an inactive
feature (luggage colour with no luggage) is ignored, never rewarded or punished.
Each feature is ``correct``, ``wrong``, ``missing`` (not answered) or ``invalid`` (not
one of its options); the last two count as not correct.  A feature the frame showed too
little of (``occluded``, from the render label's visibility) is left out of the weights:
F_qa is renormalised over the rest, so hiding a thing earns the search nothing.
"""
from __future__ import annotations

from typing import Any, Collection, Mapping

from ..protocols import SUTRequest, SUTResponse, Verdict
from ..space import SceneSpace
from .occlusion import no_verdict, nothing_to_judge
from .oracles import DEFAULT_THRESHOLD, check_threshold, vqa_failed

CORRECT, WRONG, MISSING, INVALID, OCCLUDED = "correct", "wrong", "missing", "invalid", "occluded"


class VQAJudge:
    mode = "vqa"

    def __init__(self, space: SceneSpace, threshold: float | None = None):
        self.space = space
        self.threshold = DEFAULT_THRESHOLD["vqa"] if threshold is None else check_threshold(threshold)

    def judge(self, scene: Mapping[str, Any], request: SUTRequest, response: SUTResponse,
              occluded: Collection[str] = ()) -> Verdict:
        hidden = nothing_to_judge(self.space, scene, occluded)
        if hidden:   # the pipeline does not ask the SUT about such a scene; a judge asked anyway agrees
            return no_verdict(hidden, threshold=self.threshold)
        if response.error:
            # Not a failure-inducing scene: no fitness is measured, and the search is not drawn to it.
            return Verdict({}, 1.0, False, {"sut_error": response.error, "threshold": self.threshold})
        questions = self.space.questions(scene)  # the truth comes from the scene, never from the request
        answers = response.answers or {}
        parse_status = response.extra.get("status", {}) if isinstance(response.extra, dict) else {}
        features, weights = {}, {}
        for q in questions:
            given = answers.get(q.key)
            if given is None:
                status = INVALID if parse_status.get(q.key) == INVALID else MISSING
            elif given not in q.options:
                status = INVALID
            else:
                status = CORRECT if given == q.truth else WRONG
            if q.key in occluded:   # the answer is kept for the record, never scored
                features[q.key] = {"status": OCCLUDED, "answer": given, "truth": q.truth, "weight": q.weight,
                                   "would_be": status}
                continue
            features[q.key] = {"status": status, "answer": given, "truth": q.truth, "weight": q.weight}
            weights[q.key] = q.weight
        counts = {s: sum(f["status"] == s for f in features.values())
                  for s in (CORRECT, WRONG, MISSING, INVALID, OCCLUDED)}
        details = {"features": features, "counts": counts, "threshold": self.threshold,
                   "ignored": sorted(set(answers) - set(features))}
        scored = {k: f for k, f in features.items() if f["status"] != OCCLUDED}
        f_qa, details["weighting"] = weighted_score(scored, weights)
        return Verdict({"f_qa": f_qa}, f_qa, vqa_failed(f_qa, self.threshold), details)


def weighted_score(features: dict, weights: dict) -> tuple[float, str]:
    """F_qa of judged features ({key: {"status": ...}}, occluded ones already left out) and how it was
    weighted: weights renormalised over their sum, equal weights when every weight is zero."""
    if not features:
        return 1.0, "no questions asked (no active predicted feature): nothing to get wrong"
    total = sum(weights.values())
    if total > 0:
        right = sum(weights[k] for k, f in features.items() if f["status"] == CORRECT)
        return right / total, "weights normalised by their active sum"
    # Every active weight is zero: the weights carry no preference, so count questions equally.
    right = sum(f["status"] == CORRECT for f in features.values())
    return right / len(features), "all active weights are 0: unweighted share of correct answers"
