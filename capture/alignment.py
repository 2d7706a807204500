"""The alignment aid: does the captured frame show the render's scene from the render's camera, and if
not, which way to turn the camera?

Measures, in pixels of the captured frame:

* edge distance: the median distance from each render edge to the nearest frame edge and back
  (symmetric chamfer on Canny edges). Small when the same outlines lie in the same places;
  robust to colour and exposure, which differ between render and photo anyway.
* registration: where the render's content lies in the frame, as a homography ``H`` (render pixel ->
  frame pixel). ECC first (Euclidean: shift and turn, on blurred gradient magnitudes, so brightness
  and colour do not matter); when ECC fails or is unsure, SIFT features matched between the two and a
  RANSAC homography. The shift is the mean displacement of the image corners; it is always reported,
  with "low confidence" when the registration's score is below ``MIN_SCORE``.
* what to do: a camera turned by a small angle moves the whole picture (a homography K R K^-1), so
  the render's centre found at frame pixel p says how far to pan (atan((p_x - c_x) / f_x)) and tilt
  (atan((p_y - c_y) / f_y)), and the turn of the content about it says the roll. The camera goes the
  way the content went: content further right than in the render -> turn the camera right.

The image written for the technician shows the frame with the render's edges and an arrow from the
frame's centre to where the render's centre lies, a 50/50 ghost blend beside it, and a banner with the
verdict, the advice in words and the numbers, sized to the image.
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
MIN_SCORE = 0.5          # below this ECC correlation or feature inlier share a registration is a guess
MIN_INLIERS = 12         # feature matches that agree on one homography before it counts at all
GOOD_SHARE, CHECK_SHARE = 0.012, 0.035   # of the image diagonal: 9 px and 28 px at 640x480
HOLD_DEG, HOLD_SCALE = 0.3, 0.05         # turns and size changes below these are not worth a word


class AlignmentError(UserError, ValueError):
    """An image the aid cannot read; the message names the file."""


@dataclass(frozen=True)
class Registration:
    H: np.ndarray            # 3x3, render pixel -> frame pixel (both at the frame's size)
    score: float             # ECC correlation, or the share of matched features that agree
    method: str              # "ECC" or "features"

    @property
    def confident(self) -> bool:
        return self.score >= MIN_SCORE


@dataclass(frozen=True)
class Turn:
    """How to move the camera so that the frame matches the render (degrees; see ``camera_turn``)."""
    pan_deg: float           # + turn right, - turn left
    tilt_deg: float          # + tilt down, - tilt up
    roll_deg: float          # + clockwise, - anticlockwise, seen from behind the camera
    scale: float             # content size in the frame / in the render: > 1 the camera is too close


@dataclass
class Alignment:
    edge_distance_px: float | None
    shift_px: float | None
    score: float | None         # of the registration (ECC correlation or feature inlier share)
    method: str | None          # "ECC", "features" or None (no registration)
    confident: bool             # score >= MIN_SCORE
    pan_deg: float | None       # the turn that would align the camera (None without intrinsics)
    tilt_deg: float | None
    roll_deg: float | None
    scale: float | None
    advice: str                 # what to do, in words ("turn 2.0° left, tilt 1.0° down")
    verdict: str                # "aligned", "check" or "off"
    message: str
    size: tuple[int, int]       # (width, height) of the frame the pixels refer to

    def to_json(self) -> dict:
        return {k: (round(v, 3) if isinstance(v, float) else v) for k, v in asdict(self).items()}

    def shift_text(self) -> str:
        if self.shift_px is None:
            return "shift not measured"
        how = f"{self.method} {self.score:.2f}"
        return f"shift {self.shift_px:.1f} px ({how if self.confident else 'low confidence: ' + how})"

    def line(self) -> str:
        edges = "-" if self.edge_distance_px is None else f"{self.edge_distance_px:.1f} px"
        return f"edge distance {edges}, {self.shift_text()}: {self.verdict}. {self.advice}. {self.message}"


def read_bgr(path: str | Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise AlignmentError(f"cannot read image {path}: missing, empty or not an image")
    return image


def align(render: np.ndarray, frame: np.ndarray, camera=None) -> tuple[Alignment, np.ndarray]:
    """The alignment of ``render`` (any size, resized to the frame) with ``frame``, and the aid image.
    ``camera`` (a ``capture.camera.Camera``, e.g. the pair's camera.toml) gives the focal length that
    turns pixels into degrees; without it the advice is in pixels."""
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
    reg = register(render, frame)
    if reg is None and distance is not None:
        notes.append("registration failed (ECC and features): the views differ too much to measure a shift")
    elif reg is not None and not reg.confident:
        notes.append(f"registration unsure ({reg.method} {reg.score:.2f} < {MIN_SCORE}): the shift and the advice "
                     "are a guess, the verdict goes by the edge distance")
    shift = corner_shift(reg.H, (w, h)) if reg is not None else None
    intrinsics = _intrinsics(camera, (w, h))
    turn = camera_turn(reg.H, *intrinsics) if reg is not None and intrinsics else None
    verdict = _verdict(reg, shift, distance, math.hypot(w, h))
    advice = (turn_words(turn) if turn else pixel_words(reg.H, (w, h)) if reg is not None
              else "no advice: move the camera until the edges overlap")
    plain = {"aligned": "camera and scene match the render",
             "check": "close: check the camera mount and where things are before moving on",
             "off": "move the camera (or the scene) until the edges overlap"}[verdict]
    result = Alignment(distance, shift, reg.score if reg else None, reg.method if reg else None,
                       bool(reg and reg.confident), *(_turn_fields(turn)), advice, verdict,
                       "; ".join([plain] + notes), (w, h))
    return result, _aid_image(render, frame, edges_r, result, reg)


# ---------------------------------------------------------------------- geometry (pure)
def camera_turn(H: np.ndarray, fx: float, fy: float, cx: float, cy: float) -> Turn:
    """The camera turn that moves the frame onto the render. ``H`` maps render pixels to frame pixels.

    The render's centre (cx, cy) lies at frame pixel p = H(c): its content sits (p - c) away, so the
    camera turns by atan((p_x - c_x)/f_x) to the right and atan((p_y - c_y)/f_y) down. The roll is the
    turn of H's local linear part at c (image y points down, so a positive angle is clockwise on screen;
    seen from behind the camera, rolling it clockwise turns the picture's content clockwise back)."""
    c = np.array([cx, cy])
    p = _apply(H, c)
    J = _jacobian(H, c)
    roll = math.degrees(math.atan2(J[1, 0] - J[0, 1], J[0, 0] + J[1, 1]))
    # a turn alone magnifies a ray phi off the axis by 1/cos(phi) across and 1/cos^2(phi) along: what is
    # left after it is the change of distance (or of lens)
    off_axis = math.atan(math.hypot((p[0] - cx) / fx, (p[1] - cy) / fy))
    scale = math.sqrt(abs(float(np.linalg.det(J)))) * math.cos(off_axis) ** 1.5
    return Turn(math.degrees(math.atan((p[0] - cx) / fx)), math.degrees(math.atan((p[1] - cy) / fy)), roll, scale)


def turn_words(turn: Turn) -> str:
    """``Turn`` in plain words: "turn 2.0° left, tilt 1.0° down, roll 0.5° clockwise (seen from behind the
    camera)"; "hold the camera: within 0.3°" when nothing is worth a word."""
    words = []
    if abs(turn.pan_deg) >= HOLD_DEG:
        words.append(f"turn {abs(turn.pan_deg):.1f}° {'right' if turn.pan_deg > 0 else 'left'}")
    if abs(turn.tilt_deg) >= HOLD_DEG:
        words.append(f"tilt {abs(turn.tilt_deg):.1f}° {'down' if turn.tilt_deg > 0 else 'up'}")
    if abs(turn.roll_deg) >= HOLD_DEG:
        words.append(f"roll {abs(turn.roll_deg):.1f}° {'clockwise' if turn.roll_deg > 0 else 'anticlockwise'} "
                     "(seen from behind the camera)")
    if abs(turn.scale - 1.0) >= HOLD_SCALE:
        closer = turn.scale > 1.0
        words.append(f"move {'back' if closer else 'closer'}: things look {abs(turn.scale - 1.0):.0%} "
                     f"{'larger' if closer else 'smaller'} than in the render")
    return ", ".join(words) if words else f"hold the camera: within {HOLD_DEG}°"


def pixel_words(H: np.ndarray, size: tuple[int, int]) -> str:
    """Without a focal length: which way the render's centre lies in the frame, in pixels."""
    c = np.array([(size[0] - 1) / 2, (size[1] - 1) / 2])
    dx, dy = _apply(H, c) - c
    parts = [f"{abs(dx):.0f} px {'right' if dx > 0 else 'left'}" if abs(dx) >= 1 else "",
             f"{abs(dy):.0f} px {'down' if dy > 0 else 'up'}" if abs(dy) >= 1 else ""]
    moved = ", ".join(p for p in parts if p)
    return f"turn the camera towards the render's centre: {moved}" if moved else "hold the camera"


def corner_shift(H: np.ndarray, size: tuple[int, int]) -> float:
    """Mean displacement of the frame's corners between render and frame, in frame pixels."""
    w, h = size
    corners = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], float)
    return float(np.mean(np.linalg.norm(_apply(H, corners) - corners, axis=-1)))


def _apply(H: np.ndarray, points: np.ndarray) -> np.ndarray:
    p = np.atleast_2d(points)
    q = np.c_[p, np.ones(len(p))] @ np.asarray(H, float).T
    out = q[:, :2] / q[:, 2:3]
    return out[0] if np.ndim(points) == 1 else out


def _jacobian(H: np.ndarray, c: np.ndarray, eps: float = 1.0) -> np.ndarray:
    """d H(x) / d x at c (central differences; H is smooth, a pixel is small)."""
    cols = [(_apply(H, c + e) - _apply(H, c - e)) / (2 * eps) for e in (np.array([eps, 0.0]), np.array([0.0, eps]))]
    return np.stack(cols, axis=1)


def _intrinsics(camera, size: tuple[int, int]) -> tuple[float, float, float, float] | None:
    """(fx, fy, cx, cy) of ``camera`` at the frame's size."""
    if camera is None:
        return None
    sx, sy = size[0] / camera.width, size[1] / camera.height
    return camera.fx * sx, camera.fy * sy, (camera.cx + 0.5) * sx - 0.5, (camera.cy + 0.5) * sy - 0.5


def _turn_fields(turn: Turn | None) -> tuple:
    return (turn.pan_deg, turn.tilt_deg, turn.roll_deg, turn.scale) if turn else (None, None, None, None)


VERDICTS = ("aligned", "check", "off")


def _verdict(reg: Registration | None, shift: float | None, distance: float | None, diag: float) -> str:
    """By the shift of a confident registration; else by the edge distance, which an unsure shift can
    still move from "aligned" to "check" (never to "off": it is a guess)."""
    def by(value: float | None) -> int:
        return 2 if value is None else 0 if value <= GOOD_SHARE * diag else 1 if value <= CHECK_SHARE * diag else 2
    if reg is not None and reg.confident:
        return VERDICTS[by(shift)]
    return VERDICTS[max(by(distance), min(by(shift), 1) if reg is not None else 0)]


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


def register(render: np.ndarray, frame: np.ndarray) -> Registration | None:
    """Where the render lies in the frame (same size): ECC, else features when ECC fails or is unsure
    and the features do better; None when neither finds anything."""
    size = frame.shape[1::-1]
    ecc = _plausible(_ecc(render, frame), size)
    if ecc is not None and ecc.confident:
        return ecc
    features = _plausible(_features(render, frame), size)
    candidates = [r for r in (ecc, features) if r is not None]
    return max(candidates, key=lambda r: r.score) if candidates else None


def _plausible(reg: Registration | None, size: tuple[int, int]) -> Registration | None:
    """None for a degenerate fit: a real camera mismatch neither flips the picture nor scales it 2x."""
    if reg is None or not np.all(np.isfinite(reg.H)):
        return None
    det = float(np.linalg.det(_jacobian(reg.H, np.array([(size[0] - 1) / 2, (size[1] - 1) / 2]))))
    return reg if 0.25 <= det <= 4.0 else None


def _gradient(image: np.ndarray, scale: float) -> np.ndarray:
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(np.float32)
    grey = cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    mag = np.hypot(cv2.Sobel(grey, cv2.CV_32F, 1, 0), cv2.Sobel(grey, cv2.CV_32F, 0, 1))
    mag = cv2.GaussianBlur(mag, (0, 0), 2.0)
    return mag / max(1e-6, float(mag.max()))


def _ecc(render: np.ndarray, frame: np.ndarray) -> Registration | None:
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
            return None
        if level < 1.0:
            warp[:, 2] /= level   # the translation grows with the image; the rotation does not
    if ecc is None:
        return None
    warp = np.vstack([warp, [0, 0, 1]]).astype(np.float32)
    try:   # a turned camera moves the picture in perspective: refine the shift-and-turn to a homography
        ecc, warp = cv2.findTransformECC(template, moving, warp, cv2.MOTION_HOMOGRAPHY, criteria, None, 5)
    except cv2.error:
        pass
    # ECC's warp maps frame -> render at the working scale; back to full size, then inverted
    S = np.diag([scale, scale, 1.0])
    frame_to_render = np.linalg.inv(S) @ warp.astype(np.float64) @ S
    try:
        return Registration(np.linalg.inv(frame_to_render), float(ecc), "ECC")
    except np.linalg.LinAlgError:
        return None


def _features(render: np.ndarray, frame: np.ndarray) -> Registration | None:
    """SIFT on contrast-equalised grey images, Lowe's ratio test, a RANSAC homography (render -> frame)."""
    clahe = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8))
    sift = cv2.SIFT_create(nfeatures=2000)
    kr, dr = sift.detectAndCompute(clahe.apply(cv2.cvtColor(render, cv2.COLOR_BGR2GRAY)), None)
    kf, df = sift.detectAndCompute(clahe.apply(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)), None)
    if dr is None or df is None or len(kr) < MIN_INLIERS or len(kf) < MIN_INLIERS:
        return None
    pairs = cv2.BFMatcher(cv2.NORM_L2).knnMatch(dr, df, k=2)
    good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < 0.75 * p[1].distance]
    if len(good) < MIN_INLIERS:
        return None
    src = np.float32([kr[m.queryIdx].pt for m in good])
    dst = np.float32([kf[m.trainIdx].pt for m in good])
    H, inliers = cv2.findHomography(src, dst, cv2.RANSAC, 3.0)
    if H is None or int(inliers.sum()) < MIN_INLIERS:
        return None
    return Registration(H, float(inliers.sum()) / len(good), "features")


# ---------------------------------------------------------------------- the image
COLOURS = {"aligned": (80, 200, 60), "check": (0, 190, 255), "off": (60, 60, 230)}
FONT = cv2.FONT_HERSHEY_SIMPLEX


def text_scale(width: int) -> float:
    """Font scale for a banner across ``width`` pixels: the text grows with the image (about 40 px
    capitals on a 1280-wide aid at 0.9), so it reads at the size the image is shown."""
    return max(0.45, 0.9 * width / 1280)


def _aid_image(render: np.ndarray, frame: np.ndarray, edges_r: np.ndarray, result: Alignment,
               reg: Registration | None) -> np.ndarray:
    edges = frame.copy()
    thick = cv2.dilate(edges_r.astype(np.uint8), np.ones((2, 2), np.uint8)) > 0
    edges[thick] = (255, 255, 0)                       # render outlines in cyan over the photo
    if reg is not None:
        _arrow(edges, reg, result)
    ghost = cv2.addWeighted(frame, 0.5, render, 0.5, 0.0)
    panels = np.hstack([edges, ghost])
    unsure = "" if result.confident or reg is None else " (low confidence)"
    lines = [(f"{result.verdict.upper()}{unsure}: {result.advice}", COLOURS[result.verdict]),
             (f"edges {_fmt(result.edge_distance_px)}, {result.shift_text()} | left: render edges, arrow: "
              "turn the camera that way | right: ghost", (235, 235, 235))]
    return np.vstack([_banner(lines, panels.shape[1]), panels])


def _banner(lines: list[tuple[str, tuple[int, int, int]]], width: int) -> np.ndarray:
    """Lines of text on a dark box as wide as the image, at ``text_scale(width)``; a line too long for
    the width wraps at spaces (the font never shrinks below the scale)."""
    scale = text_scale(width)
    thickness = max(1, round(scale * 2))
    line_h = int(cv2.getTextSize("Ag", FONT, scale, thickness)[0][1] * 2.0)
    wrapped = [(row, colour) for text, colour in lines
               for row in _wrap(text.replace("°", " deg"), width - line_h, scale, thickness)]   # Hershey: no °
    bar = np.full((line_h * len(wrapped) + line_h // 3, width, 3), 25, np.uint8)
    for i, (text, colour) in enumerate(wrapped):
        cv2.putText(bar, text, (line_h // 2, int(line_h * (i + 0.8))), FONT, scale, colour, thickness, cv2.LINE_AA)
    return bar


def _wrap(text: str, width: int, scale: float, thickness: int) -> list[str]:
    rows, row = [], ""
    for word in text.split(" "):
        trial = f"{row} {word}" if row else word
        if row and cv2.getTextSize(trial, FONT, scale, thickness)[0][0] > width:
            rows.append(row)
            trial = word
        row = trial
    return rows + [row]


def _arrow(image: np.ndarray, reg: Registration, result: Alignment) -> None:
    """From the frame's centre to where the render's centre lies: the way to turn the camera."""
    h, w = image.shape[:2]
    c = np.array([(w - 1) / 2, (h - 1) / 2])
    p = _apply(reg.H, c)
    if not np.all(np.isfinite(p)) or np.linalg.norm(p - c) < 3:
        return
    colour = COLOURS[result.verdict] if result.confident else (150, 150, 150)
    size = max(2, w // 320)
    start, end = tuple(int(v) for v in c), tuple(int(v) for v in np.clip(p, -w, 2 * w))
    tip = min(0.5, 12.0 * size / max(1.0, float(np.linalg.norm(p - c))))   # a visible head on a short arrow
    cv2.drawMarker(image, start, (255, 255, 255), cv2.MARKER_CROSS, 8 * size, size)
    cv2.arrowedLine(image, start, end, (0, 0, 0), size + 2, cv2.LINE_AA, tipLength=tip)
    cv2.arrowedLine(image, start, end, colour, size, cv2.LINE_AA, tipLength=tip)


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}px"
