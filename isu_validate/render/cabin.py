"""Cabin rigs (``rigs/cabins/*.toml``): seat, anchor and phone-position geometry, lighting, optional assets."""
from __future__ import annotations

import hashlib
import json
import os
import tomllib
from pathlib import Path

from ..paths import resolve_rig
from ..errors import UserError

PHONE_POSITIONS = tuple(f"P{i}" for i in range(1, 11))
ASSET_PARTS = ("cabin", "driver_seat", "passenger_seat", "rear_bench", "steering_wheel",
               "luggage", "child_seat", "phone", "colabottle", "colacan")
# things lying on the co-driver seat: [codriver_seat.<feature>] position and rotation_deg
CODRIVER_SEAT_OBJECTS = ("phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat")
ASSET_SUFFIXES = (".glb", ".gltf", ".obj", ".fbx")
_REQUIRED = {"shell": ("x_rear", "x_front", "half_width", "roof", "belt_line", "dashboard_top"),
             "steering_wheel": ("centre", "radius", "tilt_deg"),
             "seat_belt": ("upper_anchor", "buckle", "lap_anchor"),
             "anchors": ("child_seat", "luggage_PASSENGER", "luggage_BACK", "interior_light", "rear_light"),
             "codriver_seat": CODRIVER_SEAT_OBJECTS,
             "lighting": ("environment_strength", "window_light_w", "interior_light_w")}
# the CC0 world HDRIs (Poly Haven, 1K) in the bpy wheel: bpy/<version>/datafiles/studiolights/world/<name>.exr
STUDIO_LIGHTS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")
LIGHT_LEVELS = ("LOW", "MEDIUM", "HIGH")


class CabinRigError(UserError, ValueError):
    """A cabin rig file is missing something or names an asset that cannot be used."""


def load_cabin(name_or_path: str | os.PathLike = "default") -> dict:
    """The cabin rig as a plain dict (sent to the Blender worker as JSON); asset paths made absolute."""
    path = Path(resolve_rig("cabins", name_or_path))
    try:
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise CabinRigError(f"{path}: not valid TOML: {exc}") from None
    _check(raw, str(path))
    raw["assets"] = _resolve_assets(raw.get("assets", {}), path)
    raw["source"] = str(path)
    return raw


def environment_for(lighting: dict, surroundings: str, external_light: str) -> str:
    """The studio light seen through the windows: the rig's `environment` when it names one sky for every
    scene, else its `surroundings` table's entry for the scene's surroundings and external light."""
    if "environment" in lighting:
        return lighting["environment"]
    table = lighting["surroundings"]
    if surroundings not in table:
        raise CabinRigError(f"the cabin rig's [lighting.surroundings] has no {surroundings!r}; it has "
                            f"{', '.join(table)} (see rigs/cabins/default.toml)")
    return table[surroundings][external_light]


def environments(lighting: dict) -> list[str]:
    """Every studio light the rig can show, sorted."""
    if "environment" in lighting:
        return [lighting["environment"]]
    return sorted({name for table in lighting["surroundings"].values() for name in table.values()})


def cabin_hash(cabin: dict) -> str:
    """Identifies the cabin's content (asset files by their bytes): part of the render cache key."""
    # `recreate` holds words and measurements for recreation sheets: it never changes a render
    content = {k: v for k, v in cabin.items() if k not in ("source", "name", "recreate")}
    digest = hashlib.sha256(json.dumps(content, sort_keys=True, default=str).encode())
    for part in sorted(cabin.get("assets", {})):
        digest.update(Path(cabin["assets"][part]["file"]).read_bytes())
    return digest.hexdigest()[:16]


# what a rig hand position's hand may hold: nothing (an open hand) or a can, gripped round its body with
# its top towards the thumb (drinking)
HAND_HOLDS = ("nothing", "can")


def _check(raw: dict, where: str) -> None:
    for table, keys in _REQUIRED.items():
        if not isinstance(raw.get(table), dict):
            raise CabinRigError(f"{where}: missing [{table}] table (copy it from rigs/cabins/default.toml)")
        missing = [k for k in keys if k not in raw[table]]
        if missing:
            raise CabinRigError(f"{where}: [{table}] lacks {', '.join(missing)} (see rigs/cabins/default.toml)")
    _check_lighting(raw["lighting"], where)
    seats = raw.get("seats", {})
    for seat in ("driver", "passenger", "rear"):
        if seat not in seats:
            raise CabinRigError(f"{where}: missing [seats.{seat}] (see rigs/cabins/default.toml)")
    for name in CODRIVER_SEAT_OBJECTS:
        spec = raw["codriver_seat"][name]
        if not (isinstance(spec, dict) and _triple(spec.get("position")) and _triple(spec.get("rotation_deg"))):
            raise CabinRigError(f"{where}: [codriver_seat] {name} needs position = [x, y, z] and "
                                f"rotation_deg = [rx, ry, rz] (see rigs/cabins/default.toml)")
    positions = raw.get("phone_positions", {})
    missing = [p for p in PHONE_POSITIONS if p not in positions]
    if missing:
        raise CabinRigError(f"{where}: [phone_positions] lacks {', '.join(missing)}; each needs hand, "
                            f"relative_to, offset and rotation_deg")
    for name, spec in positions.items():
        if not _reaches(spec):
            raise CabinRigError(f"{where}: [phone_positions.{name}] needs hand = 'left'|'right' and "
                                f"relative_to = 'head'|'shoulder'|'wheel'")
        if "fingers" in spec and not _triple(spec["fingers"]):
            raise CabinRigError(f"{where}: [phone_positions.{name}] fingers must be a direction [x, y, z] "
                                f"(where the fingers point; leave it out for away from the shoulder)")
        if not isinstance(spec.get("at_ear", False), bool):
            raise CabinRigError(f"{where}: [phone_positions.{name}] at_ear must be true or false (a call: the "
                                f"screen is dark), got {spec['at_ear']!r}")
        if "tilt" in spec and not _shares(spec["tilt"]):
            raise CabinRigError(f"{where}: [phone_positions.{name}] tilt must be three shares [tip, roll, turn] "
                                f"between 0 and 1 (how much of the space's phone_tip, phone_roll and phone_turn the "
                                f"phone takes there), got {spec['tilt']!r}")
    for name, spec in raw.get("hand_positions", {}).items():
        if not (_reaches(spec) and all(_triple(spec.get(k)) for k in ("offset", "palm", "fingers"))):
            raise CabinRigError(f"{where}: [hand_positions.{name}] needs hand = 'left'|'right', relative_to = "
                                f"'head'|'shoulder'|'wheel', offset = [x, y, z] and the directions palm and "
                                f"fingers = [x, y, z] (see rigs/cabins/default.toml)")
        if spec.get("holds", "nothing") not in HAND_HOLDS:
            raise CabinRigError(f"{where}: [hand_positions.{name}] holds must be one of {', '.join(HAND_HOLDS)} "
                                f"(what the hand holds there), got {spec['holds']!r}")

    for name, spec in raw.get("gaze_targets", {}).items():
        if not (isinstance(spec, dict) and spec.get("relative_to") in ("head", "shoulder", "wheel")
                and _triple(spec.get("offset")) and isinstance(spec.get("at_hands", False), bool)):
            raise CabinRigError(f"{where}: [gaze_targets.{name}] needs relative_to = 'head'|'shoulder'|'wheel', "
                                f"offset = [x, y, z] and at_hands = true|false (see rigs/cabins/default.toml)")


def _reaches(spec: dict) -> bool:
    """A phone or hand position names the hand that goes there and what its offset is measured from."""
    return spec.get("hand") in ("left", "right") and spec.get("relative_to") in ("head", "shoulder", "wheel")


def _check_lighting(light: dict, where: str) -> None:
    """The skies: one `environment` or a `surroundings` table of studio lights per external light."""
    fix = f"(studio lights: {', '.join(STUDIO_LIGHTS)}; see rigs/cabins/default.toml)"
    if "environment" in light:
        if light["environment"] not in STUDIO_LIGHTS:
            raise CabinRigError(f"{where}: [lighting] environment {light['environment']!r} is not a studio light {fix}")
    else:
        table = light.get("surroundings")
        if not isinstance(table, dict) or not table:
            raise CabinRigError(f"{where}: [lighting] needs `environment` (one sky) or [lighting.surroundings] "
                                f"tables (a sky per external light for each surroundings value) {fix}")
        for name, skies in table.items():
            if not isinstance(skies, dict) or set(skies) != set(LIGHT_LEVELS) or \
                    any(sky not in STUDIO_LIGHTS for sky in skies.values()):
                raise CabinRigError(f"{where}: [lighting.surroundings] {name} must map LOW, MEDIUM and HIGH to "
                                    f"studio lights {fix}")
    sun = light.get("sun_strength", {})
    if not isinstance(sun, dict) or any(k not in LIGHT_LEVELS or not isinstance(v, (int, float)) or v < 0
                                        for k, v in sun.items()):
        raise CabinRigError(f"{where}: [lighting] sun_strength must map external light levels (LOW, MEDIUM, HIGH) "
                            f"to the sun's strength in W/m² (0 or absent: no sun)")


def _triple(value) -> bool:
    return isinstance(value, list) and len(value) == 3 and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)


def _shares(value) -> bool:
    return _triple(value) and all(0.0 <= v <= 1.0 for v in value)


def _resolve_assets(assets: dict, rig_path: Path) -> dict:
    resolved = {}
    for part, spec in assets.items():
        if part not in ASSET_PARTS:
            raise CabinRigError(f"{rig_path}: [assets.{part}] is not a part that can be replaced; "
                                f"parts: {', '.join(ASSET_PARTS)}")
        spec = {"file": spec} if isinstance(spec, str) else dict(spec)
        file = (rig_path.parent / spec.get("file", "")).resolve()
        if file.suffix.lower() not in ASSET_SUFFIXES or not file.is_file():
            raise CabinRigError(f"{rig_path}: [assets.{part}] file {file} must be an existing "
                                f"{'/'.join(ASSET_SUFFIXES)} file (relative paths start at the rig file)")
        spec["file"] = str(file)
        resolved[part] = spec
    return resolved
