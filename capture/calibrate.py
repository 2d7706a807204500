"""Calibration from images to camera file: detect, solve, judge (uncertainty, cross-validation, warnings)."""
from __future__ import annotations

import datetime as _dt
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from isu_validate.errors import InputError, InputNotFound

from . import checks, uncertainty
from .board import BoardSpec, Detection, detect
from .camera import Camera
from .projection_diff import DiffMap, projection_diff
from .solve import MIN_CORNERS_PER_FRAME, CalibrationError, Solution, solve

MIN_FRAMES_PER_HALF = 3


@dataclass
class CalibrationResult:
    camera: Camera
    solution: Solution
    uncertainty_map: uncertainty.UncertaintyMap
    crossval: DiffMap | None
    halves: tuple[Solution, Solution] | None
    skipped: list[tuple[str, str]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    undetermined: str | None = None      # why the views do not determine the intrinsics (None: they do)


def detect_images(paths, spec: BoardSpec, progress=None) -> tuple[list[Detection], list[tuple[str, str]]]:
    """Board corners in every image; images without enough corners are skipped with a reason.

    Refuses a set whose images differ in size: one calibration describes one sensor mode.
    Images are read one at a time (a set of 4K frames does not fit in memory at once).
    """
    paths = [str(p) for p in paths]
    detections, skipped = [], []
    sizes = defaultdict(list)
    for i, p in enumerate(paths):
        img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        if img is None:
            if not Path(p).exists():
                raise InputNotFound(f"image {p} does not exist")
            skipped.append((p, "not a readable image"))
            continue
        sizes[(img.shape[1], img.shape[0])].append(p)
        det = detect(spec, img, p)
        if len(det) < MIN_CORNERS_PER_FRAME:
            skipped.append((p, f"{len(det)} board corners found (need {MIN_CORNERS_PER_FRAME})"))
        else:
            detections.append(det)
        if progress:
            progress(i + 1, len(paths), p, len(det))
    check_one_size(sizes)
    return detections, skipped


def check_one_size(sizes: dict) -> None:
    if len(sizes) > 1:
        listing = "; ".join(f"{w}x{h}: {len(ps)} image(s), e.g. {ps[0]}" for (w, h), ps in sizes.items())
        raise InputError(f"the images have different sizes ({listing}); calibrate each resolution separately "
                         "(a camera model describes one sensor mode)")


def calibrate(detections: list[Detection], model: str, *, board: BoardSpec | None = None, name: str = "camera",
              working_distance_m: float = 1.0, skipped=(), cross_validate: bool = True,
              outlier_sigma: float = 4.0) -> CalibrationResult:
    if not detections:
        raise CalibrationError("no image shows the board; check the board spec (squares, dictionary) "
                               "matches the printed board")
    sizes = defaultdict(list)
    for d in detections:
        sizes[d.image_size].append(d.source)
    check_one_size(sizes)
    size = detections[0].image_size
    t0 = time.perf_counter()
    sol = solve(model, detections, size, outlier_sigma=outlier_sigma)
    t_solve = time.perf_counter() - t0
    umap = uncertainty.uncertainty_map(sol, working_distance_m)
    usum = uncertainty.summary(sol, working_distance_m)
    t_unc = time.perf_counter() - t0 - t_solve
    crossval, halves = _cross_validate(sol, outlier_sigma, working_distance_m) if cross_validate else (None, None)
    t_cv = time.perf_counter() - t0 - t_solve - t_unc
    cv_stats = crossval.stats() if crossval else None
    warnings = checks.data_warnings(sol, usum, cv_stats)
    intervals = checks.intrinsics_intervals(sol)
    undetermined = checks.undetermined_intrinsics(sol, intervals)
    if undetermined:
        warnings.insert(0, undetermined)
    if cross_validate and crossval is None:
        warnings.append(f"cross-validation skipped: it needs at least {2 * MIN_FRAMES_PER_HALF} frames")
    timings = {"solve_s": t_solve, "uncertainty_s": t_unc, "cross_validation_s": t_cv}
    camera = _camera(name, sol, usum, cv_stats, warnings, board, skipped, working_distance_m, outlier_sigma)
    camera.quality["intrinsics_95"] = {k: v["interval_95"] for k, v in intervals.items()}
    camera.quality["intrinsics_determined"] = undetermined is None
    return CalibrationResult(camera, sol, umap, crossval, halves, list(skipped), warnings, timings, undetermined)


def _cross_validate(sol: Solution, outlier_sigma: float, distance_m: float):
    """Calibrate the even and the odd frames separately and difference their projections at
    the working distance, where the projection uncertainty is reported too."""
    n = len(sol.detections)
    if n < 2 * MIN_FRAMES_PER_HALF:
        return None, None
    halves = []
    for idx in (np.arange(0, n, 2), np.arange(1, n, 2)):
        dets = [sol.detections[i] for i in idx]
        # Starting from the full solution only saves iterations: a converged least-squares
        # fit does not depend on where it started, so the halves stay independent.
        start = (sol.intrinsics, sol.rvecs[idx], sol.tvecs[idx])
        halves.append(solve(sol.model, dets, sol.image_size, outlier_sigma=outlier_sigma, start=start))
    a, b = halves
    return projection_diff(a.model, a.intrinsics, b.model, b.intrinsics, sol.image_size, distance_m=distance_m), (a, b)


def _camera(name, sol, usum, cv_stats, warnings, board, skipped, distance, outlier_sigma) -> Camera:
    from importlib.metadata import PackageNotFoundError, version
    try:
        tool = f"isu-validate {version('isu-validate')}"
    except PackageNotFoundError:
        tool = "isu-validate"
    residuals = sol.residuals()
    quality = {
        "rms_px": sol.rms_px(),          # sqrt(mean |residual|^2) over inlier corners, as OpenCV reports it
        "noise_px": sol.noise_px,        # per-axis observation noise (mrcal's "RMS" is this one)
        "frames": len(sol.detections), "corners": sol.n_corners, "outliers": sol.n_outliers,
        "uncertainty_px": usum,
        "cross_validation_diff_px": cv_stats or {},
        "warnings": warnings,
    }
    calibration = {
        "board": str(board) if board else "",
        "model": sol.model,
        "images": [d.source for d in sol.detections],
        "frame_rms_px": [float(np.sqrt(np.mean(np.sum(r[m] ** 2, axis=1)))) if m.any() else float("nan")
                         for r, m in zip(residuals, sol.inliers)],
        "skipped": [{"image": p, "reason": why} for p, why in skipped],
        "outlier_sigma": outlier_sigma,
        "working_distance_m": distance,
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "tool": tool,
    }
    return Camera(name, sol.model, sol.image_size[0], sol.image_size[1], sol.intrinsics,
                  quality=quality, calibration=calibration)
