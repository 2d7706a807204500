"""The renderer's own use of a camera's imaging model (``--camera``), with real Blender at the draft preset:
the linear render is developed the way the camera would, the light features reach the image through its
auto-exposure, and ``exposure apply`` on the saved linear EXR gives the renderer's own frame."""
from __future__ import annotations

import json
from dataclasses import replace

import cv2
import numpy as np
import pytest

from capture.camera_model.develop import develop_file
from capture.camera import load_camera
from isu_validate.render import open_renderer

pytestmark = pytest.mark.blender



def _scene(light: str) -> dict:
    """A valid scene of the shipped space (whatever its features are called) under ``light``."""
    from isu_validate.space import load_space
    scene = load_space("isu-paper").sample(np.random.default_rng(4), 1)[0]
    return {**scene, "external_light": light, "car_lights": "OFF"}


@pytest.fixture(scope="module")
def ae_rig():
    rig = load_camera("in-cabin-ae")
    return replace(rig, imaging=rig.imaging.with_part(noise=None))    # noise-free: frames compare exactly


@pytest.fixture(scope="module")
def frames(ae_rig, tmp_path_factory):
    """LOW and HIGH external light, rendered plainly and through the camera."""
    root = tmp_path_factory.mktemp("exposure-render")
    out = {}
    plain = replace(load_camera("default"), imaging=None)   # the default rig auto-exposes: take its model off
    for name, camera in (("plain", plain), ("camera", ae_rig)):
        with open_renderer("draft", camera=camera, channels=("exr",), cache_dir=root / "cache",
                           log_dir=root / "logs") as r:
            for light in ("LOW", "HIGH"):
                result = r.render(_scene(light), root / name / f"{light}.png")
                out[name, light] = result
            out[name, "cached"] = r.render(_scene("HIGH"), root / name / "again.png")
    return out


def _label(result) -> dict:
    return json.loads(result.channels["label"].read_text())


def _mean(result) -> float:
    return float(cv2.imread(str(result.image)).mean())


def test_a_camera_without_a_model_renders_as_before(frames):
    assert "imaging" not in _label(frames["plain", "HIGH"])


def test_the_light_features_reach_the_image_through_the_cameras_auto_exposure(frames):
    plain = _mean(frames["plain", "HIGH"]) - _mean(frames["plain", "LOW"])
    camera = _mean(frames["camera", "HIGH"]) - _mean(frames["camera", "LOW"])
    assert plain > 60                       # a renderer alone shows the night as night
    assert 0 < camera < plain / 2           # the camera gains it up, until its limits
    low, high = (_label(frames["camera", k])["imaging"]["exposure"] for k in ("LOW", "HIGH"))
    # the night takes the longest exposure and all the gain (whether that just reaches the target depends on
    # how much the scene reflects: this one's white T-shirt meters 0.416, within the tolerance of 0.42)
    assert low["exposure_us"] == 16600.0 and low["gain"] == 16.0 and low["at_limit"] in ("max", None)
    assert high["at_limit"] is None and high["metered"] == pytest.approx(0.42, abs=0.005)
    assert high["exposure_us"] < low["exposure_us"]


def test_exposure_apply_on_the_linear_render_gives_the_renderers_frame(frames, ae_rig, tmp_path):
    result = frames["camera", "HIGH"]
    row = develop_file(result.channels["exr"], ae_rig.imaging, tmp_path / "developed.png")
    assert np.array_equal(cv2.imread(str(tmp_path / "developed.png")), cv2.imread(str(result.image)))
    assert row["exposure"]["exposure_us"] == pytest.approx(_label(result)["imaging"]["exposure"]["exposure_us"],
                                                           rel=1e-4)


def test_a_cached_render_keeps_what_the_camera_chose(frames):
    cached = frames["camera", "cached"]
    assert cached.cached
    assert _label(cached)["imaging"] == _label(frames["camera", "HIGH"])["imaging"]


def test_a_virtual_chart_renders_where_the_real_one_stood(tmp_path):
    """A chart shown on a board 0.9 m in front of the default camera is the 'real' frame; `exposure chart`
    finds it, solves its pose and renders the virtual chart at the same place."""
    from capture.camera_model import chart, virtual_chart
    from isu_validate.srgb import srgb_encode_float
    from isu_validate.cli import main
    from isu_validate.render import render_board

    rig = load_camera("default")
    _, size = virtual_chart.board_layout(virtual_chart.DEFAULT_PITCH_M)
    texture = tmp_path / "chart.png"
    cv2.imwrite(str(texture), cv2.cvtColor((srgb_encode_float(chart.chart_image()) * 255 + 0.5).astype(np.uint8),
                                           cv2.COLOR_RGB2BGR))
    position = rig.R @ np.array([-size[0] / 2, -size[1] / 2, 0.9]) + rig.t
    render_board(texture, size, (rig.R, position), tmp_path / "real.png", camera=rig, preset="standard")
    assert main(["exposure", "chart", "--real", str(tmp_path / "real.png"), "--camera", "default",
                 "--out", str(tmp_path / "sim.png")]) == 0
    real, sim = (cv2.cvtColor(cv2.imread(str(tmp_path / n)), cv2.COLOR_BGR2RGB) for n in ("real.png", "sim.png"))
    centres = [chart.find(img).quads.mean(axis=1) for img in (real, sim)]
    # mcc places its patch model within ~6 px of the true centres; the pose inherits that
    assert np.abs(centres[0] - centres[1]).max() < 10
