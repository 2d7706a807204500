"""Paired outcomes of each test before (the run) and after (the replay), and what they add up to.

At a threshold t a test fails as the run's oracle says (``analysis.thresholds.fails_at``: F_qa < t).
Only tests replayed with a verdict are paired; a SUT error in the replay or a test that could not be
replayed is counted apart, never as a failure. The paired outcomes are compared with McNemar's exact
test: a two-sided binomial test of the discordant pairs (fixed against new failures) at 1/2.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..analysis.thresholds import fails_at, thresholds_for
from ..archive import TestRecord
from .ask import Judged, changed

FIXED, NEW, PERSISTING, STILL_PASSING = "fixed", "new", "persisting", "still_passing"
SUT_ERROR, NOT_REPLAYED = "sut_error", "not_replayed"
PAIRED = (FIXED, NEW, PERSISTING, STILL_PASSING)
CSV_COLUMNS = ["test_id", "status", "f_qa_before", "f_qa_after", "became_right", "became_wrong", "image", "note"]


@dataclass
class Replayed:
    """One test with a verdict in the run, and what became of it."""
    record: TestRecord
    before: Judged
    after: Judged | None = None      # None: not asked (see ``skipped``)
    image: str = ""
    skipped: str | None = None
    rerendered: bool = False
    right: list[str] = field(default_factory=list)   # features whose answer became right
    wrong: list[str] = field(default_factory=list)   # ... became wrong

    def __post_init__(self):
        if self.paired:
            self.right, self.wrong = changed(self.before, self.after)

    @property
    def paired(self) -> bool:
        return self.after is not None and self.after.f_qa is not None

    def status(self, threshold: float) -> str:
        if self.after is None:
            return NOT_REPLAYED
        if self.after.f_qa is None:
            return SUT_ERROR
        was, now = fails_at("vqa", self.before.f_qa, threshold), fails_at("vqa", self.after.f_qa, threshold)
        return {(True, False): FIXED, (False, True): NEW, (True, True): PERSISTING}.get((was, now), STILL_PASSING)


def mcnemar(fixed: int, new: int) -> dict:
    """McNemar's exact test on the discordant pairs; p = 1.0 when there are none (nothing changed)."""
    n = fixed + new
    if n == 0:
        p = 1.0
    else:
        from scipy.stats import binomtest
        p = float(binomtest(fixed, n, 0.5).pvalue)
    return {"p": p, "fixed": fixed, "new": new, "discordant": n,
            "test": "exact two-sided binomial test of fixed against new failures at 1/2"}


def thresholds(threshold: float) -> list[float]:
    """The report's thresholds (as the run report's RQ1 table) and the one the counts are at."""
    return sorted(set(thresholds_for("vqa")) | {threshold}, reverse=True)


def rates(items: list[Replayed], threshold: float) -> list[dict]:
    paired = [r for r in items if r.paired]
    out = []
    for t in thresholds(threshold):
        before = sum(fails_at("vqa", r.before.f_qa, t) for r in paired)
        after = sum(fails_at("vqa", r.after.f_qa, t) for r in paired)
        out.append({"threshold": t, "failures_before": before, "failures_after": after,
                    "rate_before": before / len(paired) if paired else None,
                    "rate_after": after / len(paired) if paired else None})
    return out


def per_feature(items: list[Replayed], space) -> dict[str, dict]:
    """Per predicted feature, over the paired tests where it was judged both times."""
    out = {f.name: {"label": f.display_name, "judged": 0, "right_before": 0, "right_after": 0, "became_right": 0,
                    "became_wrong": 0} for f in space.predicted}
    for item in (r for r in items if r.paired):
        for key in item.after.features:
            was, now = item.before.status(key), item.after.status(key)
            if key not in out or was is None or "occluded" in (was, now):
                continue
            row = out[key]
            row["judged"] += 1
            row["right_before"] += was == "correct"
            row["right_after"] += now == "correct"
        for key in item.right:
            out[key]["became_right"] += 1
        for key in item.wrong:
            out[key]["became_wrong"] += 1
    return out


def summarise(items: list[Replayed], threshold: float, space) -> dict:
    counts = {s: 0 for s in (*PAIRED, SUT_ERROR, NOT_REPLAYED)}
    for item in items:
        counts[item.status(threshold)] += 1
    return {"threshold": threshold, "n_tests": len(items), "n_replayed": sum(counts[s] for s in PAIRED),
            **{s: counts[s] for s in PAIRED},
            "failures_before": counts[FIXED] + counts[PERSISTING], "failures_after": counts[NEW] + counts[PERSISTING],
            "sut_errors": counts[SUT_ERROR], "not_replayed": counts[NOT_REPLAYED],
            "rerendered": sum(r.rerendered and r.after is not None for r in items),
            "rates": rates(items, threshold), "per_feature": per_feature(items, space),
            "mcnemar": mcnemar(counts[FIXED], counts[NEW])}


def rows(items: list[Replayed], threshold: float) -> list[dict]:
    """replay.csv: one row per test with a verdict in the run."""
    def note(item: Replayed) -> str:
        if item.skipped:
            return item.skipped
        if item.after is not None and item.after.error:
            return f"SUT error: {item.after.error}"
        return "image rendered again" if item.rerendered else ""

    return [{"test_id": r.record.test_id, "status": r.status(threshold), "f_qa_before": r.before.f_qa,
             "f_qa_after": r.after.f_qa if r.after is not None else None, "became_right": ";".join(r.right),
             "became_wrong": ";".join(r.wrong), "image": r.image, "note": note(r)} for r in items]
