"""Failure analysis per feature: how often each question is answered wrong and in which
direction (FRONT_FACING answered as REAR_FACING), and the failure rate per feature value.
A feature the frame hid (``occluded``) was not judged: it is counted apart, never as wrong."""
from __future__ import annotations

from collections import Counter
from typing import Iterable

from ..archive import TestRecord
from .runs import Run

NO_ANSWER = "(no answer)"
ABSENT = "(absent)"
NUMERIC_BINS = 4


def wrong_answers(run: Run, record: TestRecord) -> dict[str, tuple[str, str]]:
    """feature -> (truth, answer) for every question this test got wrong (VQA only)."""
    if record.errored or record.answers is None:
        return {}
    answers, hidden = record.answers, set(record.occluded)
    return {key: (truth, str(answers.get(key, NO_ANSWER)))
            for key, truth in run.truth(record).items()
            if key not in hidden and str(answers.get(key, NO_ANSWER)) != truth}


def _answered(runs: Iterable[Run]):
    for run in runs:
        for record in run.valid:
            if record.answers is not None:
                yield run, record


def feature_errors(runs: Iterable[Run]) -> tuple[list[dict], list[dict]]:
    """(per-feature rows, confusion rows): asked (and judged), occluded (asked, not judged), wrong,
    wrong rate among the judged, most frequent wrong direction."""
    asked, hidden, wrong, confusion = Counter(), Counter(), Counter(), Counter()
    for run, record in _answered(runs):
        truth = run.truth(record)
        occluded = set(record.occluded) & set(truth)
        hidden.update(occluded)
        asked.update(set(truth) - occluded)
        for key, (right, answer) in wrong_answers(run, record).items():
            wrong[key] += 1
            confusion[(key, right, answer)] += 1
    rows = []
    for key in sorted(set(asked) | set(hidden), key=lambda k: (-wrong[k] / max(asked[k], 1), k)):
        top = max(((c, t, a) for (f, t, a), c in confusion.items() if f == key), default=None)
        rows.append({"feature": key, "asked": asked[key], "occluded": hidden[key], "wrong": wrong[key],
                     "wrong_rate": round(wrong[key] / asked[key], 4) if asked[key] else float("nan"),
                     "most_common_error": f"{top[1]} answered as {top[2]} ({top[0]}x)" if top else ""})
    pairs = [{"feature": f, "truth": t, "answer": a, "count": c}
             for (f, t, a), c in sorted(confusion.items(), key=lambda kv: (-kv[1], kv[0]))]
    return rows, pairs


def value_failure_rates(runs: list[Run]) -> list[dict]:
    """Failure rate of the tests that have each value of each feature (numeric features binned)."""
    if not runs:
        return []
    space = runs[0].space
    tests, fails = Counter(), Counter()
    for run in runs:
        for record in run.valid:
            for name, feature in space.features.items():
                key = (name, value_label(feature, record.canonical.get(name)))
                tests[key] += 1
                fails[key] += record.failed
    names = list(space.features)

    def order(key):
        name, value = key
        values = space.features[name].values
        return names.index(name), values.index(value) if value in values else len(values), value

    return [{"feature": f, "value": v, "tests": tests[(f, v)], "failing": fails[(f, v)],
             "failure_rate": round(fails[(f, v)] / tests[(f, v)], 4)} for f, v in sorted(tests, key=order)]


def value_label(feature, value) -> str:
    if value is None:
        return ABSENT
    if feature.discrete:
        return str(value)
    width = (feature.high - feature.low) / NUMERIC_BINS or 1.0
    i = min(NUMERIC_BINS - 1, int((float(value) - feature.low) // width))
    low = feature.low + i * width
    unit = f" {feature.unit}" if feature.unit else ""
    return f"[{low:g}, {low + width:g}){unit}" if i < NUMERIC_BINS - 1 else f"[{low:g}, {feature.high:g}]{unit}"
