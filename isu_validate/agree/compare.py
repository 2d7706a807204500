"""Sim/real agreement, as the paper defines it.

For each sample, real frame and predicted feature active in the scene's truth, the SUT's answers
on the render and on the photo are each correct or not (the VQA judge's notion: the answer equals
the truth). The category: both correct, both wrong, correct only on sim, correct only on real.
Agreement rate = (both correct + both wrong) / all compared. Both wrong counts as agreement even
when the two wrong answers differ: the question is whether the failure transfers.
Several real frames of one sample are compared one by one (one row per frame and feature).
Not compared, and counted apart: features the label marks occluded, features the SUT left
unanswered (or answered outside the options) on either image, and images where the SUT failed.
The same is done for the stylised render (nst) against the photo.
A frame's sidecar may mark it a stand-in (a render taken for the photo where no car was at hand):
each row says so, the frames of each kind are counted, and the agreement is also given per kind,
so a figure measured on renders is never read as a real-world one.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

BOTH_CORRECT, BOTH_WRONG, SIM_ONLY, REAL_ONLY = "both_correct", "both_wrong", "sim_only", "real_only"
NST_ONLY = "nst_only"
OCCLUDED, UNANSWERED, SUT_ERROR = "occluded", "unanswered", "sut_error"
AGREE = (BOTH_CORRECT, BOTH_WRONG)
COMPARED = (BOTH_CORRECT, BOTH_WRONG, SIM_ONLY, REAL_ONLY)
NOT_COMPARED = (OCCLUDED, UNANSWERED, SUT_ERROR)
CSV_COLUMNS = ["sample", "frame", "feature", "truth", "sim", "real", "category", "nst", "nst_category", "stand_in"]
PROVENANCE = {"real": False, "stand_in": True}     # by_provenance key -> the rows' stand_in value


@dataclass
class Judged:
    """One image's answers as the judge saw them: feature -> (answer, status) or a SUT error."""
    answers: dict[str, tuple[str | None, str]] = field(default_factory=dict)
    error: str | None = None


def category(sim_status: str, real_status: str, render_only: str = SIM_ONLY) -> str:
    """The category of one comparison from the judge's statuses (correct, wrong, missing, invalid)."""
    if sim_status not in ("correct", "wrong") or real_status not in ("correct", "wrong"):
        return UNANSWERED
    sim_ok, real_ok = sim_status == "correct", real_status == "correct"
    if sim_ok and real_ok:
        return BOTH_CORRECT
    if not sim_ok and not real_ok:
        return BOTH_WRONG
    return render_only if sim_ok else REAL_ONLY


def rows_for_frame(sample: str, frame: str, truth: dict[str, str], occluded: set[str], sim: Judged,
                   real: Judged, nst: Judged | None, stand_in: bool = False) -> list[dict]:
    """One row per feature asked about this scene; ``stand_in``: the frame is a stand-in render."""
    rows = []
    for feature, correct in truth.items():
        row = {"sample": sample, "frame": frame, "feature": feature, "truth": correct,
               "sim": _answer(sim, feature), "real": _answer(real, feature), "category": "",
               "nst": _answer(nst, feature) if nst else "", "nst_category": "", "stand_in": stand_in}
        row["category"] = _category(feature, occluded, sim, real, SIM_ONLY)
        if nst is not None:
            row["nst_category"] = _category(feature, occluded, nst, real, NST_ONLY)
        rows.append(row)
    return rows


def _answer(judged: Judged, feature: str) -> str:
    if judged.error:
        return ""
    answer, _ = judged.answers.get(feature, (None, "missing"))
    return "" if answer is None else str(answer)


def _category(feature: str, occluded: set[str], render: Judged, real: Judged, render_only: str) -> str:
    if feature in occluded:
        return OCCLUDED
    if render.error or real.error:
        return SUT_ERROR
    return category(render.answers.get(feature, (None, "missing"))[1],
                    real.answers.get(feature, (None, "missing"))[1], render_only)


# ---------------------------------------------------------------------- counting
def counts(categories: Iterable[str], render_only: str = SIM_ONLY) -> dict:
    """Category counts, the number compared and the agreement rate (None when nothing was compared)."""
    cats = list(categories)
    kinds = (BOTH_CORRECT, BOTH_WRONG, render_only, REAL_ONLY)
    out = {k: cats.count(k) for k in kinds}
    out["compared"] = sum(out.values())
    out["agreement_rate"] = (out[BOTH_CORRECT] + out[BOTH_WRONG]) / out["compared"] if out["compared"] else None
    for k in NOT_COMPARED:
        out[k] = cats.count(k)
    return out


def grouped(rows: list[dict], key: str, column: str = "category", render_only: str = SIM_ONLY) -> dict:
    groups: dict[str, list[str]] = {}
    for row in rows:
        groups.setdefault(row[key], []).append(row[column])
    return {k: counts(v, render_only) for k, v in groups.items()}


def summarise(rows: list[dict]) -> dict:
    """The numbers of summary.json (without realism, validity and settings)."""
    overall = counts(r["category"] for r in rows)
    compared = [r for r in rows if r["category"] in COMPARED]
    summary = {
        "agreement_rate": overall["agreement_rate"],
        "n_samples": len({r["sample"] for r in compared}),
        "n_frames": len({(r["sample"], r["frame"]) for r in compared}),
        "n_features_compared": overall["compared"],
        **{k: overall[k] for k in COMPARED},
        "not_compared": {k: overall[k] for k in NOT_COMPARED},
        "per_feature": grouped(rows, "feature"),
        "per_sample": grouped(rows, "sample"),
        **provenance(rows),
    }
    nst_rows = [r for r in rows if r["nst_category"]]
    if nst_rows:
        nst = counts((r["nst_category"] for r in nst_rows), NST_ONLY)
        both = [r for r in nst_rows if r["nst_category"] in COMPARED + (NST_ONLY,) and r["category"] in COMPARED]
        sim_same = counts(r["category"] for r in both)
        nst_same = counts((r["nst_category"] for r in both), NST_ONLY)
        summary.update({
            "agreement_rate_nst": nst["agreement_rate"],
            "n_samples_nst": len({r["sample"] for r in nst_rows if r["nst_category"] in AGREE + (NST_ONLY, REAL_ONLY)}),
            "n_features_compared_nst": nst["compared"],
            "nst_counts": {k: nst[k] for k in (BOTH_CORRECT, BOTH_WRONG, NST_ONLY, REAL_ONLY)},
            "per_feature_nst": grouped(nst_rows, "feature", "nst_category", NST_ONLY),
            # the change on exactly the rows both compared, so a missing nst.png cannot fake an effect
            "nst_change": {"rows": len(both), "sim": sim_same["agreement_rate"], "nst": nst_same["agreement_rate"],
                           "change": (None if not both else nst_same["agreement_rate"] - sim_same["agreement_rate"])},
        })
    return summary


def provenance(rows: list[dict]) -> dict:
    """``stand_in_frames``, ``real_frames`` (of the frames compared: together ``n_frames``), and the
    agreement on each kind apart."""
    frames = {(r["sample"], r["frame"]): r["stand_in"] for r in rows if r["category"] in COMPARED}
    by_kind = {}
    for kind, flag in PROVENANCE.items():
        counted = counts(r["category"] for r in rows if r["stand_in"] == flag)
        by_kind[kind] = {"frames": sum(v == flag for v in frames.values()), **counted}
    return {"stand_in_frames": by_kind["stand_in"]["frames"], "real_frames": by_kind["real"]["frames"],
            "by_provenance": by_kind}
