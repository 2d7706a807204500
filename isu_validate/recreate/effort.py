"""Recreation effort: what changing one scene into the next costs a lab, and an order that keeps it low.

People and child seats are slow to change, a can is quick (``rigs/effort/default.toml``, editable).
Finding the cheapest order is a shortest Hamiltonian path: exact (Held-Karp dynamic programming)
up to ``EXACT_MAX`` samples, beyond that the best greedy nearest-neighbour path improved by
2-opt and or-opt moves. The run's own order is always a candidate, so the chosen order never
costs more than it. Hand-written rather than a TSP package: the solvers on the registry
(python-tsp, elkai, fast-tsp) either pull in a dozen dependencies or want symmetric closed
tours, and this is forty lines of well-known algorithms.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from ..paths import resolve_rig
from ..space import SceneSpace
from ..tomlfile import read_toml
from ..errors import UserError

EXACT_MAX = 12


class EffortError(UserError, ValueError):
    """An effort file that cannot be used; the message names the file and the fix."""


@dataclass(frozen=True)
class ChangeGroup:
    name: str
    features: tuple[str, ...]
    minutes: float
    tolerance: float = 0.0
    note: str = ""


@dataclass
class EffortModel:
    groups: list[ChangeGroup]
    default: float
    per_scene: float
    source: str = "<memory>"
    unused: list[str] = field(default_factory=list)   # features named in the file but absent from the space

    def changed(self, a: Mapping[str, Any] | None, b: Mapping[str, Any]) -> list[ChangeGroup]:
        """The groups that change from scene ``a`` (canonical; None: an empty car) to scene ``b``."""
        return [g for g in self.groups if _differs(g, a, b)]

    def step(self, a: Mapping[str, Any] | None, b: Mapping[str, Any]) -> float:
        return self.per_scene + sum(g.minutes for g in self.changed(a, b))

    def matrix(self, scenes: Sequence[Mapping[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
        """(setup[j]: an empty car to scene j, cost[i, j]: scene i to scene j) in minutes."""
        setup = np.array([self.step(None, s) for s in scenes])
        cost = np.array([[self.step(a, b) for b in scenes] for a in scenes])
        return setup, cost

    def total(self, scenes: Sequence[Mapping[str, Any]], order: Sequence[int] | None = None) -> float:
        order = list(range(len(scenes))) if order is None else list(order)
        return path_cost(*self.matrix(scenes), order)


def _differs(group: ChangeGroup, a, b) -> bool:
    for name in group.features:
        if a is None:
            if name in b:
                return True
            continue
        if (name in a) != (name in b):
            return True
        if name not in a:
            continue
        va, vb = a[name], b[name]
        if isinstance(va, (int, float)) and isinstance(vb, (int, float)) and not isinstance(va, bool):
            if abs(float(va) - float(vb)) > group.tolerance:
                return True
        elif va != vb:
            return True
    return False


def load_effort(name_or_path: str | os.PathLike, space: SceneSpace) -> EffortModel:
    """The lab's change costs for ``space``: every feature is in exactly one group."""
    try:
        path = resolve_rig("effort", name_or_path)
    except FileNotFoundError as exc:
        raise EffortError(str(exc)) from None
    raw = read_toml(path, EffortError, "effort file")
    where = str(path)
    default, per_scene = (_minutes(raw.get(k, d), f"{where}: `{k}`") for k, d in (("default", 0.5), ("per_scene", 0.0)))
    groups, seen, unused = [], set(), []
    for name, spec in (raw.get("groups") or {}).items():
        here = f"{where}: [groups.{name}]"
        if not isinstance(spec, dict) or not isinstance(spec.get("features"), list):
            raise EffortError(f"{here} needs `features = [...]` and `minutes = N`")
        names = [str(f) for f in spec["features"]]
        twice = sorted(seen & set(names))
        if twice:
            raise EffortError(f"{here}: {twice} already belong to another group; put each feature in one group")
        seen |= set(names)
        unused += [f for f in names if f not in space.features]
        present = tuple(f for f in names if f in space.features)
        group = ChangeGroup(name, present, _minutes(spec.get("minutes"), f"{here} `minutes`"),
                            _minutes(spec.get("tolerance", 0.0), f"{here} `tolerance`"), str(spec.get("note", "")))
        if present:
            groups.append(group)
    for feature in space.names:
        if feature not in seen:
            groups.append(ChangeGroup(feature, (feature,), default, note=space.features[feature].display_name))
    return EffortModel(groups, default, per_scene, where, unused)


def _minutes(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0:
        raise EffortError(f"{where} must be a number of minutes >= 0, got {value!r}")
    return float(value)


# ---------------------------------------------------------------------- ordering
def path_cost(setup: np.ndarray, cost: np.ndarray, order: Sequence[int]) -> float:
    if not len(order):
        return 0.0
    o = np.asarray(order, dtype=int)
    return float(setup[o[0]] + cost[o[:-1], o[1:]].sum())


def best_order(setup: np.ndarray, cost: np.ndarray) -> list[int]:
    """The cheapest order found (exact up to EXACT_MAX samples); never dearer than 0, 1, 2, ..."""
    n = len(setup)
    if n <= 1:
        return list(range(n))
    candidates = [list(range(n))]
    if n <= EXACT_MAX:
        candidates.append(_held_karp(setup, cost))
    else:
        greedy = min((_nearest_neighbour(setup, cost, s) for s in range(n)), key=lambda o: path_cost(setup, cost, o))
        candidates += [_improve(setup, cost, greedy), _improve(setup, cost, list(range(n)))]
    return min(candidates, key=lambda o: path_cost(setup, cost, o))


def _held_karp(setup: np.ndarray, cost: np.ndarray) -> list[int]:
    """Exact shortest path visiting every sample once, starting anywhere (from the empty car)."""
    n = len(setup)
    full = 1 << n
    best = np.full((full, n), np.inf)
    parent = np.full((full, n), -1, dtype=int)
    for j in range(n):
        best[1 << j, j] = setup[j]
    for mask in range(1, full):
        ends = [j for j in range(n) if mask >> j & 1 and np.isfinite(best[mask, j])]
        for j in ends:
            for k in range(n):
                if mask >> k & 1:
                    continue
                nxt, value = mask | 1 << k, best[mask, j] + cost[j, k]
                if value < best[nxt, k]:
                    best[nxt, k], parent[nxt, k] = value, j
    mask, j = full - 1, int(np.argmin(best[full - 1]))
    order = []
    while j >= 0:
        order.append(j)
        mask, j = mask & ~(1 << j), parent[mask, j]
    return order[::-1]


def _nearest_neighbour(setup: np.ndarray, cost: np.ndarray, start: int) -> list[int]:
    order, left = [start], set(range(len(setup))) - {start}
    while left:
        here = order[-1]
        order.append(min(left, key=lambda k: (cost[here, k], k)))
        left.discard(order[-1])
    return order


def _improve(setup: np.ndarray, cost: np.ndarray, order: list[int]) -> list[int]:
    """2-opt (reverse a stretch) and or-opt (move one sample) until neither helps."""
    best, value = list(order), path_cost(setup, cost, order)
    improved = True
    while improved:
        improved = False
        n = len(best)
        for i in range(n - 1):
            for j in range(i + 1, n):
                for trial in (best[:i] + best[i:j + 1][::-1] + best[j + 1:],
                              best[:i] + best[i + 1:j + 1] + [best[i]] + best[j + 1:]):
                    v = path_cost(setup, cost, trial)
                    if v < value - 1e-9:
                        best, value, improved = trial, v, True
    return best
