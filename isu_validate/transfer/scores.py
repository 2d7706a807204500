"""How well a SUT's answers about one feature match the truth: the figures ``transfer`` prints.

Accuracy with its Wilson 95% interval; balanced accuracy (the mean recall over the true classes: always
answering one class scores 1/k whatever the class shares) with a seeded, class-stratified percentile
bootstrap interval; each class's recall with its Wilson interval; the majority-class baseline; the
confusion matrix; the ROC AUC where the SUT gave probabilities (binary features). Questions the SUT left
unanswered (an error, a reply with no option) are counted apart and left out of the rates.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from ..recognition.tally import auc, wilson

BOOTSTRAP = 1000


@dataclass(frozen=True)
class Answer:
    truth: str
    said: str | None                 # None: unanswered
    p_positive: float | None = None  # the SUT's probability of the positive class, when it gives one
    group: str | None = None         # the photo's cluster (its driver, its video clip): the bootstrap's unit


def positive_class(options: tuple[str, ...] | list[str]) -> str:
    """The class an AUC ranks by: YES where the question has it, else its first option."""
    return "YES" if "YES" in options else options[0]


def score(answers: list[Answer], options: tuple[str, ...] | list[str], seed: int = 0) -> dict:
    answered = [a for a in answers if a.said is not None]
    truth_counts = Counter(a.truth for a in answers)
    out = {"options": list(options), "n": len(answers), "answered": len(answered),
           "unanswered": len(answers) - len(answered),
           "truth_counts": dict(sorted(truth_counts.items())),
           "said_counts": dict(sorted(Counter(a.said or "(unanswered)" for a in answers).items()))}
    majority, count = max(sorted(truth_counts.items()), key=lambda kv: kv[1])
    out["majority_baseline"] = {"class": majority, "accuracy": count / len(answers),
                                "balanced_accuracy": 1.0 / len(truth_counts)}
    if not answered:
        return {**out, "accuracy": None, "accuracy_ci95": None, "balanced_accuracy": None,
                "balanced_accuracy_ci95": None, "recall": {}, "confusion": None, "auc": None,
                "p_positive_median": None}
    truth = np.array([a.truth for a in answered])
    said = np.array([a.said for a in answered])
    hits = int((truth == said).sum())
    classes = sorted(set(truth))
    groups = _groups(answered)
    labels = list(dict.fromkeys([*options, *sorted(set(said) - set(options))]))
    out.update(accuracy=hits / len(answered), accuracy_ci95=wilson(hits, len(answered)),
               recall={c: _recall(truth, said, c) for c in classes},
               balanced_accuracy=balanced_accuracy(truth, said),
               balanced_accuracy_ci95=_bootstrap_ba(truth, said, seed, groups),
               bootstrap_unit="group" if groups is not None else "photo",
               confusion={"labels": labels,
                          "rows": {c: [int(((truth == c) & (said == s)).sum()) for s in labels] for c in classes}},
               auc=_auc(answered, positive_class(options)),
               p_positive_median=_median_p(answered))
    return out


def said_by_label(rows: list[tuple[tuple[str, ...], str, str | None, float | None]], positive: str) -> dict:
    """Per label of the real set (its class folder, a box class; a photo counts under each of its labels):
    how many photos, their true answers, what the SUT said, and the share it said ``positive`` among those
    it answered. Where a SUT's false answers come from: State Farm's drinking photos read as a phone.

    A row is (labels, truth, said, P(positive) or None). Where the SUT gave probabilities, each label also
    gets ``auc_against_other_side``: how well the SUT ranks this label's photos against the other side of
    the question (a label of positive photos against every negative photo of the set, a label of negative
    photos against every positive one). An AUC under 0.5 names a label the SUT finds more positive than the
    positives themselves: a confusion, not noise in the threshold."""
    table: dict[str, dict] = {}
    for labels, truth, said, p in rows:
        for label in labels or ("(no label)",):
            entry = table.setdefault(label, {"n": 0, "truth": Counter(), "said": Counter(), "p": []})
            entry["n"] += 1
            entry["truth"][truth] += 1
            entry["said"][said or "(unanswered)"] += 1
            if said is not None:
                entry["p"].append((truth == positive, p))
    scored = [(truth == positive, p) for _, truth, said, p in rows if said is not None]
    out = {}
    for label, e in sorted(table.items()):
        answered = e["n"] - e["said"].get("(unanswered)", 0)
        out[label] = {"n": e["n"], "truth": dict(sorted(e["truth"].items())), "said": dict(sorted(e["said"].items())),
                      "said_positive": e["said"].get(positive, 0) / answered if answered else None,
                      "auc_against_other_side": _auc_against_other_side(e["p"], scored,
                                                                        _side(e["truth"], positive))}
    return out


def _side(truth: Counter, positive: str) -> bool:
    """Whether a label stands for the positive side: most of its photos are truly positive (ties: negative)."""
    return truth.get(positive, 0) > sum(truth.values()) / 2


def _auc_against_other_side(label: list[tuple[bool, float | None]], everyone: list[tuple[bool, float | None]],
                            positive_side: bool) -> float | None:
    """AUC of a label's photos on its side against every photo of the set on the other side; None where a
    photo involved has no probability or either side is empty."""
    mine = [p for is_positive, p in label if is_positive == positive_side]
    theirs = [p for is_positive, p in everyone if is_positive != positive_side]
    if any(p is None for p in mine + theirs):
        return None
    return auc(mine, theirs) if positive_side else auc(theirs, mine)


BY_LABEL_SHOWN = 24   # labels printed per set (the most photos first); all of them are in summary.json


def format_said_by_label(name: str, sc: dict) -> list[str]:
    """For a yes/no feature: the share of each of the set's labels the SUT answered positive, a label whose
    photos are truly positive marked *, and where the SUT gave probabilities how it ranks the label against the
    other side (``auc_against_other_side``): where false answers come from."""
    table = sc.get("said_by_label")
    if not table or len(sc["options"]) != 2:
        return []
    positive = positive_class(sc["options"])
    shown = sorted(table.items(), key=lambda kv: -kv[1]["n"])[:BY_LABEL_SHOWN]
    ranked = any(e.get("auc_against_other_side") is not None for _, e in shown)
    cells = [f"{label}{'*' if _side(Counter(e['truth']), positive) else ''} "
             f"{'-' if e['said_positive'] is None else format(e['said_positive'], '.0%')} ({e['n']}"
             + (f", AUC {_fmt_auc(e.get('auc_against_other_side'))})" if ranked else ")")
             for label, e in sorted(shown)]
    head = (f"  {name}: said {positive} per label (* truly {positive}; n"
            + (", AUC against the other side: under 0.5, ranked more positive than the positives" if ranked else "")
            + ")")
    lines, line = [head], "   "
    for cell in cells:
        if len(line) + len(cell) > 100:
            lines.append(line)
            line = "   "
        line += f" {cell}"
    return lines + [line] + ([f"    ... and {len(table) - len(shown)} more labels"] if len(table) > len(shown) else [])


def _fmt_auc(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def _median_p(answered: list[Answer]) -> float | None:
    """The median probability the SUT gave the positive class (a SUT that says YES to everything: near 1)."""
    values = [a.p_positive for a in answered if a.p_positive is not None]
    return float(np.median(values)) if values else None


def balanced_accuracy(truth: np.ndarray, said: np.ndarray) -> float:
    """Mean recall over the classes present in ``truth`` (scikit-learn's definition, without its warning
    when a predicted class never occurs in the truth)."""
    return float(np.mean([np.mean(said[truth == c] == c) for c in np.unique(truth)]))


def _recall(truth: np.ndarray, said: np.ndarray, c: str) -> dict:
    mask = truth == c
    hits = int((said[mask] == c).sum())
    return {"rate": hits / int(mask.sum()), "n": int(mask.sum()), "ci95": wilson(hits, int(mask.sum()))}


def _groups(answered: list[Answer]) -> np.ndarray | None:
    groups = [a.group for a in answered]
    return None if any(g is None for g in groups) else np.array(groups)


def _bootstrap_ba(truth: np.ndarray, said: np.ndarray, seed: int, groups: np.ndarray | None = None):
    """95% percentile interval. Photos independent: resampled within each true class (the class shares stay
    fixed). Photos in clusters (frames of one driver's video are near-twins): whole clusters resampled, a
    replicate missing a class left out; without 2 clusters and 2 photos per class, no interval."""
    rng = np.random.default_rng(seed)
    correct = truth == said
    classes = np.unique(truth)
    if groups is not None:
        names, index = np.unique(groups, return_inverse=True)
        members = [np.flatnonzero(index == g) for g in range(len(names))]
        if len(names) < 2:
            return None
        values = []
        for pick in rng.integers(len(names), size=(BOOTSTRAP, len(names))):
            rows = np.concatenate([members[g] for g in pick])
            if len(np.unique(truth[rows])) == len(classes):
                values.append(np.mean([correct[rows][truth[rows] == c].mean() for c in classes]))
        values = np.array(values)
    else:
        by_class = [np.flatnonzero(truth == c) for c in classes]
        if any(len(g) < 2 for g in by_class):
            return None
        values = np.mean([correct[rng.choice(g, size=(BOOTSTRAP, len(g)))].mean(axis=1) for g in by_class], axis=0)
    if len(values) < BOOTSTRAP // 2:
        return None
    return [float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))]


def _auc(answered: list[Answer], positive: str) -> float | None:
    scored = [a for a in answered if a.p_positive is not None]
    if len(scored) < len(answered) or len({a.truth == positive for a in scored}) < 2:
        return None   # some answers without a probability, or one class only: no ROC curve
    return auc([a.p_positive for a in scored if a.truth == positive],
               [a.p_positive for a in scored if a.truth != positive])
