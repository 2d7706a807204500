"""The alignment aid: does the captured frame show the render's scene from the render's camera?

Two numbers, both in pixels of the captured frame:

* edge distance: the median distance from each render edge to the nearest frame edge and back
  (symmetric chamfer on Canny edges). Small when the same outlines lie in the same places;
  robust to colour and exposure, which differ between render and photo anyway.
* shift: how far the render must move to match the frame, from ECC registration (Euclidean:
  shift and turn) on blurred gradient magnitudes, again so that brightness and colour do not
  matter; the mean displacement of the image corners. Unset when ECC does not converge.

The image written for the technician shows the frame with the render's edges on it, and a 50/50
ghost blend beside it, with the numbers and a verdict at the top.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from isu_validate.errors import UserError

ECC_WIDTH = 320          # ECC runs at this width (and the shift is scaled back): fast and less noise-driven
FLAT_GRADIENT = 24.0     # Sobel magnitude (0..255 images) below which a frame has no edges: a 6-level step
MIN_ECC = 0.5            # below this correlation a registration is a guess, not a measurement
GOOD_SHARE, CHECK_SHARE = 0.012, 0.035   # of the image diagonal: 9 px and 28 px at 640x480


class AlignmentError(UserError, ValueError):
    """An image the aid cannot read; the message names the file."""


@dataclass
class Alignment:
    edge_distance_px: float | None
    shift_px: float | None
    ecc: float | None
    verdict: str                # "aligned", "check" or "off"
    message: str
    size: tuple[int, int]       # (width, height) of the frame the pixels refer to

    def to_json(self) -> dict:
        return {k: (round(v, 3) if isinstance(v, float) else v) for k, v in asdict(self).items()}

    def line(self) -> str:
        def px(v):
            return "-" if v is None else f"{v:.1f} px"
        return (f"edge distance {px(self.edge_distance_px)}, shift {px(self.shift_px)}"
                + (f" (ECC {self.ecc:.2f})" if self.ecc is not None else "") + f": {self.verdict}. {self.message}")


def read_bgr(path: str | Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise AlignmentError(f"cannot read image {path}: missing, empty or not an image")
    return image


def align(render: np.ndarray, frame: np.ndarray) -> tuple[Alignment, np.ndarray]:
    """The alignment of ``render`` (any size, resized to the frame) with ``frame``, and the aid image."""
    frame = _bgr(frame)
    h, w = frame.shape[:2]
    notes = []
    rh, rw = render.shape[:2]
    if abs(rw / rh - w / h) > 0.02 * (w / h):
        notes.append(f"the render is {rw}x{rh} and the frame {w}x{h}: different shapes, the camera does not "
                     "match camera.toml")
    render = cv2.resize(_bgr(render), (w, h), interpolation=cv2.INTER_AREA if rw > w else cv2.INTER_LINEAR)
    edges_r, edges_f = _edges(render), _edges(frame)
    distance = _edge_distance(edges_r, edges_f)
    if distance is None:
        notes.append("no edges in " + ("the frame (black, flat or out of focus?)" if not edges_f.any()
                                       else "the render"))
    shift, ecc = _ecc_shift(render, frame)
    if shift is None and distance is not None:
        notes.append("registration did not converge: the views differ too much to measure a shift")
    elif ecc is not None and ecc < MIN_ECC:
        notes.append(f"registration unsure (ECC {ecc:.2f} < {MIN_ECC}): judged by the edge distance alone")
        shift = None
    diag = math.hypot(w, h)
    judged = shift if shift is not None else distance
    if judged is None:
        verdict = "off"
    else:
        verdict = "aligned" if judged <= GOOD_SHARE * diag else "check" if judged <= CHECK_SHARE * diag else "off"
    advice = {"aligned": "camera and scene match the render",
              "check": "close: check the camera mount and where things are before moving on",
              "off": "move the camera (or the scene) until the edges overlap"}[verdict]
    result = Alignment(distance, shift, ecc, verdict, "; ".join([advice] + notes), (w, h))
    return result, _aid_image(render, frame, edges_r, result)


# ---------------------------------------------------------------------- measures
def _bgr(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    if image.dtype != np.uint8:
        image = cv2.convertScaleAbs(image, alpha=255.0 / max(1.0, float(image.max())))
    return image[..., :3]


def _edges(image: np.ndarray) -> np.ndarray:
    """Canny on the strongest channel's gradient at each pixel: colour edges count, not only grey steps."""
    blurred = cv2.GaussianBlur(image, (5, 5), 1.2)
    gx = np.stack([cv2.Sobel(blurred[..., c], cv2.CV_16S, 1, 0) for c in range(3)])
    gy = np.stack([cv2.Sobel(blurred[..., c], cv2.CV_16S, 0, 1) for c in range(3)])
    magnitude = np.hypot(gx.astype(np.float32), gy.astype(np.float32))
    strongest = magnitude.argmax(axis=0)[None]
    dx, dy = (np.take_along_axis(g, strongest, 0)[0] for g in (gx, gy))
    peak = magnitude.max(axis=0)
    if float(peak.max()) < FLAT_GRADIENT:   # flat: nothing worth calling an edge
        return np.zeros(peak.shape, bool)
    # thresholds from the image's own gradient spread: a dark photo and a bright render get comparable edges
    high = max(float(np.percentile(peak, 97)), 0.2 * float(peak.max()))
    return cv2.Canny(np.ascontiguousarray(dx), np.ascontiguousarray(dy), 0.4 * high, high, L2gradient=True) > 0


def _edge_distance(a: np.ndarray, b: np.ndarray) -> float | None:
    if not a.any() or not b.any():
        return None
    to_b = cv2.distanceTransform((~b).astype(np.uint8), cv2.DIST_L2, 5)
    to_a = cv2.distanceTransform((~a).astype(np.uint8), cv2.DIST_L2, 5)
    return float((np.median(to_b[a]) + np.median(to_a[b])) / 2.0)


def _gradient(image: np.ndarray, scale: float) -> np.ndarray:
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(np.float32)
    grey = cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    mag = np.hypot(cv2.Sobel(grey, cv2.CV_32F, 1, 0), cv2.Sobel(grey, cv2.CV_32F, 0, 1))
    mag = cv2.GaussianBlur(mag, (0, 0), 2.0)
    return mag / max(1e-6, float(mag.max()))


def _ecc_shift(render: np.ndarray, frame: np.ndarray) -> tuple[float | None, float | None]:
    """Coarse to fine (a quarter of ECC_WIDTH, then ECC_WIDTH): the coarse level catches larger shifts."""
    h, w = frame.shape[:2]
    scale = min(1.0, ECC_WIDTH / w)
    warp = np.eye(2, 3, dtype=np.float32)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-6)
    ecc = None
    for level in (0.25, 1.0):
        template, moving = _gradient(frame, scale * level), _gradient(render, scale * level)
        if min(template.shape) < 16:
            continue
        try:
            ecc, warp = cv2.findTransformECC(template, moving, warp, cv2.MOTION_EUCLIDEAN, criteria, None, 5)
        except cv2.error:
            return None, None
        if level < 1.0:
            warp[:, 2] /= level   # the translation grows with the image; the rotation does not
    if ecc is None:
        return None, None
    sh, sw = template.shape
    corners = np.array([[0, 0, 1], [sw - 1, 0, 1], [0, sh - 1, 1], [sw - 1, sh - 1, 1]], np.float64)
    moved = corners @ warp.astype(np.float64).T
    shift = float(np.mean(np.linalg.norm(moved - corners[:, :2], axis=1))) / scale
    return shift, float(ecc)


# ---------------------------------------------------------------------- the image
COLOURS = {"aligned": (80, 200, 60), "check": (0, 190, 255), "off": (60, 60, 230)}


def _aid_image(render: np.ndarray, frame: np.ndarray, edges_r: np.ndarray, result: Alignment) -> np.ndarray:
    edges = frame.copy()
    thick = cv2.dilate(edges_r.astype(np.uint8), np.ones((2, 2), np.uint8)) > 0
    edges[thick] = (255, 255, 0)                       # render outlines in cyan over the photo
    ghost = cv2.addWeighted(frame, 0.5, render, 0.5, 0.0)
    panels = np.hstack([edges, ghost])
    bar = np.full((28, panels.shape[1], 3), 30, np.uint8)
    text = (f"{result.verdict.upper()}  edges {_fmt(result.edge_distance_px)}  shift {_fmt(result.shift_px)}"
            "  | left: render edges, right: ghost")
    scale = min(0.5, 0.95 * panels.shape[1] / (cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 1.0, 1)[0][0] + 16))
    cv2.putText(bar, text, (8, 19), cv2.FONT_HERSHEY_SIMPLEX, scale, COLOURS[result.verdict], 1, cv2.LINE_AA)
    return np.vstack([bar, panels])


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}px"
