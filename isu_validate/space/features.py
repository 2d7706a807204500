"""One feature of a scene space: its type, domain, and what the SUT is asked about it."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from .conditions import Condition, parse_condition
from .errors import SpaceError

DISCRETE_TYPES = ("categorical", "ordinal")
NUMERIC_TYPES = ("integer", "continuous")
TYPES = DISCRETE_TYPES + NUMERIC_TYPES


@dataclass(frozen=True)
class Feature:
    name: str
    type: str
    values: tuple = ()            # categorical / ordinal domain
    low: float = 0.0              # integer / continuous domain
    high: float = 0.0
    unit: str = ""
    active_when: Condition | None = None
    predicted: bool = False
    weight: float = 0.0
    question: str = ""
    options: tuple[str, ...] = ()
    truth_map: Mapping[str, str] = field(default_factory=dict)
    caption: str = ""
    label: str = ""               # a short display name for people ("phone on the co-driver seat")
    describe: Mapping[str, str] = field(default_factory=dict)  # value -> plain text for a lab technician
    visible_parts: tuple[str, ...] = ()   # render parts that show it (see isu_validate/render/visibility.py)
    min_visible: float | None = None      # below this visible share it is occluded (None: the default)

    @property
    def display_name(self) -> str:
        return self.label or self.name.replace("_", " ")

    @property
    def discrete(self) -> bool:
        return self.type in DISCRETE_TYPES

    @property
    def span(self) -> float:
        """Width of the domain in encoding units (0 for a single-valued feature)."""
        if self.discrete:
            return float(len(self.values) - 1)
        return float(self.high - self.low)

    def is_active(self, scene: Mapping[str, Any]) -> bool:
        return self.active_when is None or self.active_when.matches(scene)

    def contains(self, value: Any) -> bool:
        if self.discrete:
            return value in self.values
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        if self.type == "integer" and int(value) != value:
            return False
        return self.low <= value <= self.high

    def truth(self, value: Any) -> str:
        """The correct answer option for a feature value."""
        if value is None:
            return "NONE"
        key = str(value)
        if key in self.truth_map:
            return self.truth_map[key]
        return self.truth_map.get("*", key)

    # ---- [0,1] encoding (min-max over the domain; ordinal and categorical by index)
    def encode(self, value: Any) -> float:
        if self.discrete:
            raw = float(self.values.index(value))
            low = 0.0
        else:
            raw, low = float(value), float(self.low)
        return (raw - low) / self.span if self.span > 0 else 0.0

    def decode(self, u: float) -> Any:
        u = min(1.0, max(0.0, float(u)))
        if self.discrete:
            return self.values[int(round(u * self.span))]
        value = self.low + u * self.span
        return int(round(value)) if self.type == "integer" else float(value)

    def to_toml_dict(self) -> dict:
        out: dict[str, Any] = {"type": self.type}
        if self.discrete:
            out["values"] = list(self.values)
        else:
            out.update(low=self.low, high=self.high)
        if self.active_when is not None:
            out["active_when"] = self.active_when.to_toml_dict()
        if self.predicted:
            out.update(predicted=True, weight=self.weight, question=self.question, options=list(self.options))
            if self.truth_map:
                out["truth"] = dict(self.truth_map)
            if self.visible_parts:
                out["visible_parts"] = list(self.visible_parts)
            if self.min_visible is not None:
                out["min_visible"] = self.min_visible
        return out


_KNOWN_KEYS = {"type", "values", "low", "high", "unit", "active_when", "predicted", "weight",
               "question", "options", "truth", "caption", "description", "label", "describe",
               "visible_parts", "min_visible"}


def parse_feature(name: str, raw: Mapping[str, Any], where: str) -> Feature:
    here = f"{where}: feature {name!r}"
    if not isinstance(raw, Mapping):
        raise SpaceError(f"{here}: must be a table")
    unknown = set(raw) - _KNOWN_KEYS
    if unknown:
        raise SpaceError(f"{here}: unknown keys {sorted(unknown)} (known: {sorted(_KNOWN_KEYS)})")
    kind = raw.get("type")
    if kind not in TYPES:
        raise SpaceError(f"{here}: unknown type {kind!r}; use one of {', '.join(TYPES)}")
    kwargs: dict[str, Any] = {"name": name, "type": kind, "unit": str(raw.get("unit", "")),
                              "caption": str(raw.get("caption", ""))}
    if kind in DISCRETE_TYPES:
        values = raw.get("values")
        if not isinstance(values, list) or not values:
            raise SpaceError(f"{here}: empty domain; list at least one value in `values`")
        if len(set(map(str, values))) != len(values):
            raise SpaceError(f"{here}: `values` has duplicates")
        kwargs["values"] = tuple(str(v) for v in values)
    else:
        try:
            low, high = float(raw["low"]), float(raw["high"])
        except (KeyError, TypeError, ValueError):
            raise SpaceError(f"{here}: a {kind} feature needs numeric `low` and `high`") from None
        if not low <= high:
            raise SpaceError(f"{here}: empty domain, low {low} > high {high}")
        if kind == "integer" and (low != int(low) or high != int(high)):
            raise SpaceError(f"{here}: integer bounds must be whole numbers")
        kwargs.update(low=low, high=high)
    kwargs.update(_parse_texts(raw, kwargs, here))
    if "active_when" in raw:
        kwargs["active_when"] = parse_condition(raw["active_when"], f"{here} active_when")
    if raw.get("predicted", False):
        kwargs.update(_parse_prediction(raw, kwargs, here))
    elif "visible_parts" in raw or "min_visible" in raw:
        raise SpaceError(f"{here}: visible_parts and min_visible belong to predicted features (only they are judged)")
    return Feature(**kwargs)


def _parse_texts(raw: Mapping[str, Any], kwargs: dict, here: str) -> dict:
    """``label`` and ``describe`` are for people (recreation sheets, reports): they never change the hash."""
    label = raw.get("label", "")
    if not isinstance(label, str):
        raise SpaceError(f"{here}: `label` must be a string, got {label!r}")
    describe = raw.get("describe", {})
    if not isinstance(describe, Mapping) or not all(isinstance(v, str) for v in describe.values()):
        raise SpaceError(f"{here}: `describe` must be a table of value = \"text\", got {describe!r}")
    unknown = [k for k in describe if kwargs.get("values") and k not in kwargs["values"]]
    if unknown:
        raise SpaceError(f"{here}: `describe` names {unknown}, which are not values of the feature "
                         f"(its values: {list(kwargs['values'])})")
    return {"label": label.strip(), "describe": {str(k): v.strip() for k, v in describe.items()}}


def _parse_prediction(raw: Mapping[str, Any], kwargs: dict, here: str) -> dict:
    if kwargs["type"] not in DISCRETE_TYPES:
        raise SpaceError(f"{here}: only categorical and ordinal features can be predicted")
    weight = raw.get("weight", 1.0)
    if isinstance(weight, bool) or not isinstance(weight, (int, float)) or weight < 0:
        raise SpaceError(f"{here}: weight must be a number >= 0, got {weight!r}")
    question = raw.get("question")
    if not isinstance(question, str) or not question.strip():
        raise SpaceError(f"{here}: a predicted feature needs a `question`")
    options = raw.get("options", list(kwargs["values"]) + ["NONE"])
    if not isinstance(options, list) or not options:
        raise SpaceError(f"{here}: `options` must list the answers the SUT may give")
    options = tuple(str(o) for o in options)
    truth_map = {str(k): str(v) for k, v in raw.get("truth", {}).items()}
    for value in kwargs["values"]:
        answer = truth_map.get(value, truth_map.get("*", value))
        if answer not in options:
            raise SpaceError(f"{here}: value {value!r} has the answer {answer!r}, "
                             f"which is not among the options {list(options)}")
    return {"predicted": True, "weight": float(weight), "question": question.strip(),
            "options": options, "truth_map": truth_map, **_parse_visibility(raw, here)}


def _parse_visibility(raw: Mapping[str, Any], here: str) -> dict:
    parts = raw.get("visible_parts", [])
    if not isinstance(parts, list) or not all(isinstance(p, str) and p.strip() for p in parts):
        raise SpaceError(f"{here}: visible_parts must list render part names, e.g. [\"driver_face\"]")
    share = raw.get("min_visible")
    if share is not None:
        if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0.0 <= share <= 1.0:
            raise SpaceError(f"{here}: min_visible must be a share in [0, 1], got {share!r}")
        if not parts:
            raise SpaceError(f"{here}: min_visible needs visible_parts (the parts whose visible share it bounds)")
        share = float(share)
    return {"visible_parts": tuple(p.strip() for p in parts), "min_visible": share}
