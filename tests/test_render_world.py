"""The world outside the windows and the car's style (issue 44): the skies ship in the bpy wheel under CC0,
the cabin rig chooses them per light and surroundings, isu-paper stays as it was, and a render shows the
world through the window glass (which is no render instance) and each value of the new features."""
from __future__ import annotations

import copy
import hashlib
import importlib.util
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from capture.camera import load_camera
from isu_validate.render import DEFAULTS, open_renderer
from isu_validate.render.cabin import (STUDIO_LIGHTS, CabinRigError, _check_lighting, environment_for,
                                       environments, load_cabin)
from isu_validate.render.labels import INSTANCE_ID
from isu_validate.space import load_space

ROOT = Path(__file__).resolve().parents[1]
# the draft preset (320x240, 1 sample, denoised): what a window shows in the cheapest frames a run makes
TEST_PRESET = "draft"
NEW = ("surroundings", "sun_direction", "cabin_trim", "seat_material")
SCENE = {"driver_gender": "MALE", "driver_emotion": "SERIOUS", "driver_height": "H2", "driver_weight": "W2",
         "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "NO",
         "car_lights": "OFF", "external_light": "HIGH", "luggage": "NO", "phone_codriver_seat": "NO",
         "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO", "driver_skin_tone": "MEDIUM",
         "driver_hair_colour": "BROWN", "driver_hair_style": "SHORT", "surroundings": "TREES",
         "sun_direction": "FRONT", "cabin_trim": "GREY", "seat_material": "FABRIC",
         # isu-diverse's clothes, as isu-paper renders them (a plain T-shirt, navy trousers, nothing else)
         "driver_top": "TSHIRT", "driver_top_print": "PLAIN", "driver_trousers_colour": "NAVY",
         "driver_eyewear": "NONE", "driver_cap": "NO", "driver_watch": "NO",
         # ... both hands on the wheel, the screen as used
         "driver_hands": "WHEEL", "driver_gaze": "ROAD", "phone_screen": "BY_USE", "seat_belt_colour": "CHARCOAL"}


def _world_folder() -> Path:
    bpy_dir = Path(importlib.util.find_spec("bpy").submodule_search_locations[0])
    found = sorted(bpy_dir.glob("*/datafiles/studiolights/world"))
    assert found, f"no studiolights/world folder in the installed bpy ({bpy_dir})"
    return found[-1]


def test_the_skies_the_rig_names_ship_in_the_installed_bpy_under_cc0():
    world = _world_folder()
    assert "licensed as CC0" in (world / "license.txt").read_text()
    assert {p.stem for p in world.glob("*.exr")} == set(STUDIO_LIGHTS)
    names = environments(load_cabin("default")["lighting"])
    assert len(names) >= 5
    for name in names:
        assert (world / f"{name}.exr").stat().st_size > 50_000, name


def test_isu_paper_is_unchanged_and_isu_diverse_adds_the_world_as_unasked_features():
    digest = hashlib.sha256((ROOT / "rigs/spaces/isu-paper.toml").read_bytes()).hexdigest()
    assert digest == "8ff24fce6058a9238024751a80e7ac5ef23b1119d3c56a30129f282e97ed185b"
    paper, diverse = load_space("isu-paper"), load_space("isu-diverse")
    assert paper.hash == "455a004df69c278b" and not set(NEW) & set(paper.names)
    for name in NEW:
        assert name in diverse.names and not diverse.features[name].predicted and name in DEFAULTS
    # the sun only shines in HIGH light: in LOW or MEDIUM the feature does not exist (nor reach the renderer)
    low = diverse.canonical({**SCENE, "external_light": "LOW"})
    assert "sun_direction" not in low and diverse.canonical(SCENE)["sun_direction"] == "FRONT"
    # every surroundings value has a sky at every light; isu-paper's scenes get the default's
    lighting = load_cabin("default")["lighting"]
    for value in diverse.features["surroundings"].values:
        for level in ("LOW", "MEDIUM", "HIGH"):
            assert environment_for(lighting, value, level) in STUDIO_LIGHTS
    assert [environment_for(lighting, DEFAULTS["surroundings"], lv) for lv in ("LOW", "MEDIUM", "HIGH")] == \
        ["sunset", "city", "city"]


@pytest.mark.parametrize("edit, message", [
    (lambda light: light["surroundings"]["TOWN"].update(HIGH="beach"), "TOWN must map LOW, MEDIUM and HIGH"),
    (lambda light: light["surroundings"]["TREES"].pop("LOW"), "TREES must map"),
    (lambda light: light.pop("surroundings"), "needs `environment` \\(one sky\\) or"),
    (lambda light: light.update(environment="moon"), "'moon' is not a studio light"),
    (lambda light: light.update(sun_strength={"HIGH": -1}), "sun_strength must map"),
])
def test_a_cabin_rig_with_bad_skies_is_refused_naming_the_fix(edit, message):
    light = copy.deepcopy(load_cabin("default")["lighting"])
    edit(light)
    with pytest.raises(CabinRigError, match=message) as info:
        _check_lighting(light, "my.toml")
    assert str(info.value).startswith("my.toml: ")
    assert "studio lights: city, courtyard" in str(info.value) or "sun_strength" in message


def test_one_environment_overrides_the_table_and_an_unknown_surroundings_is_refused():
    lighting = {**load_cabin("default")["lighting"], "environment": "sunset"}
    assert environment_for(lighting, "TREES", "HIGH") == "sunset" and environments(lighting) == ["sunset"]
    with pytest.raises(CabinRigError, match="has no 'BEACH'"):
        environment_for(load_cabin("default")["lighting"], "BEACH", "HIGH")


@pytest.fixture(scope="module")
def renderer(tmp_path_factory):
    root = tmp_path_factory.mktemp("world")
    plain = replace(load_camera("default"), imaging=None)   # auto-exposure off: pixels follow the scene
    r = open_renderer(TEST_PRESET, camera=plain, channels=("seg",), space="isu-diverse", log_dir=root / "logs")
    yield r, root
    r.close()


def _render(renderer, scene, name):
    r, root = renderer
    result = r.render(scene, root / f"{name}.png")
    return (cv2.imread(str(result.image)).astype(float),
            cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED))


def test_the_world_shows_through_the_windows_with_detail(renderer):
    """Through the windows (pixels where the segmentation shows nothing of the car: the exterior) there is
    a world, not a uniform wall: its pixels vary, and other surroundings look different there."""
    trees, seg = _render(renderer, SCENE, "trees")
    outside = seg == 0
    assert outside.sum() > 0.03 * seg.size, "no window shows the exterior"
    grey = trees.mean(axis=2)[outside]
    assert grey.std() > 12 and np.percentile(grey, 90) - np.percentile(grey, 10) > 30
    town, seg2 = _render(renderer, {**SCENE, "surroundings": "TOWN"}, "town")
    both = outside & (seg2 == 0)
    assert np.abs(trees - town).max(axis=2)[both].mean() > 10
    assert (seg2 == INSTANCE_ID["driver"]).sum() > 0


# where each feature shows: the whole frame (light) or the seats (their covers)
WHERE = {"seat_material": ("driver_seat", "passenger_seat", "rear_bench")}


@pytest.mark.parametrize("name", NEW)
def test_every_value_of_the_new_features_changes_the_image(renderer, name):
    values = load_space("isu-diverse").features[name].values
    rendered = [_render(renderer, {**SCENE, name: v}, f"{name}-{v}") for v in values]
    (first, seg), others = rendered[0], rendered[1:]
    for value, (image, seg_v) in zip(values[1:], others):
        assert (seg_v == seg).all(), f"{name}={value} moved something: it changes looks only"
        changed = np.abs(image - first).max(axis=2) > 12
        assert changed.sum() >= 50, f"{name}={value} looks like {name}={values[0]}"
        if name in WHERE:
            inside = np.isin(seg, [INSTANCE_ID[p] for p in WHERE[name]])
            assert changed[inside].sum() >= 0.6 * changed.sum(), f"{name}: the change is not on the seats"
