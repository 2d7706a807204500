"""Failure regions in the design space as readable rules, from a shallow decision tree over
the scene features (as OpenSBT does): "seat_belt = NO and external_light <= LOW: 12 of 14 failing".

Categorical features are one-hot columns, ordinal features their rank, numeric features
their value; a feature the scene lacks is coded below its domain, so it reads as "absent".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..space import SceneSpace

MAX_DEPTH = 3


@dataclass(frozen=True)
class Column:
    feature: str
    kind: str          # onehot | rank | value
    value: str = ""    # the category of a one-hot column


def design_matrix(space: SceneSpace, scenes: list[dict]) -> tuple[np.ndarray, list[Column]]:
    columns: list[Column] = []
    for name, f in space.features.items():
        if f.type == "categorical":
            columns += [Column(name, "onehot", v) for v in f.values]
        else:
            columns.append(Column(name, "rank" if f.discrete else "value"))
    x = np.array([[_code(space, c, s) for c in columns] for s in scenes], dtype=float)
    x = x.reshape(len(scenes), len(columns))
    return x, columns


def _code(space: SceneSpace, column: Column, scene: dict) -> float:
    value = scene.get(column.feature)
    if column.kind == "onehot":
        return float(value == column.value)
    feature = space.features[column.feature]
    if value is None:
        return -1.0 if column.kind == "rank" else feature.low - max(feature.high - feature.low, 1.0)
    return float(feature.values.index(value)) if column.kind == "rank" else float(value)


def failure_regions(space: SceneSpace, scenes: list[dict], failed: list[bool], seed: int = 0) -> list[dict]:
    """Leaves where most tests fail, as rules, most failures first; [] when nothing separates."""
    from sklearn.tree import DecisionTreeClassifier  # scikit-learn: only when there is something to split

    y = np.asarray(failed, dtype=int)
    if len(y) < 4 or y.min() == y.max():
        return []
    x, columns = design_matrix(space, scenes)
    tree = DecisionTreeClassifier(max_depth=MAX_DEPTH, min_samples_leaf=max(2, len(y) // 50),
                                  random_state=seed).fit(x, y)
    leaf_of = tree.apply(x)
    out = []
    for conditions, leaf in _leaves(tree.tree_, 0, []):
        members = leaf_of == leaf
        n, n_fail = int(members.sum()), int(y[members].sum())
        if n and n_fail / n >= 0.5:
            out.append({"rule": describe(space, columns, conditions), "failing": n_fail, "tests": n,
                        "precision": round(n_fail / n, 4), "share_of_failures": round(n_fail / int(y.sum()), 4)})
    return sorted(out, key=lambda r: (-r["failing"], -r["precision"]))


def _leaves(t, node: int, path: list):
    if t.children_left[node] == -1:
        yield path, node
        return
    col, thr = int(t.feature[node]), float(t.threshold[node])
    yield from _leaves(t, t.children_left[node], path + [(col, "<=", thr)])
    yield from _leaves(t, t.children_right[node], path + [(col, ">", thr)])


def describe(space: SceneSpace, columns: list[Column], conditions: list) -> str:
    """Conditions on one feature are merged, then written in the feature's own values."""
    by_feature: dict[str, list] = {}
    for col, op, thr in conditions:
        by_feature.setdefault(columns[col].feature, []).append((columns[col], op, thr))
    parts = [_describe_feature(space, name, conds) for name, conds in by_feature.items()]
    return " and ".join(p for p in parts if p) or "all tests"


def _describe_feature(space: SceneSpace, name: str, conds: list) -> str:
    feature = space.features[name]
    if conds[0][0].kind == "onehot":
        equal = [c.value for c, op, _ in conds if op == ">"]
        if equal:
            return f"{name} = {equal[0]}"
        remaining = [v for v in feature.values if v not in {c.value for c, _, _ in conds}]
        if not remaining:                                    # every value ruled out: only "absent" is left
            return f"{name} absent"
        text = f"{name} = {remaining[0]}" if len(remaining) == 1 else f"{name} in {{{', '.join(remaining)}}}"
        return text + (" (or absent)" if feature.active_when is not None else "")
    low = max((thr for _, op, thr in conds if op == ">"), default=None)
    high = min((thr for _, op, thr in conds if op == "<="), default=None)
    bottom = 0.0 if feature.discrete else feature.low       # codes below this mean "absent"
    if high is not None and high < bottom:
        return f"{name} absent"
    may_be_absent = feature.active_when is not None and low is None   # absent codes lie below every bound
    if low is not None and low < bottom:
        low = None                                           # "> absent code": present
    if feature.discrete:
        allowed = [v for r, v in enumerate(feature.values)
                   if (low is None or r > low) and (high is None or r <= high)]
        text = f"{name} = {allowed[0]}" if len(allowed) == 1 else f"{name} in {{{', '.join(allowed)}}}"
    else:
        unit = f" {feature.unit}" if feature.unit else ""
        bounds = ([f"> {low:.4g}"] if low is not None else []) + ([f"<= {high:.4g}"] if high is not None else [])
        text = f"{name} " + " and ".join(bounds) + unit if bounds else f"{name} present"
    if may_be_absent and text != f"{name} present" and (low is None and high is not None):
        text += " (or absent)"
    return text
