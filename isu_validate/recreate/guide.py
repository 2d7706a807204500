"""What a lab technician must set up for one scene: a plain-language checklist of its active features.

Words come from the scene space (a feature's ``label`` and ``describe``, e.g. a height class
as "1.50-1.60 m"), with readable defaults; where things go comes from the cabin rig's
``[recreate.<feature>]`` tables, in the cabin frame the technician measures in. Nothing here
knows a feature by name: the space and the rig say everything.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from ..space import SceneSpace
from ..space.features import Feature
from .body import weight_at_height

AXES = "x forward, y left, z up; origin on the centre line, floor level, at the centre of the front seat cushions"


@dataclass
class Placement:
    text: str                                   # measured position in words
    point: tuple[float, float, float] | None    # cabin frame, metres (for the sketch)
    angle_deg: float | None = None              # about z, counter-clockwise seen from above
    footprint: tuple[float, float] | None = None


@dataclass
class Item:
    feature: str
    title: str
    text: str
    placement: Placement | None = None
    crop_parts: tuple[str, ...] = ()
    hidden: float | None = None      # the visible share when the render hid it (occluded: set, never judged)


def readable(feature: Feature, value: Any) -> str:
    """The value in words: the space's description, else a tidy form of the value itself."""
    if str(value) in feature.describe:
        return feature.describe[str(value)]
    if feature.type == "continuous":
        unit = {"deg": "°"}.get(feature.unit, f" {feature.unit}" if feature.unit else "")
        return f"{float(value):.0f}{unit}"
    if feature.type == "integer":
        return f"{int(value)}{' ' + feature.unit if feature.unit else ''}"
    text = str(value)
    words = text.replace("_", "").isalpha() and text.isupper()   # FRONT_FACING, not H4 or P10
    return text.replace("_", " ").lower() if words else text


def checklist(space: SceneSpace, scene: Mapping[str, Any], cabin: dict,
              hidden: Mapping[str, float] | None = None) -> list[Item]:
    """One item per active feature of the scene, in the space's order. ``hidden``: the features the
    render marked occluded, with their visible share (the run's label: ``occluded``, ``visibility``)."""
    canonical = space.canonical(scene)
    rules = cabin.get("recreate", {}) if isinstance(cabin.get("recreate"), dict) else {}
    hidden = hidden or {}
    items = []
    for name, value in canonical.items():
        feature = space.features[name]
        rule = rules.get(name, {})
        text = _words(feature, value, rule, canonical)
        note = (rule.get("notes") or {}).get(str(value))
        if note and note not in text:
            text = f"{text} ({note})"
        crop = tuple(getattr(feature, "visible_parts", ()) or rule.get("crop", ()))
        items.append(Item(name, feature.display_name, text, _placement(rule, value, cabin), crop, hidden.get(name)))
    _apply_turns(items, rules, canonical)
    return items


def _words(feature: Feature, value: Any, rule: Mapping, canonical: Mapping[str, Any]) -> str:
    """The value in words; a weight class as kilograms at the rendered stature when the rig links the two."""
    height_feature = rule.get("weight_at_height_of")
    if height_feature in canonical:
        text = weight_at_height(str(value), str(canonical[height_feature]))
        if text:
            return text
    return readable(feature, value)


def _placement(rule: Mapping, value: Any, cabin: dict) -> Placement | None:
    place = rule.get("place")
    if isinstance(place, Mapping):
        place = place.get(str(value))
    if not isinstance(place, str):
        return None
    section, _, key = place.replace("{value}", str(value)).partition(".")
    target = (cabin.get(section) or {}).get(key)
    footprint = tuple(rule["footprint"]) if "footprint" in rule else None
    if isinstance(target, list) and len(target) == 3:
        x, y, z = (float(v) for v in target)
        return Placement(f"at x = {x:+.2f} m, y = {y:+.2f} m, z = {z:.2f} m", (x, y, z), None, footprint)
    if isinstance(target, Mapping) and "position" in target:   # a placed object: position and XYZ rotation
        x, y, z = (float(v) for v in target["position"])
        turn = float((target.get("rotation_deg") or (0.0, 0.0, 0.0))[2])
        return Placement(f"at x = {x:+.2f} m, y = {y:+.2f} m, z = {z:.2f} m", (x, y, z), turn, footprint)
    if isinstance(target, Mapping) and "offset" in target:   # a hand position, relative to the body
        dx, dy, dz = (float(v) for v in target["offset"])
        return Placement(f"{target.get('hand', '?')} hand, {dx:+.2f} / {dy:+.2f} / {dz:+.2f} m "
                         f"(x / y / z) from the centre of the driver's {target.get('relative_to', '?')}", None)
    return None


def sketch_number(items: list[Item], placed: Item) -> int:
    """The number the sketch gives a placed thing (things with a point, in checklist order)."""
    drawn = [i for i in items if i.placement and i.placement.point]
    return drawn.index(placed) + 1 if placed in drawn else 0


def _apply_turns(items: list[Item], rules: Mapping, canonical: Mapping[str, Any]) -> None:
    """An angle feature turns the thing another feature placed: put the angle on that placement."""
    by_feature = {i.feature: i for i in items}
    for item in items:
        target = (rules.get(item.feature) or {}).get("turns")
        placed = by_feature.get(target)
        if not placed or not placed.placement or not isinstance(canonical.get(item.feature), (int, float)):
            continue
        angle = float(canonical[item.feature])
        placed.placement.angle_deg = angle
        item.text = (f"{item.text} counter-clockwise seen from above; 0° = its front facing forward "
                     f"(drawn at ({sketch_number(items, placed)}) on the sketch)")
