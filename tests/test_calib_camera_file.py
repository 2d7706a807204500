"""The camera file contract: one reader for calibration and rendering, TOML round trip, JSON, mrcal export."""
from __future__ import annotations

import ast
import json

import cv2
import numpy as np
import pytest

from capture import camera as camera_file
from capture import lens, synthetic
from capture.camera import Camera, CameraFileError, camera_from_dict, look_at_rotation
from capture.mrcal_file import write_cameramodel


def _camera(model="opencv8"):
    truth = {"opencv8": synthetic.DEFAULT_CAMERA, "fisheye": synthetic.FISHEYE_180}.get(model)
    intr = np.array(truth.intrinsics) if truth else np.array([500.0, 501.0, 319.0, 238.0])
    R = look_at_rotation([0.6, 0.0, 1.13], [-0.55, 0.04, 0.40])
    return Camera("cabin-cam", model, 640, 480, intr, (0.6, 0.0, 1.13), tuple(map(tuple, R)), True,
                       quality={"rms_px": 0.41, "uncertainty_px": {"centre": 0.05, "edge": 0.1, "corner": float("nan"),
                                                                   "distance_m": 1.0}, "warnings": ["a <b> & 'c'"]},
                       calibration={"board": "charuco:11x8:0.03:0.022:DICT_5X5_100", "images": ["a.png"]})


@pytest.mark.parametrize("model", ["pinhole", "opencv8", "fisheye"])
def test_toml_round_trip_and_the_renderer_projects_the_same_pixels(tmp_path, model):
    from capture.camera import load_camera
    cam = _camera(model)
    path = camera_file.write_toml(cam, tmp_path / "cam.toml")
    back = camera_file.read_toml(path)
    assert np.array_equal(back.intrinsics, cam.intrinsics) and back.model == model
    assert back.quality["warnings"] == ["a <b> & 'c'"]
    rig = load_camera(path)  # the renderer's loader
    pts_cabin = np.array([[-0.5, 0.3, 0.6], [-0.9, -0.2, 0.5], [0.0, 0.37, 0.9]])
    R = np.asarray(cam.rotation)
    pts_cam = (pts_cabin - cam.position) @ R
    assert np.allclose(rig.project(pts_cabin), lens.project(model, cam.intrinsics, pts_cam), atol=1e-6)


def test_json_is_the_same_content():
    cam = _camera()
    doc = json.loads(camera_file.to_json(cam))
    assert doc["intrinsics"]["fx"] == cam.intrinsics[0]
    assert doc["quality"]["uncertainty_px"]["corner"] == "nan"  # JSON has no NaN: written as a string


def _mrcal(path) -> dict:
    """mrcal's .cameramodel is a Python dict literal after its comment lines."""
    return ast.literal_eval("\n".join(ln for ln in path.read_text().splitlines() if not ln.lstrip().startswith("#")))


def test_mrcal_cameramodel_keeps_the_lens_and_the_pose(tmp_path):
    cam = _camera()
    path = write_cameramodel(cam, tmp_path / "cam.cameramodel")
    text = path.read_text()
    assert "'lensmodel': 'LENSMODEL_OPENCV8'" in text and "'imagersize': [ 640, 480 ]" in text
    raw = _mrcal(path)
    assert np.allclose(raw["intrinsics"], cam.intrinsics)
    rt = np.asarray(raw["extrinsics"])              # rt_cam_ref: cabin -> camera
    R_cam_from_cabin = cv2.Rodrigues(rt[:3])[0]
    assert np.allclose(-R_cam_from_cabin.T @ rt[3:], cam.position, atol=1e-12)
    assert np.allclose(R_cam_from_cabin.T, np.asarray(cam.rotation), atol=1e-12)


def test_fisheye_cannot_go_to_mrcal_and_says_what_to_do(tmp_path):
    with pytest.raises(CameraFileError, match="--model opencv8"):
        write_cameramodel(_camera("fisheye"), tmp_path / "f.cameramodel")


def test_bad_files_name_the_problem(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('name = "x"\n[image]\nwidth = 640\nheight = 480\n'
                 '[intrinsics]\nmodel = "fisheye"\nfx = 1\nfy = 1\ncx = 1\n')
    with pytest.raises(CameraFileError, match="has no 'cy'"):
        camera_file.read_toml(p)
    p.write_text('[image]\nwidth = 640\nheight = 480\n[intrinsics]\nmodel = "fisheye"\nfx = 1\nfy = 1\ncx = 1\ncy = 1\n'
                 'distortion = [0.1]\n')
    with pytest.raises(CameraFileError, match="needs exactly 4 coefficients k1..k4, got 1"):
        camera_file.read_toml(p)
    with pytest.raises(FileNotFoundError):
        camera_file.read_toml(tmp_path / "none.toml")


# ---------------------------------------------------------------------- one file, one meaning
_LENS = {"model": "opencv8", "fx": 310.0, "fy": 305.0, "cx": 322.1, "cy": 241.3,
         "distortion": [-0.28, 0.07, 0.001, -0.002, 0.01]}       # five OpenCV coefficients, as written
_FILES = {
    "five coefficients, rotation, no `registered`":
        {"image": {"width": 640, "height": 480}, "intrinsics": _LENS,
         "extrinsics": {"position": [0.6, 0.0, 1.17],
                        "rotation": [list(r) for r in look_at_rotation([0.6, 0.0, 1.17], [-0.55, 0.12, 0.6])]}},
    "look_at": {"image": {"width": 640, "height": 480}, "intrinsics": _LENS,
                "extrinsics": {"position": [0.6, 0.0, 1.17], "look_at": [-0.55, 0.12, 0.6], "up": [0.0, 0.0, 1.0]}},
}


@pytest.mark.parametrize("name", sorted(_FILES))
def test_one_camera_file_means_the_same_to_calibrate_and_render(tmp_path, name):
    """Calibration (``calibrate diff``/``register`` read a path), rendering (``load_render_camera``) and the
    JSON round trip all read a file through the one reader and project a cabin point to the same pixel."""
    from capture.camera import load_render_camera, read_toml, write_toml
    from isu_validate.render.camera import pinhole_plan
    import tomli_w
    path = tmp_path / "cam.toml"
    path.write_text(tomli_w.dumps(_FILES[name]))
    calibrated, rendered = read_toml(path), load_render_camera(path)
    again = camera_from_dict(json.loads(camera_file.to_json(calibrated)), "json")
    written = read_toml(write_toml(calibrated, tmp_path / "again.toml"))
    assert calibrated.registered and rendered.registered          # [extrinsics] with a position: a meant pose
    assert calibrated.distortion == tuple(_LENS["distortion"])    # kept as written: five, not padded
    assert calibrated.hash == rendered.hash                        # the render cache key of this file
    points = np.array([[-0.5, 0.3, 0.6], [-0.9, -0.2, 0.5], [0.0, 0.37, 0.9], [2.0, 0.0, 1.0]])  # last: behind
    uv = rendered.project(points)
    assert np.isnan(uv[3]).all() and np.isfinite(uv[:3]).all()
    assert np.array_equal(calibrated.project(points), uv, equal_nan=True)
    for cam in (again, written):     # a rotation read back is re-orthonormalised: equal to rounding
        assert cam.distortion == calibrated.distortion
        assert np.allclose(cam.project(points), uv, atol=1e-9, equal_nan=True)
    # the camera-frame projection is the same lens: OpenCV's, padded or not
    in_cam = calibrated.to_camera(points[:3])
    assert np.allclose(calibrated.project_camera(in_cam), uv[:3], atol=1e-9)
    padded = lens.full_intrinsics("opencv8", calibrated.intrinsics)
    assert len(padded) == 12 and np.allclose(lens.project("opencv8", padded, in_cam), uv[:3], atol=1e-9)
    # the renderer's warp undoes the lens it projects with
    plan = pinhole_plan(rendered)
    u, v = (int(round(c)) for c in uv[0])
    ray = np.array([plan.map_x[v, u] - plan.cx, plan.map_y[v, u] - plan.cy]) / plan.f
    assert np.allclose(ray, calibrated.rays([[u, v]])[0], atol=1e-4)


def test_a_file_without_extrinsics_is_the_unregistered_placeholder(tmp_path):
    from capture.camera import FORWARD_ROTATION, load_render_camera, read_toml
    path = tmp_path / "bare.toml"
    path.write_text('[image]\nwidth = 64\nheight = 48\n[intrinsics]\nfx = 50\nfy = 50\ncx = 31.5\ncy = 23.5\n')
    cam = read_toml(path)
    assert not cam.registered and cam.position == (0.0, 0.0, 0.0) and cam.rotation == FORWARD_ROTATION
    with pytest.raises(CameraFileError, match="never registered"):
        load_render_camera(path)
    assert load_render_camera(path, extrinsics_from="default").registered
