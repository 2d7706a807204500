"""Cabin registration: ArUco markers at known cabin positions give the camera's pose."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from capture import synthetic
from capture.camera import Camera, look_at_rotation, read_toml, write_toml
from capture.registration import RegistrationError, load_markers, register
from isu_validate.cli import main

CAM = synthetic.TrueCamera("opencv8", (480.0, 480.0, 321.0, 238.5, -0.12, 0.03, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), 640, 480)
POSITION = np.array([0.6, 0.0, 1.13])
R_CABIN_CAM = look_at_rotation(POSITION, [-0.55, 0.04, 0.40])
PX_PER_M = 2000.0
MARKERS = {3: (0.025, 0.05), 7: (0.375, 0.05)}  # top-left corners on the plaque, metres
SIZE_M = 0.1


def _plaque():
    """A 0.5 x 0.2 m white plaque with two DICT_4X4_50 markers, and its pose in the cabin."""
    tex = np.full((int(0.2 * PX_PER_M), int(0.5 * PX_PER_M)), 255, np.uint8)
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    side = int(SIZE_M * PX_PER_M)
    for marker_id, (x, y) in MARKERS.items():
        c, r = int(x * PX_PER_M), int(y * PX_PER_M)
        tex[r:r + side, c:c + side] = cv2.aruco.generateImageMarker(dictionary, marker_id, side)
    R_tilt = cv2.Rodrigues(np.array([np.radians(25), np.radians(-15), 0.0]))[0]
    R_cabin_plaque = R_CABIN_CAM @ R_tilt
    origin = POSITION + R_CABIN_CAM @ np.array([-0.25, -0.05, 0.75])
    return tex, R_cabin_plaque, origin


def _scene(tmp_path):
    tex, R_cp, origin = _plaque()
    R_cam_plaque = R_CABIN_CAM.T @ R_cp
    t = R_CABIN_CAM.T @ (origin - POSITION)
    image = synthetic.render_plane(tex, PX_PER_M, (0, 0), CAM, cv2.Rodrigues(R_cam_plaque)[0], t, background=120)
    lines = ['dictionary = "DICT_4X4_50"']
    for marker_id, (x, y) in MARKERS.items():
        local = np.array([[x, y, 0], [x + SIZE_M, y, 0], [x + SIZE_M, y + SIZE_M, 0], [x, y + SIZE_M, 0]])
        cabin = local @ R_cp.T + origin
        lines += ["[[markers]]", f"id = {marker_id}", f"corners = {[[round(float(v), 6) for v in p] for p in cabin]}"]
    markers = tmp_path / "markers.toml"
    markers.write_text("\n".join(lines) + "\n")
    camera = Camera("cam", CAM.model, CAM.width, CAM.height, np.array(CAM.intrinsics))
    return image, markers, camera


def test_two_markers_give_the_camera_pose(tmp_path):
    image, markers, camera = _scene(tmp_path)
    dictionary, table = load_markers(markers)
    cam = register(camera, image, dictionary, table, "reg.png")
    assert cam.registered and cam.registration["markers"] == [3, 7]
    assert np.linalg.norm(np.asarray(cam.position) - POSITION) < 0.01
    dR = np.asarray(cam.rotation).T @ R_CABIN_CAM
    assert np.degrees(np.arccos(np.clip((np.trace(dR) - 1) / 2, -1, 1))) < 0.5
    assert cam.registration["rms_px"] < 0.5


def test_register_command_writes_the_pose_into_the_camera_file(tmp_path):
    image, markers, camera = _scene(tmp_path)
    cv2.imwrite(str(tmp_path / "reg.png"), image)
    write_toml(camera, tmp_path / "cam.toml")
    assert main(["calibrate", "register", str(tmp_path / "cam.toml"), str(tmp_path / "reg.png"),
                 "--markers", str(markers), "--out", str(tmp_path / "reg.toml")]) == 0
    assert np.linalg.norm(np.asarray(read_toml(tmp_path / "reg.toml").position) - POSITION) < 0.01


def test_markers_not_in_view_or_badly_listed_are_clear_errors(tmp_path):
    image, markers, camera = _scene(tmp_path)
    dictionary, table = load_markers(markers)
    with pytest.raises(RegistrationError, match=r"none of the listed markers \(\[11\]\) was found.*found \[3, 7\]"):
        register(camera, image, dictionary, {11: table[3]})
    with pytest.raises(RegistrationError, match="different|same resolution"):
        register(camera, cv2.resize(image, (320, 240)), dictionary, table)
    bad = tmp_path / "bad.toml"
    bad.write_text('[[markers]]\nid = 1\ncorners = [[0, 0, 0]]\n')
    with pytest.raises(RegistrationError, match="four"):
        load_markers(bad)


def test_the_shipped_example_marker_file_registers_the_default_camera(tmp_path):
    """rigs/markers/example.toml, photographed through the default rig (markers drawn at their listed
    corners), gives back the default rig's pose through `calibrate register --markers example`."""
    from isu_validate.paths import rigs_dir
    from capture.camera import load_camera

    rig = load_camera("default")
    assert rig.model == "pinhole"
    truth = synthetic.TrueCamera("pinhole", (rig.fx, rig.fy, rig.cx, rig.cy), rig.width, rig.height)
    R_cabin_cam, position = np.asarray(rig.rotation), np.asarray(rig.position)
    dictionary, table = load_markers(rigs_dir() / "markers" / "example.toml")
    assert len(table) >= 2
    aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    photo = np.full((truth.height, truth.width), 120, np.uint8)
    for marker_id, corners in table.items():
        side = np.linalg.norm(corners[1] - corners[0])
        px_per_m = 2000.0
        n = int(round(side * px_per_m))
        tex = np.full((2 * n, 2 * n), 255, np.uint8)           # the marker with a white margin
        tex[n // 2:n // 2 + n, n // 2:n // 2 + n] = cv2.aruco.generateImageMarker(aruco, marker_id, n)
        x = (corners[1] - corners[0]) / side                    # along the printed rows
        y = (corners[3] - corners[0]) / np.linalg.norm(corners[3] - corners[0])
        R_cam_plane = R_cabin_cam.T @ np.column_stack([x, y, np.cross(x, y)])
        t = R_cabin_cam.T @ (corners[0] - position)
        views = [synthetic.render_plane(tex, px_per_m, (n // 2, n // 2), truth, cv2.Rodrigues(R_cam_plane)[0], t,
                                        background=b) for b in (0, 255)]
        hit = np.abs(views[0].astype(int) - views[1].astype(int)) < 128   # where the plane is, not the background
        photo[hit] = views[0][hit]
    cv2.imwrite(str(tmp_path / "photo.png"), photo)
    camera = Camera("cam", "pinhole", truth.width, truth.height, np.array(truth.intrinsics, dtype=float))
    write_toml(camera, tmp_path / "cam.toml")
    assert main(["calibrate", "register", str(tmp_path / "cam.toml"), str(tmp_path / "photo.png"),
                 "--markers", "example", "--out", str(tmp_path / "reg.toml")]) == 0
    registered = read_toml(tmp_path / "reg.toml")
    assert registered.registration["markers"] == sorted(table)              # every marker seen
    assert np.linalg.norm(np.asarray(registered.position) - position) < 0.02  # within 2 cm (mm-rounded corners)
    dR = np.asarray(registered.rotation).T @ R_cabin_cam
    assert np.degrees(np.arccos(np.clip((np.trace(dR) - 1) / 2, -1, 1))) < 1.0
