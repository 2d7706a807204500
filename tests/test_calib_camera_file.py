"""The camera file contract: TOML round trip, the renderer loads it unchanged, JSON, mrcal export."""
from __future__ import annotations

import json

import numpy as np
import pytest

from capture import camera_file, lens, synthetic
from capture.camera_file import CameraFileError, CameraModel


def _camera(model="opencv8"):
    truth = {"opencv8": synthetic.DEFAULT_CAMERA, "fisheye": synthetic.FISHEYE_180}.get(model)
    intr = np.array(truth.intrinsics) if truth else np.array([500.0, 501.0, 319.0, 238.0])
    from isu_validate.render.camera import look_at_rotation
    R = look_at_rotation([0.6, 0.0, 1.13], [-0.55, 0.04, 0.40])
    return CameraModel("cabin-cam", model, 640, 480, intr, (0.6, 0.0, 1.13), tuple(map(tuple, R)), True,
                       quality={"rms_px": 0.41, "uncertainty_px": {"centre": 0.05, "edge": 0.1, "corner": float("nan"),
                                                                   "distance_m": 1.0}, "warnings": ["a <b> & 'c'"]},
                       calibration={"board": "charuco:11x8:0.03:0.022:DICT_5X5_100", "images": ["a.png"]})


@pytest.mark.parametrize("model", ["pinhole", "opencv8", "fisheye"])
def test_toml_round_trip_and_the_renderer_projects_the_same_pixels(tmp_path, model):
    from isu_validate.render.camera import load_camera
    cam = _camera(model)
    path = camera_file.write_toml(cam, tmp_path / "cam.toml")
    back = camera_file.read_toml(path)
    assert np.array_equal(back.intrinsics, cam.intrinsics) and back.model == model
    assert back.quality["warnings"] == ["a <b> & 'c'"]
    rig = load_camera(path)  # the renderer's loader, unchanged
    pts_cabin = np.array([[-0.5, 0.3, 0.6], [-0.9, -0.2, 0.5], [0.0, 0.37, 0.9]])
    R = np.asarray(cam.rotation)
    pts_cam = (pts_cabin - cam.position) @ R
    assert np.allclose(rig.project(pts_cabin), lens.project(model, cam.intrinsics, pts_cam), atol=1e-6)


def test_json_is_the_same_content():
    cam = _camera()
    doc = json.loads(camera_file.to_json(cam))
    assert doc["intrinsics"]["fx"] == cam.intrinsics[0]
    assert doc["quality"]["uncertainty_px"]["corner"] == "nan"  # JSON has no NaN: written as a string


def test_mrcal_cameramodel_round_trip_keeps_the_pose(tmp_path):
    cam = _camera()
    path = camera_file.write_cameramodel(cam, tmp_path / "cam.cameramodel")
    text = path.read_text()
    assert "'lensmodel': 'LENSMODEL_OPENCV8'" in text and "'imagersize': [ 640, 480 ]" in text
    back = camera_file.read_cameramodel(path)
    assert np.allclose(back.intrinsics, cam.intrinsics)
    assert np.allclose(back.position, cam.position, atol=1e-12)
    assert np.allclose(np.asarray(back.rotation), np.asarray(cam.rotation), atol=1e-12)


def test_fisheye_cannot_go_to_mrcal_and_says_what_to_do(tmp_path):
    with pytest.raises(CameraFileError, match="--model opencv8"):
        camera_file.write_cameramodel(_camera("fisheye"), tmp_path / "f.cameramodel")


def test_bad_files_name_the_problem(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('name = "x"\n[image]\nwidth = 640\nheight = 480\n[intrinsics]\nmodel = "fisheye"\nfx = 1\nfy = 1\ncx = 1\n')
    with pytest.raises(CameraFileError, match="missing 'cy'"):
        camera_file.read_toml(p)
    p.write_text('[image]\nwidth = 640\nheight = 480\n[intrinsics]\nmodel = "fisheye"\nfx = 1\nfy = 1\ncx = 1\ncy = 1\n'
                 'distortion = [0.1]\n')
    with pytest.raises(CameraFileError, match="takes 4 distortion coefficients, got 1"):
        camera_file.read_toml(p)
    with pytest.raises(FileNotFoundError):
        camera_file.read_toml(tmp_path / "none.toml")
