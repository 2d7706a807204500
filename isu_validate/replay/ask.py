"""Asking the new SUT about one stored test and judging the answer exactly as the run judged it.

The request is rebuilt from the stored scene with the run's prompt and prompt style (``build_request``),
the judge is the run's (``make_judge`` with its mode and threshold over the space the run recorded), and
each test keeps its own occluded features: the same questions, weights, occlusion and threshold rule.
The run's own answers are judged again by the same judge, so "became right / wrong" compares like
with like; the run's stored F_qa stays the "before" value.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..archive import TestRecord
from ..evaluate import make_judge
from ..evaluate.vqa import OCCLUDED
from ..protocols import SUTResponse
from ..sut import build_request, query_guarded
from .stored import StoredRun


@dataclass
class Judged:
    """One set of answers to a test's questions, judged."""
    f_qa: float | None                                  # None: a SUT error, no verdict
    features: dict[str, dict] = field(default_factory=dict)   # key -> {status, answer, truth, weight}
    answers: dict = field(default_factory=dict)
    raw: str = ""
    error: str | None = None
    rejudged: float | None = None   # the run's answers judged again (``before`` only): its F_qa

    def status(self, key: str) -> str | None:
        feature = self.features.get(key)
        return None if feature is None else feature["status"]


class Asker:
    def __init__(self, stored: StoredRun, sut):
        self.stored, self.sut = stored, sut
        self.space, self.pipeline = stored.space, stored.pipeline
        self.judge = make_judge("vqa", self.space, threshold=stored.threshold)

    def _request(self, record: TestRecord, image: Path):
        return build_request(self.space, record.canonical, image, "vqa", self.pipeline.prompt,
                             style=self.pipeline.prompt_style)

    def before(self, record: TestRecord) -> Judged:
        """The run's answers judged again (the F_qa is the run's own, as recorded)."""
        request = self._request(record, Path(record.image or f"{record.test_id}.png"))
        status = (record.details.get("sut") or {}).get("status", {})
        response = SUTResponse(raw=record.sut_raw or "", answers=dict(record.answers or {}), extra={"status": status})
        verdict = self.judge.judge(record.canonical, request, response, occluded=record.occluded)
        return Judged(self.stored.run.metric(record), verdict.details.get("features", {}),
                      dict(record.answers or {}), record.sut_raw or "", rejudged=verdict.primary)

    def ask(self, record: TestRecord, image: Path) -> tuple[Judged, bool]:
        """The new SUT's answers, judged; and whether every reply came from the cache."""
        request = self._request(record, image)
        response = query_guarded(self.sut, request)
        cached = all(response.extra.get("cached") or [False])
        if response.error:
            return Judged(None, raw=response.raw or "", error=response.error), cached
        verdict = self.judge.judge(record.canonical, request, response, occluded=record.occluded)
        return Judged(verdict.primary, verdict.details.get("features", {}), dict(response.answers or {}),
                      response.raw or ""), cached


def changed(before: Judged, after: Judged) -> tuple[list[str], list[str]]:
    """Features whose answer became right, and those that became wrong (occluded ones are not judged)."""
    right, wrong = [], []
    for key, feature in after.features.items():
        was, now = before.status(key), feature["status"]
        if was is None or OCCLUDED in (was, now):
            continue
        if now == "correct" and was != "correct":
            right.append(key)
        elif was == "correct" and now != "correct":
            wrong.append(key)
    return right, wrong
