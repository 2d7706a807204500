"""What the hands do besides holding a phone, and the phone's screen (issue 44, `isu-blender-10`): unasked
features of isu-diverse only; isu-paper keeps both hands on the wheel and renders the screen BY_USE."""
from __future__ import annotations

import numpy as np
import pytest

from isu_validate.render.renderer import DEFAULTS
from isu_validate.space import load_space

BASE = {"driver_gender": "MALE", "driver_emotion": "SERIOUS", "driver_height": "H2", "driver_weight": "W2",
        "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "NO",
        "car_lights": "OFF", "external_light": "MEDIUM", "luggage": "NO", "phone_codriver_seat": "NO",
        "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO",
        # isu-diverse's looks, world and car as isu-paper renders them
        "driver_skin_tone": "MEDIUM", "driver_hair_colour": "BROWN", "driver_hair_style": "SHORT",
        "driver_top": "TSHIRT", "driver_top_print": "PLAIN", "driver_trousers_colour": "NAVY",
        "driver_eyewear": "NONE", "driver_cap": "NO", "driver_watch": "NO", "surroundings": "TOWN",
        "cabin_trim": "GREY", "seat_material": "FABRIC", "driver_hands": "WHEEL", "phone_screen": "BY_USE"}


def test_hands_and_screen_are_unasked_features_of_isu_diverse_with_the_paper_defaults():
    paper, diverse = load_space("isu-paper"), load_space("isu-diverse")
    for name, default in (("driver_hands", "WHEEL"), ("phone_screen", "BY_USE")):
        assert name in diverse.names and name not in paper.names and not diverse.features[name].predicted
        assert DEFAULTS[name] == default and default in diverse.features[name].values


@pytest.mark.blender
def test_a_free_hand_moves_the_arm_and_the_screen_is_dark_at_the_ear_and_lit_when_read(tmp_path):
    import cv2

    from isu_validate.render import open_renderer
    from isu_validate.render.labels import INSTANCE_ID
    variants = {"wheel": {}, "lap": {"driver_hands": "LAP"},
                "read_by_use": {"phone_position": "P5"}, "read_off": {"phone_position": "P5", "phone_screen": "OFF"},
                "ear_by_use": {"phone_position": "P1"}, "ear_on": {"phone_position": "P1", "phone_screen": "ON"}}
    frames = {}
    with open_renderer("draft", space="isu-diverse", channels=("seg",), log_dir=tmp_path / "logs") as r:
        for name, change in variants.items():
            result = r.render({**BASE, **change}, tmp_path / f"{name}.png")
            frames[name] = (cv2.imread(str(result.image)).astype(int),
                            cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED))
    driver, phone = INSTANCE_ID["driver"], INSTANCE_ID["phone"]
    (wheel, wheel_seg), (lap, lap_seg) = frames["wheel"], frames["lap"]
    moved = (np.abs(lap - wheel).max(axis=2) > 24) & ((wheel_seg == driver) | (lap_seg == driver))
    assert moved.sum() >= 100, f"the right hand on the lap changed only {moved.sum()} driver pixels"
    # texting on the lap: the camera sees the screen, lit by default and black glass when OFF
    (lit, seg), (dark, _) = frames["read_by_use"], frames["read_off"]
    screen = seg == phone
    assert screen.sum() >= 20
    assert lit[screen].mean() > dark[screen].mean() + 15, (lit[screen].mean(), dark[screen].mean())
    # at the ear BY_USE is dark: never brighter on the phone than a screen forced on
    (ear, ear_seg), (ear_on, _) = frames["ear_by_use"], frames["ear_on"]
    at_ear = ear_seg == phone
    if at_ear.any():
        assert ear[at_ear].mean() <= ear_on[at_ear].mean() + 1
