"""Warnings when the data cannot support the model: what reprojection RMS alone hides."""
from __future__ import annotations

import cv2
import numpy as np

from .board import Detection
from .solve import Solution

MIN_FRAMES = 10
MIN_TILT_DEG = 15.0       # below this every view is effectively fronto-parallel
MIN_PERSPECTIVE = 0.08    # the same, as depth variation across the board (10 deg already gives ~0.1)
EDGE_BAND = 0.12          # the outer 12% of the image on each side counts as "near the edge"
# The intrinsics count as determined when their 95% intervals are narrower than these, relative to the focal
# length (fx, fy) or to the image width/height (cx, cy): a 2% focal error already moves an image-corner point
# ~2% of the half-diagonal (~8 px at 640x480). Good calibrations reach ~0.1-0.3%; four phone views of one
# board reached 20-30% (OpenCV's tutorial photos).
DETERMINED_95 = 0.02
Z95 = 1.959964


def frame_tilts_deg(sol: Solution) -> np.ndarray:
    """Angle between each board's normal and the line of sight to its centre (solved poses)."""
    tilts = []
    for d, r, t in zip(sol.detections, sol.rvecs, sol.tvecs):
        R = cv2.Rodrigues(r)[0]
        centre = R @ d.board_points.mean(axis=0) + t
        cos = abs(R[:, 2] @ centre) / np.linalg.norm(centre)
        tilts.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return np.array(tilts)


def perspective_depth_range(d: Detection, image_size, fraction: float = 0.5) -> float:
    """Relative depth variation across the board from a homography fitted to the central corners.

    The third row of H = K [r1 r2 t] is (r13, r23, tz) whatever K is, so this needs no
    intrinsics: a fronto-parallel board gives 0.  Only corners near the image centre are
    used, where lens distortion (which a homography would read as perspective) is small.
    """
    w, h = image_size
    keep = np.linalg.norm(d.pixels - [(w - 1) / 2, (h - 1) / 2], axis=1) < fraction * np.hypot(w, h) / 2
    if keep.sum() < 8:
        return float("nan")
    H, _ = cv2.findHomography(d.board_points[keep, :2], d.pixels[keep], 0)
    if H is None:
        return float("nan")
    depth = d.board_points[keep, :2] @ H[2, :2] + H[2, 2]
    return float((depth.max() - depth.min()) / np.abs(depth).mean())


def fronto_parallel_warning(sol: Solution) -> str | None:
    advice = "tilt the board by 30-45 deg in several directions"
    tilts = frame_tilts_deg(sol)
    if sol.covariance is not None and tilts.max() < MIN_TILT_DEG:
        return (f"all views are fronto-parallel (largest board tilt {tilts.max():.1f} deg): focal length and "
                f"board distance are confounded; {advice}")
    # A poorly determined solve can bend its poses (fronto-parallel views fitted with eight
    # distortion terms came out "tilted" by 20-40 deg with a focal length of 97 px instead
    # of 520), so the images are asked too, through a test that needs no intrinsics.
    if sol.model == "fisheye":
        return None  # no central region is distortion-free enough for the homography test
    ranges = [perspective_depth_range(d, sol.image_size) for d in sol.detections]
    finite = [r for r in ranges if np.isfinite(r)]
    if finite and max(finite) < MIN_PERSPECTIVE:
        return (f"all views look fronto-parallel (depth varies by at most {100 * max(finite):.0f}% across any "
                f"board): focal length and board distance are confounded; {advice}")
    return None


def edge_coverage(sol: Solution) -> dict:
    """Which image margins (left, right, top, bottom) have inlier corners in them."""
    w, h = sol.image_size
    pts = np.concatenate([d.pixels[m] for d, m in zip(sol.detections, sol.inliers)])
    bx, by = EDGE_BAND * w, EDGE_BAND * h
    return {"left": bool(np.any(pts[:, 0] < bx)), "right": bool(np.any(pts[:, 0] > w - 1 - bx)),
            "top": bool(np.any(pts[:, 1] < by)), "bottom": bool(np.any(pts[:, 1] > h - 1 - by))}


def intrinsics_intervals(sol: Solution) -> dict:
    """fx, fy, cx, cy: value, standard deviation and 95% interval from the parameter covariance (None when the
    solve left them undetermined: an infinite interval)."""
    cov = sol.intrinsics_covariance
    out = {}
    for i, name in enumerate(("fx", "fy", "cx", "cy")):
        value = float(sol.intrinsics[i])
        sd = float(np.sqrt(max(cov[i, i], 0.0))) if cov is not None else float("inf")
        out[name] = {"value": value, "stdev": sd, "interval_95": [value - Z95 * sd, value + Z95 * sd]}
    return out


def undetermined_intrinsics(sol: Solution, intervals: dict) -> str | None:
    """Why the views do not determine the intrinsics themselves (parameters, not projections), with the
    95% intervals; None when they do."""
    w, h = sol.image_size
    scale = {"fx": intervals["fx"]["value"], "fy": intervals["fy"]["value"], "cx": w, "cy": h}
    loose = [k for k, v in intervals.items() if not Z95 * v["stdev"] <= DETERMINED_95 * abs(scale[k])]
    if not loose:
        return None
    shown = ", ".join(f"{k} {v['value']:.1f} (95%: {v['interval_95'][0]:.1f} to {v['interval_95'][1]:.1f})"
                      if np.isfinite(v["stdev"]) else f"{k} {v['value']:.1f} (undetermined)"
                      for k, v in intervals.items())
    return (f"the views do not determine the intrinsics: {shown}; the 95% interval of {', '.join(loose)} is "
            f"wider than +-{DETERMINED_95:.0%} (of the focal length for fx, fy; of the image width, height for cx, "
            f"cy). Add views ({MIN_FRAMES}+ recommended, 20-40 best), tilted by 30-45 deg in several "
            "directions and covering the image's corners")


def data_warnings(sol: Solution, uncertainty: dict | None = None, crossval: dict | None = None) -> list[str]:
    out = []
    n = len(sol.detections)
    if n < MIN_FRAMES:
        out.append(f"too few frames: {n} views with the board; use at least {MIN_FRAMES} (20-40 recommended), "
                   "tilted and spread over the whole image")
    fronto = fronto_parallel_warning(sol)
    if fronto:
        out.append(fronto)
    missing = [side for side, seen in edge_coverage(sol).items() if not seen]
    if missing:
        out.append(f"no corners near the {', '.join(missing)} image edge(s): the lens model is extrapolated "
                   "there; take views with the board reaching into every edge and corner")
    if sol.covariance is None:
        out.append("the solve leaves some parameters undetermined (" + "; ".join(sol.notes) + "): "
                   "the reported uncertainty is infinite; add tilted views or use a simpler lens model")
    total = sol.n_corners + sol.n_outliers
    if total and sol.n_outliers > 0.05 * total:
        out.append(f"{sol.n_outliers} of {total} corners ({100 * sol.n_outliers / total:.0f}%) were rejected as "
                   "outliers: check focus, motion blur and the board spec")
    if np.isfinite(sol.noise_px) and sol.noise_px > 1.0:
        out.append(f"observation noise {sol.noise_px:.2f} px is high: blur, rolling shutter or a lens model "
                   "that does not fit; a richer --model may help")
    if uncertainty and np.isfinite(uncertainty.get("corner", np.nan)) and uncertainty["corner"] > 1.0:
        out.append(f"projection uncertainty at the image corners is {uncertainty['corner']:.2f} px at "
                   f"{uncertainty['distance_m']:g} m: add views covering the corners")
    if crossval and uncertainty and np.isfinite(crossval.get("median", np.nan)):
        # Two independent half-calibrations should differ by about sqrt(2) x the uncertainty
        # of a half (itself ~sqrt(2) x that of the whole): far more means the model is wrong.
        expected = 2.0 * uncertainty.get("centre", 0.0)
        if crossval["median"] > max(4.0 * expected, 0.2):
            out.append(f"cross-validation diff {crossval['median']:.2f} px (median) is far above what the noise "
                       f"explains (~{expected:.2f} px): the lens model may not fit this lens; try a richer --model")
    return out
