"""Conditions over scene features: ``{feature: value | [values] | {in|not_in|min|max}}``.

An inactive feature (absent from the scene, or ``None``) matches no ``in``,
``min`` or ``max`` term and every ``not_in`` term: a missing suitcase is on no
seat, so it is certainly not on the passenger seat.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping


@dataclass(frozen=True)
class Term:
    feature: str
    inside: tuple | None = None   # allowed values
    outside: tuple | None = None  # forbidden values
    low: float | None = None
    high: float | None = None

    def matches(self, scene: Mapping[str, Any]) -> bool:
        value = scene.get(self.feature)
        if value is None:
            return self.inside is None and self.low is None and self.high is None
        if self.inside is not None and value not in self.inside:
            return False
        if self.outside is not None and value in self.outside:
            return False
        if self.low is not None and not float(value) >= self.low:
            return False
        if self.high is not None and not float(value) <= self.high:
            return False
        return True


@dataclass(frozen=True)
class Condition:
    terms: tuple[Term, ...]

    def matches(self, scene: Mapping[str, Any]) -> bool:
        return all(t.matches(scene) for t in self.terms)

    @property
    def features(self) -> tuple[str, ...]:
        return tuple(t.feature for t in self.terms)

    def to_toml_dict(self) -> dict:
        out = {}
        for t in self.terms:
            spec = {}
            if t.inside is not None:
                spec["in"] = list(t.inside)
            if t.outside is not None:
                spec["not_in"] = list(t.outside)
            if t.low is not None:
                spec["min"] = t.low
            if t.high is not None:
                spec["max"] = t.high
            out[t.feature] = spec
        return out


def parse_condition(raw: Any, where: str) -> Condition:
    """Parse a TOML condition table; ``where`` names the place for error messages."""
    from .errors import SpaceError

    if not isinstance(raw, Mapping) or not raw:
        raise SpaceError(f"{where}: a condition must be a non-empty table of feature = value(s)")
    terms = []
    for feature, spec in raw.items():
        if isinstance(spec, (str, int, float, bool)):
            terms.append(Term(feature, inside=(spec,)))
        elif isinstance(spec, list):
            if not spec:
                raise SpaceError(f"{where}: condition on {feature!r} lists no values")
            terms.append(Term(feature, inside=tuple(spec)))
        elif isinstance(spec, Mapping):
            unknown = set(spec) - {"in", "not_in", "min", "max"}
            if unknown:
                raise SpaceError(f"{where}: condition on {feature!r} has unknown keys {sorted(unknown)}; "
                                 "use in, not_in, min, max")
            terms.append(Term(
                feature,
                inside=tuple(spec["in"]) if "in" in spec else None,
                outside=tuple(spec["not_in"]) if "not_in" in spec else None,
                low=float(spec["min"]) if "min" in spec else None,
                high=float(spec["max"]) if "max" in spec else None,
            ))
        else:
            raise SpaceError(f"{where}: cannot read the condition on {feature!r}: {spec!r}")
    return Condition(tuple(terms))
