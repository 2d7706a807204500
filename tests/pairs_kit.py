"""Small pairs directories for the RQ3 tests: samples with real and stand-in frames, and a SUT whose
answers per image are fixed, so every agreement figure is known by hand."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from tests.test_agree import SPACE, SUT, drawing, stand_in

TRUTH = {"driver_gender": "MALE", "seat_belt": "YES", "luggage": "NO"}
SCENE = {**TRUTH, "car_lights": "ON"}
WRONG = {"driver_gender": "FEMALE", "seat_belt": "NO", "luggage": "YES"}
CAMERA_SIDECAR = {"device": "v4l2:/dev/video0", "exposure_us": 8000, "iso": 400,
                  "timestamp": "2026-11-22T00:00:00+00:00"}
STAND_IN_SIDECAR = {"device": "stand-in render (not a camera)", "stand_in": True, "exposure_us": None,
                    "iso": None}


def space_file(tmp_path: Path) -> Path:
    path = tmp_path / "mini.toml"
    path.write_text(SPACE)
    return path


def make_sample(root: Path, name: str, frames: list[bool], seed: int = 0, scene: dict | None = None) -> Path:
    """A sample of the mini space with one frame per flag (True: a stand-in, False: a camera frame)."""
    d = root / name
    (d / "real").mkdir(parents=True)
    (d / "scene.json").write_text(json.dumps({"test_id": name, "space": "mini", "scene": scene or SCENE}))
    sim = drawing(seed)
    sim.save(d / "sim.png")
    for k, is_stand_in in enumerate(frames):
        frame = d / "real" / f"frame_{k:04d}.png"
        stand_in(sim, 10 * seed + k).save(frame)
        frame.with_suffix(".json").write_text(json.dumps(STAND_IN_SIDECAR if is_stand_in else CAMERA_SIDECAR))
    return d


def fixed_sut(tmp_path: Path, answers: dict) -> str:
    """A command SUT answering ``answers[<sample>/<file>]`` (see tests/test_agree.py's SUT)."""
    table, program = tmp_path / "answers.json", tmp_path / "sut.py"
    table.write_text(json.dumps(answers))
    program.write_text(SUT)
    return f"command:{sys.executable} {program} {table} {tmp_path / 'calls.log'}"
