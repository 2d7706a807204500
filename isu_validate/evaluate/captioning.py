"""Captioning fitness: the SUT's caption against the scene's reference caption.

Four metrics (F_emb, BLEU, METEOR, BERTScore F1; settings in ``SETTINGS``), the primary
one F_emb.  With repeats, every caption is scored and the metrics are averaged; the
mean pairwise F_emb between the repeats is reported as the SUT's consistency.
An empty caption scores 0 on every metric.  Features the frame hides (``occluded``) are
left out of the reference caption: every sentence that names one is dropped.
"""
from __future__ import annotations

from itertools import combinations
from typing import Any, Collection, Mapping

from ..protocols import SUTRequest, SUTResponse, Verdict
from ..space import SceneSpace
from . import similarity, text_metrics
from .occlusion import no_verdict, nothing_to_judge
from .oracles import (CAPTION_METRICS, DEFAULT_THRESHOLD, check_conjunction, check_threshold, conjunction_failed,
                      emb_failed)
from .reference_caption import reference_caption, template_for
from ..errors import InputError

SETTINGS = {**text_metrics.SETTINGS, **similarity.SETTINGS}


def caption_metrics(caption: str, reference: str) -> dict[str, float]:
    return {"f_emb": similarity.f_emb(caption, reference),
            "f_bleu": text_metrics.bleu(caption, reference),
            "f_meteor": text_metrics.meteor(caption, reference),
            "f_bert": similarity.bertscore(caption, reference)["f1"]}


class CaptionJudge:
    mode = "vc"

    def __init__(self, space: SceneSpace, threshold: float | Mapping[str, float] | None = None,
                 oracle: str | None = None, template: str | None = None):
        self.space, self.template = space, template
        template_for(space, template)  # a missing or foreign template stops the run before any test
        self.oracle = oracle or "emb"
        if self.oracle == "emb":
            if isinstance(threshold, Mapping):
                raise InputError("the emb oracle takes one number (fail when F_emb <= it); "
                                 "per-metric thresholds belong to oracle='conjunction'")
            self.threshold: Any = DEFAULT_THRESHOLD["vc"] if threshold is None else check_threshold(threshold)
        elif self.oracle == "conjunction":
            self.threshold = check_conjunction(threshold)
        else:
            raise InputError(f"unknown captioning oracle {oracle!r}; use 'emb' (F_emb <= threshold) or "
                             "'conjunction' (every given metric at or below its threshold)")

    def judge(self, scene: Mapping[str, Any], request: SUTRequest, response: SUTResponse,
              occluded: Collection[str] = ()) -> Verdict:
        settings = {"oracle": self.oracle, "threshold": self.threshold}
        hidden = nothing_to_judge(self.space, scene, occluded)
        if hidden:   # the pipeline does not ask the SUT about such a scene; a judge asked anyway agrees
            return no_verdict(hidden, **settings)
        if response.error:
            return Verdict({}, 1.0, False, {"sut_error": response.error, **settings})
        # the reference says nothing about what the frame hides: no sentence naming an occluded feature
        reference = reference_caption(self.space, scene, self.template, hidden=occluded)
        captions = [c or "" for c in (response.extra.get("captions") or [response.caption])]
        scored = [caption_metrics(c, reference) for c in captions]
        fitness = {m: sum(s[m] for s in scored) / len(scored) for m in CAPTION_METRICS}
        failed = (emb_failed(fitness, self.threshold) if self.oracle == "emb"
                  else conjunction_failed(fitness, self.threshold))
        details: dict[str, Any] = {"reference_caption": reference, "caption_template": self.template or "default",
                                   "metrics": SETTINGS, **settings, "occluded": sorted(occluded),
                                   "truncated": any(similarity.is_truncated(c) for c in captions if c.strip())}
        if any(not c.strip() for c in captions):
            details["problems"] = ["empty caption: scored 0 on every metric"]
        if len(captions) > 1:
            details["per_caption"] = scored
            details["consistency"] = _pairwise_similarity(captions)
        return Verdict(fitness, fitness["f_emb"], failed, details)


def _pairwise_similarity(captions: list[str]) -> float:
    pairs = list(combinations(range(len(captions)), 2))
    return sum(similarity.f_emb(captions[i], captions[j]) for i, j in pairs) / len(pairs)
