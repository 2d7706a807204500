"""Which failures retraining the heads cannot fix, and the failure rates without them.

A feature is "not fixed" when the focused model still answers it wrongly on the replayed run about as
often as the shipped model did: its heads got the data and could not use it (the frozen backbone's
pooled features do not carry what the feature needs: a driver's expression is a few pixels of a 64 px
face). The failure rates are then recomputed with those features left out of F_qa (weights
renormalised over the rest, as the judge does for occluded ones), for every row.
"""
from __future__ import annotations

from pathlib import Path

MIN_ERRORS = 3      # a feature wrong fewer times than this on the replayed run tells nothing either way
KEPT = 0.75         # still wrong at least this share as often after the focused retrain: not fixed


def feature_verdicts(run_dir: Path) -> dict[str, dict[str, list]]:
    """{test_id: {feature: [status, weight]}} of the run's tests with a verdict, as its judge gave them."""
    from ...archive import open_run

    out = {}
    for record in open_run(run_dir).records():
        features = ((record.details or {}).get("verdict") or {}).get("features")
        if record.primary is not None and features:
            out[record.test_id] = {k: [f["status"], f["weight"]] for k, f in features.items()}
    return out


def wrong_counts(per_feature: dict) -> dict[str, int]:
    """{feature: wrong answers after} from a replay summary's per_feature."""
    return {name: row["judged"] - row["right_after"] for name, row in per_feature.items()}


def not_fixed(shipped: dict[str, int], focused: dict[str, int]) -> list[str]:
    return [name for name, before in shipped.items()
            if before >= MIN_ERRORS and focused.get(name, 0) >= KEPT * before]


def statuses_after(before: dict[str, list], replayed: dict) -> dict[str, list]:
    """A test's per-feature [status, weight] under a model: the run's, with the replay's changes."""
    right = set(filter(None, (replayed.get("became_right") or "").split(";")))
    wrong = set(filter(None, (replayed.get("became_wrong") or "").split(";")))
    out = {}
    for name, (status, weight) in before.items():
        if name in right:
            status = "correct"
        elif name in wrong:
            status = "wrong"
        out[name] = [status, weight]
    return out


def f_qa_without(statuses: dict[str, list], left_out: set[str]) -> float:
    """F_qa as the judge computes it, with ``left_out`` not scored, like occluded features."""
    from ...evaluate.vqa import weighted_score

    scored = {k: v for k, v in statuses.items() if v[0] != "occluded" and k not in left_out}
    f_qa, _ = weighted_score({k: {"status": s} for k, (s, _) in scored.items()}, {k: w for k, (_, w) in scored.items()})
    return f_qa


def without(verdicts: dict, replay: dict, left_out: set[str], thresholds, at: float) -> dict:
    """One replay with ``left_out`` not scored, over the tests it paired: the failure rate per threshold,
    and McNemar's p at ``at`` of the run's outcomes (the shipped model's, so scored) against the replay's."""
    from ...replay.compare import mcnemar

    pairs = [(f_qa_without(verdicts[row["test_id"]], left_out),
              f_qa_without(statuses_after(verdicts[row["test_id"]], row), left_out))
             for row in replay["tests"] if row["f_qa_after"] not in (None, "") and row["test_id"] in verdicts]
    rates = {t: (sum(after < t for _, after in pairs) / len(pairs) if pairs else None) for t in thresholds}
    fixed = sum(before < at <= after for before, after in pairs)
    new = sum(after < at <= before for before, after in pairs)
    return {"rates": rates, "p": mcnemar(fixed, new)["p"]}
