"""What the light levels mean: per value of each light feature, what the render used and a light a lab can
arrange, from the cabin rig (``[lighting]``, and ``[recreate.<feature>] lighting`` / ``practical``).

The render's numbers are Blender's (sky strength, window light in W/m2, lamp power in W): they say
what was rendered, not what a lux meter reads. What carries over to a lab is the practical words and
how bright each exterior level is against the brightest one (their window light over its), which a lux
meter at the driver's face can check.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

from ..space import SceneSpace


@dataclass(frozen=True)
class LightRow:
    feature: str
    title: str           # the feature's words ("external light")
    value: str
    rendered: str        # what the render used
    relative: str        # against the brightest value of the same feature ("" where it means nothing)
    practical: str       # what a lab can arrange
    chosen: bool         # the scene's value


def light_rows(space: SceneSpace, scene: Mapping[str, Any], cabin: dict) -> list[LightRow]:
    """Every value of every light feature the rig describes, the scene's own marked."""
    canonical = space.canonical(scene)
    rules = cabin.get("recreate") if isinstance(cabin.get("recreate"), dict) else {}
    rows = []
    for name, feature in space.features.items():
        rule = rules.get(name)
        kind = rule.get("lighting") if isinstance(rule, Mapping) else None
        if kind not in RENDERED:
            continue
        for value in feature.values:
            rendered, relative = RENDERED[kind](cabin, str(value), rule, canonical)
            rows.append(LightRow(name, feature.display_name, str(value), rendered, relative,
                                 str((rule.get("practical") or {}).get(str(value), "")),
                                 canonical.get(name) == value))
    return rows


def _exterior(cabin: dict, value: str, rule: Mapping, scene: Mapping[str, Any]) -> tuple[str, str]:
    from ..render.cabin import environment_for
    from ..render.renderer import DEFAULTS
    light = cabin["lighting"]
    window = float(light["window_light_w"][value])
    brightest = max(float(v) for v in light["window_light_w"].values())
    share = window / brightest
    relative = "1" if share == 1 else f"{share:.2g} ({math.log2(share):+.1f} stops)"
    sky = environment_for(light, scene.get("surroundings", DEFAULTS["surroundings"]), value)
    sun = float(light.get("sun_strength", {}).get(value, 0.0))
    return (f"{sky} sky x{float(light['environment_strength'][value]):g}, "
            f"window light {window:g} W/m²{f', sun {sun:g} W/m²' if sun else ''}", relative)


def _lamps(cabin: dict, value: str, rule: Mapping, scene: Mapping[str, Any]) -> tuple[str, str]:
    if value != "ON":   # the renderer lights the lamps for ON (render/blender/lighting.py)
        return "no lamp", ""
    anchors = cabin.get("anchors", {})
    where = ", ".join(f"{anchors[a][0]:+.2f}" for a in rule.get("lamps", ()) if a in anchors)
    count = len(rule.get("lamps", ()))
    return (f"{count} warm lamp{'s' if count != 1 else ''} of {float(cabin['lighting']['interior_light_w']):g} W "
            f"(roof, x = {where} m)", "")


RENDERED = {"exterior": _exterior, "lamps": _lamps}
