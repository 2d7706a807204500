"""The calibration solve on synthetic observations with a known truth, including the hard cases."""
from __future__ import annotations

import numpy as np
import pytest

from capture import lens, synthetic
from capture.board import BoardSpec, Detection
from capture.calibrate import calibrate
from capture.projection_diff import projection_diff
from capture.solve import CalibrationError, solve

BOARD = BoardSpec(14, 10, 0.030, 0.022, "DICT_5X5_100")
PINHOLE = synthetic.TrueCamera("pinhole", (520.0, 518.0, 322.5, 241.0), 640, 480)


def data(camera, n, noise, seed, **pose_kw):
    rng = np.random.default_rng(seed)
    pose_kw.setdefault("distance_m", (0.25, 0.6))
    pose_kw.setdefault("max_tilt_deg", 60)
    poses = synthetic.random_poses(rng, n, camera, BOARD, **pose_kw)
    return poses, synthetic.observe(BOARD, camera, poses, noise, rng)


def truth_diff(sol, camera) -> float:
    return projection_diff(sol.model, sol.intrinsics, camera.model, camera.intrinsics, camera.size).stats()["median"]


def test_opencv8_recovers_the_truth_within_its_reported_uncertainty():
    cam = synthetic.DEFAULT_CAMERA
    _, dets = data(cam, 30, 0.3, seed=3)
    sol = solve("opencv8", dets, cam.size)
    sd = np.sqrt(np.diag(sol.intrinsics_covariance))[:4]
    err = np.abs(sol.intrinsics[:4] - cam.intrinsics[:4])
    assert np.all(err < 4 * sd), (err, sd)
    assert sol.noise_px == pytest.approx(0.3, rel=0.1)
    assert truth_diff(sol, cam) < 0.15


def test_noise_free_pinhole_is_exact():
    _, dets = data(PINHOLE, 8, 0.0, seed=1)
    sol = solve("pinhole", dets, PINHOLE.size)
    assert np.allclose(sol.intrinsics, PINHOLE.intrinsics, atol=1e-6)
    assert sol.n_outliers == 0


def test_strong_fisheye_beyond_90_degrees_off_axis():
    cam = synthetic.FISHEYE_180
    poses, dets = data(cam, 24, 0.3, seed=5, distance_m=(0.12, 0.35), max_off_axis_deg=88)
    angles = [np.degrees(np.arccos(lens.unproject(cam.model, cam.intrinsics, d.pixels)[:, 2])) for d in dets]
    assert max(a.max() for a in angles) > 80  # the data really reaches the edge of a 180-degree lens
    sol = solve("fisheye", dets, cam.size)
    assert np.abs(sol.intrinsics[:4] - cam.intrinsics[:4]).max() < 1.0
    assert truth_diff(sol, cam) < 0.2


def test_one_pixel_noise_is_estimated_and_the_truth_stays_inside_the_uncertainty():
    _, dets = data(PINHOLE, 20, 1.0, seed=7)
    sol = solve("pinhole", dets, PINHOLE.size)
    assert sol.noise_px == pytest.approx(1.0, rel=0.1)
    sd = np.sqrt(np.diag(sol.intrinsics_covariance))
    assert np.all(np.abs(sol.intrinsics - PINHOLE.intrinsics) < 4 * sd)


def test_five_frames_calibrate_but_warn():
    _, dets = data(PINHOLE, 5, 0.3, seed=11)
    res = calibrate(dets, "pinhole", board=BOARD)
    assert np.abs(res.solution.intrinsics - PINHOLE.intrinsics).max() < 5
    assert any("too few frames" in w for w in res.warnings)
    assert any("cross-validation skipped" in w for w in res.warnings)


def test_missing_corners_are_fine():
    rng = np.random.default_rng(2)
    _, dets = data(PINHOLE, 15, 0.3, seed=13)
    thinned = []
    for d in dets:
        keep = rng.random(len(d)) > 0.4
        thinned.append(Detection(d.source, d.image_size, d.ids[keep], d.pixels[keep], d.board_points[keep]))
    sol = solve("pinhole", thinned, PINHOLE.size)
    assert np.abs(sol.intrinsics - PINHOLE.intrinsics).max() < 1.5


def test_misdetected_corners_are_rejected_as_outliers():
    rng = np.random.default_rng(4)
    _, dets = data(synthetic.DEFAULT_CAMERA, 20, 0.3, seed=17)
    corrupted = []
    for d in dets:
        bad = rng.random(len(d)) < 0.03
        px = d.pixels.copy()
        px[bad] += rng.uniform(8, 30, size=(bad.sum(), 2)) * rng.choice([-1, 1], size=(bad.sum(), 2))
        corrupted.append((Detection(d.source, d.image_size, d.ids, px, d.board_points), bad))
    sol = solve("opencv8", [c[0] for c in corrupted], synthetic.DEFAULT_CAMERA.size)
    flagged = np.concatenate([~m for m in sol.inliers])
    truly_bad = np.concatenate([b for _, b in corrupted])
    assert truly_bad.sum() > 20
    assert np.array_equal(flagged, truly_bad)
    assert sol.noise_px == pytest.approx(0.3, rel=0.15)
    assert truth_diff(sol, synthetic.DEFAULT_CAMERA) < 0.2


def test_boards_partly_outside_the_image():
    rng = np.random.default_rng(8)
    # Close boards aimed at the image border: many views lose part of the board.
    poses = synthetic.random_poses(rng, 20, PINHOLE, BOARD, distance_m=(0.2, 0.35), max_tilt_deg=45)
    dets = synthetic.observe(BOARD, PINHOLE, poses, 0.3, rng)
    partial = sum(len(d) < len(BOARD.corners_m()) for d in dets)
    assert partial >= 10
    sol = solve("pinhole", dets, PINHOLE.size)
    assert np.abs(sol.intrinsics - PINHOLE.intrinsics).max() < 1.5


@pytest.mark.parametrize("camera", [PINHOLE, synthetic.DEFAULT_CAMERA], ids=["pinhole", "opencv8"])
def test_fronto_parallel_views_warn(camera):
    _, dets = data(camera, 12, 0.3, seed=19, max_tilt_deg=0.0, max_spin_deg=30)
    res = calibrate(dets, camera.model, board=BOARD, cross_validate=False)
    assert any("fronto-parallel" in w for w in res.warnings), res.warnings
    _, tilted = data(camera, 12, 0.3, seed=19, max_tilt_deg=45.0)
    res = calibrate(tilted, camera.model, board=BOARD, cross_validate=False)
    assert not any("fronto-parallel" in w for w in res.warnings), res.warnings


def test_an_undetermined_solve_reports_infinite_uncertainty_not_a_crash():
    # One view of a plane cannot fix four pinhole intrinsics (Zhang: two constraints per view).
    _, dets = data(PINHOLE, 1, 0.3, seed=23)
    res = calibrate(dets, "pinhole", board=BOARD)
    assert res.solution.covariance is None
    assert res.camera.quality["uncertainty_px"]["centre"] == np.inf
    assert any("undetermined" in w for w in res.warnings)


def test_two_fronto_parallel_views_with_eight_distortion_terms_warn_and_report_large_uncertainty():
    _, dets = data(synthetic.DEFAULT_CAMERA, 2, 0.3, seed=23, max_tilt_deg=0.0)
    res = calibrate(dets, "opencv8", board=BOARD)
    assert any("fronto-parallel" in w for w in res.warnings), res.warnings
    assert any("too few frames" in w for w in res.warnings)
    assert res.camera.quality["uncertainty_px"]["corner"] > 1.0


def test_mixed_image_sizes_are_refused():
    _, dets = data(PINHOLE, 4, 0.3, seed=29)
    other = dets[0]
    dets.append(Detection("small.png", (320, 240), other.ids, other.pixels / 2, other.board_points))
    with pytest.raises(ValueError,
                       match=r"different sizes \(640x480: 4 image\(s\).*320x240: 1 image\(s\), e.g. small.png"):
        calibrate(dets, "pinhole", board=BOARD)


def test_no_usable_frames_is_a_clear_error():
    with pytest.raises(CalibrationError, match="board spec"):
        calibrate([], "pinhole", board=BOARD)
    few = Detection("x.png", (640, 480), np.arange(3), np.zeros((3, 2)), np.zeros((3, 3)))
    with pytest.raises(CalibrationError, match="at least 6 board corners"):
        solve("pinhole", [few], (640, 480))


def test_corners_only_in_the_middle_warn_about_the_edges():
    _, dets = data(PINHOLE, 12, 0.3, seed=31, distance_m=(0.9, 1.2), max_off_axis_deg=8)
    res = calibrate(dets, "pinhole", board=BOARD, cross_validate=False)
    assert any("no corners near the left, right, top, bottom image edge(s)" in w for w in res.warnings), res.warnings
