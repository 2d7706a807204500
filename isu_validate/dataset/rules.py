"""Failure-region rules read back: the text ``report`` prints for a decision-tree leaf
(``analysis/regions.py: describe``), or one a user writes by hand, as a test on scenes.

    rule = parse_rule(space, "luggage_colour = YELLOW and external_light = HIGH")
    rule.holds(canonical_scene)             # True inside the region

The language is what ``describe`` writes, joined by `` and ``:

- ``F = V``, ``F in {A, B}`` (values of a categorical or ordinal feature);
- ``F > x``, ``F <= y``, ``F > x and <= y`` (numeric features; ``<`` and ``>=`` too), a unit may follow;
- ``F absent``, ``F present`` (features with ``active_when``); ``(or absent)`` after a clause admits a scene
  where the feature is inactive;
- ``all tests``: every scene.

A feature, value or clause the space does not have is an ``InputError`` naming it.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ..errors import InputError
from ..space import SceneSpace

EVERYTHING = "all tests"
OR_ABSENT = "(or absent)"
_BOUND = re.compile(r"^(>=|<=|>|<)\s*(-?[0-9.eE+-]+)$")
_OPS = {">": (True, False), ">=": (True, True), "<": (False, False), "<=": (False, True)}   # (lower?, inclusive)


@dataclass(frozen=True)
class Clause:
    """One feature's condition: allowed values (discrete) or bounds (numeric), or mere presence."""
    feature: str
    values: tuple | None = None        # allowed values of a discrete feature (None: any)
    low: float | None = None
    low_inclusive: bool = False
    high: float | None = None
    high_inclusive: bool = True
    present: bool = True               # False: the clause asks for the feature to be inactive
    or_absent: bool = False            # an inactive feature passes too

    def holds(self, canonical: Mapping[str, Any]) -> bool:
        value = canonical.get(self.feature)
        if value is None:
            return not self.present or self.or_absent
        if not self.present:
            return False
        if self.values is not None and value not in self.values:
            return False
        if self.low is not None and not (value >= self.low if self.low_inclusive else value > self.low):
            return False
        return self.high is None or (value <= self.high if self.high_inclusive else value < self.high)


@dataclass(frozen=True)
class Rule:
    text: str
    clauses: tuple[Clause, ...]

    def holds(self, canonical: Mapping[str, Any]) -> bool:
        return all(c.holds(canonical) for c in self.clauses)

    def force(self, space: SceneSpace, scene: dict, rng: np.random.Generator) -> dict:
        """``scene`` with each clause's feature set to a value the clause allows (presence is left to the
        caller's repair and check: it depends on other features)."""
        out = dict(scene)
        for clause in self.clauses:
            feature = space.features[clause.feature]
            if not clause.present:
                continue
            if clause.values is not None:
                out[clause.feature] = clause.values[int(rng.integers(len(clause.values)))]
            elif not feature.discrete:
                low = max(feature.low, clause.low if clause.low is not None else feature.low)
                high = min(feature.high, clause.high if clause.high is not None else feature.high)
                if low <= high:
                    value = float(rng.uniform(low, high))
                    out[clause.feature] = int(np.clip(round(value), np.ceil(low), np.floor(high))) \
                        if feature.type == "integer" else value
        return out


def parse_rule(space: SceneSpace, text: str) -> Rule:
    """The rule ``text`` over ``space``'s features; InputError naming what is wrong with it."""
    text = " ".join(str(text).split())
    if not text:
        raise InputError("empty rule; write e.g. \"luggage_colour = YELLOW and external_light = HIGH\"")
    if text == EVERYTHING:
        return Rule(text, ())
    clauses: list[Clause] = []
    for piece in _clause_texts(text):
        clause = _clause(space, piece, text)
        if any(c.feature == clause.feature for c in clauses):
            raise InputError(f"rule {text!r}: feature {clause.feature!r} appears twice; write its condition once")
        clauses.append(clause)
    return Rule(text, tuple(clauses))


def _clause_texts(text: str) -> list[str]:
    """The rule split at `` and ``, a bare bound (``<= 60 deg``) joined to the numeric clause before it."""
    pieces: list[str] = []
    for part in text.split(" and "):
        if pieces and re.match(r"^(>=|<=|>|<)\s", part):
            pieces[-1] += " and " + part
        else:
            pieces.append(part)
    return pieces


def _clause(space: SceneSpace, piece: str, rule: str) -> Clause:
    or_absent = piece.endswith(OR_ABSENT)
    body = piece[: -len(OR_ABSENT)].strip() if or_absent else piece
    name, _, rest = body.partition(" ")
    if name not in space.features:
        raise InputError(f"rule {rule!r}: unknown feature {name!r} (features of space {space.name!r}: "
                         f"{', '.join(space.names)})")
    feature = space.features[name]
    if or_absent and feature.active_when is None:
        raise InputError(f"rule {rule!r}: {name} is never absent (it has no active_when); drop {OR_ABSENT!r}")
    rest = rest.strip()
    if rest in ("absent", "present"):
        if feature.active_when is None and rest == "absent":
            raise InputError(f"rule {rule!r}: {name} is never absent (it has no active_when)")
        return Clause(name, present=rest == "present")
    if rest.startswith("= "):
        return Clause(name, values=(_value(feature, rest[2:].strip(), rule),), or_absent=or_absent)
    if rest.startswith("in {") and rest.endswith("}"):
        values = tuple(_value(feature, v.strip(), rule) for v in rest[4:-1].split(",") if v.strip())
        if not values:
            raise InputError(f"rule {rule!r}: {name} in {{}} allows no value")
        return Clause(name, values=values, or_absent=or_absent)
    return _bounds(feature, rest, or_absent, rule)


def _value(feature, raw: str, rule: str) -> str:
    if not feature.discrete:
        raise InputError(f"rule {rule!r}: {feature.name} is numeric; compare it with >, >=, <, <=")
    raw = raw.strip("'\"")
    if raw in feature.values:
        return raw
    folded = [v for v in feature.values if v.lower() == raw.lower()]
    if len(folded) == 1:
        return folded[0]
    raise InputError(f"rule {rule!r}: {raw!r} is not a value of {feature.name} (its values: "
                     f"{', '.join(feature.values)})")


def _bounds(feature, rest: str, or_absent: bool, rule: str) -> Clause:
    if feature.discrete:
        raise InputError(f"rule {rule!r}: cannot read {feature.name} {rest!r}; a {feature.type} feature takes "
                         f"'= VALUE' or 'in {{A, B}}' (values: {', '.join(feature.values)})")
    if feature.unit and rest.endswith(" " + feature.unit):
        rest = rest[: -len(feature.unit) - 1]
    bounds = {}
    for part in rest.split(" and "):
        match = _BOUND.match(part.strip())
        try:
            number = float(match.group(2)) if match else None
        except ValueError:
            number = None
        if number is None:
            raise InputError(f"rule {rule!r}: cannot read {feature.name} {rest!r}; write e.g. "
                             f"'{feature.name} > {feature.low:g} and <= {feature.high:g}'")
        lower, inclusive = _OPS[match.group(1)]
        bounds["low" if lower else "high"] = (number, inclusive)
    low, high = bounds.get("low", (None, False)), bounds.get("high", (None, True))
    return Clause(feature.name, low=low[0], low_inclusive=low[1], high=high[0], high_inclusive=high[1],
                  or_absent=or_absent)
