"""Judging SUT responses: VQA weighted exact match, captioning similarity, oracles.

    judge = make_judge("vqa", space)                  # fails when F_qa < 1.0
    judge = make_judge("vc", space, threshold=0.65)   # fails when F_emb <= 0.65
    judge = make_judge("vc", space, oracle="conjunction",
                       threshold={"f_emb": 0.65, "f_bleu": 0.1, "f_meteor": 0.3, "f_bert": 0.7})
    verdict = judge.judge(scene, request, response)

A SUT error gives ``Verdict({}, 1.0, failed=False, details={"sut_error": ...})``: no
fitness measured, not a failure.  Models (all-MiniLM-L6-v2) load on first use, once per process.
"""
from __future__ import annotations

from typing import Any, Mapping

from ..space import SceneSpace
from .captioning import CaptionJudge, caption_metrics
from .oracles import CAPTION_METRICS, DEFAULT_THRESHOLD, FAILURE_THRESHOLDS
from .reference_caption import reference_caption
from .vqa import VQAJudge
from ..errors import InputError

Judge = VQAJudge | CaptionJudge


def make_judge(mode: str, space: SceneSpace, *, threshold: float | Mapping[str, float] | None = None,
               oracle: str | None = None, **options: Any) -> Judge:
    """The judge of a run's mode: ``vqa`` (weighted exact match F_qa) or ``vc`` (caption metrics).
    Features the frame hid (a render's ``occluded``) are left out of the score.

        verdict = make_judge("vqa", space).judge(scene, request, response, occluded=frame.occluded)
        verdict.primary, verdict.failed, verdict.details["features"]
    """
    if mode == "vqa":
        if oracle not in (None, "below"):
            raise InputError(f"unknown VQA oracle {oracle!r}; VQA fails when F_qa < threshold (oracle 'below')")
        return VQAJudge(space, threshold)
    if mode == "vc":
        return CaptionJudge(space, threshold, oracle, **options)
    raise InputError(f"unknown mode {mode!r}; use 'vqa' (questions) or 'vc' (captioning)")


__all__ = ["CAPTION_METRICS", "CaptionJudge", "DEFAULT_THRESHOLD", "FAILURE_THRESHOLDS", "Judge", "VQAJudge",
           "caption_metrics", "make_judge", "reference_caption"]
