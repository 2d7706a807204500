"""Projection uncertainty and cross-validation: checked against Monte Carlo re-calibrations."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from capture import lens, synthetic, uncertainty
from capture.board import BoardSpec
from capture.projection_diff import projection_diff
from capture.solve import solve

BOARD = BoardSpec(14, 10, 0.030, 0.022, "DICT_5X5_100")
CAM = synthetic.TrueCamera("pinhole", (520.0, 518.0, 322.5, 241.0), 640, 480)
PIXELS = np.array([[319.5, 239.5], [319.5, 0.0], [639.0, 479.0]])


def _mean_frames_point(poses_true, sol, v):
    """Where a re-calibration puts the world point that the truth sees at v (mrcal's mean-frames tie)."""
    acc = np.zeros_like(v)
    for (r0, t0), r1, t1 in zip(poses_true, sol.rvecs, sol.tvecs):
        b = (v - t0) @ cv2.Rodrigues(np.asarray(r0, float))[0]
        acc += b @ cv2.Rodrigues(r1)[0].T + t1
    return acc / len(poses_true)


def test_predicted_uncertainty_matches_monte_carlo():
    rng = np.random.default_rng(0)
    poses = synthetic.random_poses(rng, 12, CAM, BOARD, distance_m=(0.25, 0.6), max_tilt_deg=60)
    noise = 0.5
    sol = solve("pinhole", synthetic.observe(BOARD, CAM, poses, noise, rng), CAM.size)
    predicted = uncertainty.projection_stdev(sol, PIXELS, 1.0)
    v = lens.unproject(CAM.model, CAM.intrinsics, PIXELS)
    qs = []
    for k in range(40):
        dets = synthetic.observe(BOARD, CAM, poses, noise, np.random.default_rng(100 + k))
        s = solve("pinhole", dets, CAM.size, start=(sol.intrinsics, sol.rvecs, sol.tvecs))
        qs.append(lens.project("pinhole", s.intrinsics, _mean_frames_point(poses, s, v)))
    qs = np.array(qs)
    observed = [np.sqrt(np.linalg.eigvalsh(np.cov(qs[:, i].T))[-1]) for i in range(len(PIXELS))]
    assert np.all(predicted > 0)
    assert np.allclose(predicted, observed, rtol=0.45), (predicted, observed)
    # and the corner, far from the data, is the least certain
    assert predicted[2] > predicted[0]


def test_uncertainty_scales_with_the_noise():
    rng = np.random.default_rng(1)
    poses = synthetic.random_poses(rng, 10, CAM, BOARD, distance_m=(0.25, 0.6), max_tilt_deg=60)
    low = solve("pinhole", synthetic.observe(BOARD, CAM, poses, 0.2, np.random.default_rng(5)), CAM.size)
    high = solve("pinhole", synthetic.observe(BOARD, CAM, poses, 1.0, np.random.default_rng(5)), CAM.size)
    ratio = uncertainty.summary(high, 1.0)["centre"] / uncertainty.summary(low, 1.0)["centre"]
    assert ratio == pytest.approx(5.0, rel=0.15)


def test_projection_diff_of_a_camera_with_itself_is_zero_and_sees_a_focal_change():
    intr = np.array(synthetic.DEFAULT_CAMERA.intrinsics)
    same = projection_diff("opencv8", intr, "opencv8", intr, (640, 480)).stats()
    assert same["max"] < 1e-6
    longer = intr.copy()
    longer[:2] *= 1.01  # 1% longer focal length: ~3 px at the image edge, nothing a rotation can absorb
    d = projection_diff("opencv8", intr, "opencv8", longer, (640, 480))
    assert 1.0 < d.stats()["max"] < 6.0
    assert d.diff_px[12, 16] < 0.2  # the centre barely moves


def test_a_shifted_principal_point_is_mostly_a_rotation():
    intr = np.array(CAM.intrinsics)
    shifted = intr + [0, 0, 2.0, 0]
    fitted = projection_diff("pinhole", intr, "pinhole", shifted, CAM.size).stats()
    raw = projection_diff("pinhole", intr, "pinhole", shifted, CAM.size, fit=False).stats()
    assert raw["median"] == pytest.approx(2.0, abs=1e-6)
    assert fitted["median"] < 0.15 * raw["median"]  # what is left is second order in the field angle


def test_at_a_working_distance_a_focal_change_is_partly_a_shift():
    # At one distance, moving the camera along its axis mimics a longer lens (the focal
    # length / distance confound): the fitted diff there is far smaller than at infinity.
    intr = np.array(CAM.intrinsics)
    longer = intr * [1.002, 1.002, 1, 1]
    at_inf = projection_diff("pinhole", intr, "pinhole", longer, CAM.size).stats()["median"]
    at_1m = projection_diff("pinhole", intr, "pinhole", longer, CAM.size, distance_m=1.0).stats()["median"]
    assert at_inf > 0.2 and at_1m < 0.1 * at_inf
