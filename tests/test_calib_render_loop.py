"""Closing the loop: Blender renders a ChArUco board through a camera rig; detection and
calibration must recover the rig.  This proves renderer and calibrator agree on what a camera is
(pixel-centre convention, lens model, pose conventions)."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from capture import synthetic
from capture.board import BoardSpec, board_image
from capture.calibrate import calibrate, detect_images
from capture.projection_diff import projection_diff

pytestmark = [pytest.mark.blender, pytest.mark.slow]

BOARD = BoardSpec(7, 5, 0.050, 0.036, "DICT_4X4_50")  # coarse: markers stay readable at 400x300
RIG_INTRINSICS = dict(model="opencv8", fx=330.0, fy=328.0, cx=203.2, cy=148.7,
                      distortion=[-0.18, 0.04, 0.0006, -0.0004, 0.0, 0.0, 0.0, 0.0])
N_VIEWS = 20


def test_calibrating_rendered_boards_recovers_the_rig(tmp_path):
    render = pytest.importorskip("isu_validate.render")
    from capture.camera import camera_from_dict, load_camera
    rig = load_camera().to_dict()
    rig["image"] = {"width": 400, "height": 300}
    rig["intrinsics"].update(RIG_INTRINSICS)
    cam = camera_from_dict(rig, "loop rig")
    truth = synthetic.TrueCamera(cam.model, (cam.fx, cam.fy, cam.cx, cam.cy, *cam.distortion), cam.width, cam.height)

    px_per_m, margin_m = 2500.0, BOARD.square_m / 2
    texture = board_image(BOARD, px_per_m, int(round(margin_m * px_per_m)))
    tex_path = tmp_path / "board.png"
    cv2.imwrite(str(tex_path), cv2.cvtColor(texture, cv2.COLOR_GRAY2BGR))
    size_m = (texture.shape[1] / px_per_m, texture.shape[0] / px_per_m)

    rng = np.random.default_rng(7)
    poses = synthetic.random_poses(rng, N_VIEWS, truth, BOARD, distance_m=(0.35, 0.7), max_tilt_deg=45)
    preset = render.Preset("loop", 1.0, 2, False, "NONE", 1, 1, 0, 3.0, 1.0)
    renderer = render.open_renderer(preset, camera=cam, log_dir=tmp_path)
    paths = []
    try:
        for i, (rvec, tvec) in enumerate(poses):
            R_cam_board = cv2.Rodrigues(rvec)[0]
            R_cabin_board = cam.R @ R_cam_board
            board_origin = cam.t + cam.R @ tvec
            image_origin = board_origin - R_cabin_board @ np.array([margin_m, margin_m, 0.0])
            out = tmp_path / f"view_{i:02d}.png"
            render.render_board(tex_path, size_m, (R_cabin_board, image_origin), out, renderer=renderer)
            paths.append(out)
    finally:
        renderer.close()

    detections, skipped = detect_images(paths, BOARD)
    assert len(detections) >= 0.7 * N_VIEWS, skipped  # boards partly out of view may show too few corners
    res = calibrate(detections, "opencv8", board=BOARD, cross_validate=False)
    sol = res.solution
    # Judged as mrcal would: the truth within the reported uncertainty, and the projections agreeing.
    assert sol.covariance is not None, sol.notes
    sd = np.sqrt(np.diag(sol.intrinsics_covariance))[:4]
    err = np.abs(sol.intrinsics[:4] - truth.intrinsics[:4])
    dmap = projection_diff("opencv8", sol.intrinsics, truth.model, truth.intrinsics, truth.size)
    # Compare where the data says something (mrcal's "valid intrinsics region"): grid points
    # with an observed corner within one grid step; beyond that the lens model extrapolates.
    seen = np.concatenate([d.pixels for d in sol.detections])
    gu, gv = np.meshgrid(dmap.us, dmap.vs)
    step = dmap.us[1] - dmap.us[0]
    near = np.array([np.min(np.hypot(*(seen - p).T)) < step for p in np.column_stack([gu.ravel(), gv.ravel()])])
    inside = dmap.diff_px.ravel()[near]
    diff = {"median": float(np.median(inside)), "max": float(inside.max()), "coverage": float(near.mean())}
    print("loop:", sol.intrinsics[:4], "err", err, "sd", sd, "diff", diff, "rms", sol.rms_px())
    assert np.all(err < np.maximum(4 * sd, 1.0)), (err, sd)
    assert diff["median"] < 0.35, diff
    assert sol.rms_px() < 0.6
