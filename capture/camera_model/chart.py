"""The ColorChecker 24: its reference colours, a virtual chart, detection in a frame, patch sampling.

Two detectors find the chart: OpenCV's ``mcc`` (contrib) and colour-science's
``colour-checker-detection`` (segmentation); where both fail (a small or tilted chart, a Passport),
the user points at it (``--chart-box``: a box or four corners around the 24 patches, ``box_quads``).
Each gives the 24 patch outlines in the frame; the same
sampler then takes each patch's mean colour from its central part and drops the patches that fall
outside the frame or are clipped (saturated or crushed to black), saying how many and why."""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import cv2
import numpy as np

from isu_validate.errors import InputError, UserError

DETECTORS = ("mcc", "ccd")
PATCHES, COLUMNS, ROWS = 24, 6, 4
NEUTRALS = slice(18, 24)          # white ... black, the bottom row
INNER = 0.55                      # share of a patch's width sampled (away from its edges and blur)
GAP_RATIO = 0.15                  # gap between patches / patch width (Classic ~0.11, Passport ~0.2): a box
                                  # around the patches is cut into 6 x 4 patches with such gaps
BOX_HELP = ("X,Y,W,H (pixels: the rectangle around the 24 patches, dark skin at the top left) or "
            "X1,Y1,X2,Y2,X3,Y3,X4,Y4 (the patch area's corners: dark skin, bluish green, black, white)")
CLIPPED_SHARE = 0.05              # a patch with more than this share of clipped pixels is dropped
HIGH, LOW = 250 / 255, 3 / 255


class ChartNotFound(UserError, ValueError):
    """No ColorChecker 24 in the frame; the message names the file and how to reshoot."""


@functools.lru_cache(maxsize=1)
def reference_linear() -> np.ndarray:
    """(24, 3) linear sRGB of the ColorChecker's reference reflectances (colour-science's 'ColorChecker N
    Ohta' spectral data) under D65 for the CIE 1931 2-degree observer; white patch ~0.9."""
    import colour
    sds = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    illuminant = colour.SDS_ILLUMINANTS["D65"].copy().align(cmfs.shape)
    xyz = np.array([colour.sd_to_XYZ(sd.copy().align(cmfs.shape), cmfs, illuminant) / 100.0 for sd in sds.values()])
    return np.asarray(colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False), dtype=float)


def chart_image(patch_px: int = 60, gap_px: int = 12) -> np.ndarray:
    """A linear-RGB picture of the chart: 6 x 4 patches on the chart's black frame (float32)."""
    ref = np.clip(reference_linear(), 0.0, 1.0)
    w, h = COLUMNS * patch_px + (COLUMNS + 1) * gap_px, ROWS * patch_px + (ROWS + 1) * gap_px
    img = np.full((h, w, 3), 0.012, dtype=np.float32)
    for i in range(PATCHES):
        r, c = divmod(i, COLUMNS)
        y, x = gap_px + r * (patch_px + gap_px), gap_px + c * (patch_px + gap_px)
        img[y:y + patch_px, x:x + patch_px] = ref[i]
    return img


@dataclass
class Detection:
    detector: str
    quads: np.ndarray                    # (24, 4, 2) patch outlines in frame pixels, reference order
    seconds: float = 0.0


@dataclass
class Patches:
    colours: np.ndarray                  # (24, 3) mean output level (0..1) of each patch's centre
    usable: np.ndarray                   # (24,) bool
    dropped: dict[int, str] = field(default_factory=dict)     # patch index -> why

    def counts(self) -> dict:
        why = {}
        for reason in self.dropped.values():
            why[reason] = why.get(reason, 0) + 1
        return {"used": int(self.usable.sum()), "dropped": len(self.dropped), "why": why}


def detect(image_rgb8: np.ndarray, detector: str) -> Detection | None:
    """The chart's 24 patch outlines, or None when this detector finds no chart."""
    import time
    t0 = time.perf_counter()
    quads = _mcc(image_rgb8) if detector == "mcc" else _ccd(image_rgb8)
    if quads is None:
        return None
    return Detection(detector, quads, time.perf_counter() - t0)


def _mcc(image_rgb8: np.ndarray) -> np.ndarray | None:
    finder = cv2.mcc.CCheckerDetector_create()
    if not finder.process(cv2.cvtColor(image_rgb8, cv2.COLOR_RGB2BGR), cv2.mcc.MCC24, 1):
        return None
    checker = finder.getBestColorChecker()
    return np.asarray(checker.getColorCharts(), dtype=np.float64).reshape(PATCHES, 4, 2)


def _ccd(image_rgb8: np.ndarray) -> np.ndarray | None:
    import colour_checker_detection as ccd
    h, w = image_rgb8.shape[:2]
    if h > w:
        return None                       # it turns portrait frames; their coordinates are not mapped back
    settings = ccd.SETTINGS_SEGMENTATION_COLORCHECKER_CLASSIC
    found = ccd.detect_colour_checkers_segmentation(image_rgb8.astype(np.float32) / 255.0, additional_data=True)
    if not found:
        return None
    data = found[0]
    ww, wh = settings["working_width"], int(settings["working_width"] / settings["aspect_ratio"])
    rectangle = np.float32([[ww, 0], [ww, wh], [0, wh], [0, 0]])
    to_working = cv2.getPerspectiveTransform(rectangle, np.float32(data.quadrilateral))
    scale = (max(h, w) / ww)              # colour-checker-detection works on a copy resized to 1440 wide
    quads = []
    for y0, y1, x0, x1 in np.asarray(data.swatch_masks)[:PATCHES]:
        corners = np.float32([[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
        quads.append(cv2.perspectiveTransform(corners, to_working)[0] * scale)
    return np.asarray(quads, dtype=np.float64)


def parse_box(text: str) -> np.ndarray:
    """``--chart-box`` as the four corners (4, 2) of the patch area: top left (dark skin) clockwise."""
    try:
        v = [float(x) for x in text.replace(" ", "").split(",")]
    except ValueError:
        v = []
    if len(v) == 4 and v[2] > 0 and v[3] > 0:
        x, y, w, h = v
        return np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
    if len(v) == 8:
        corners = np.array(v).reshape(4, 2)
        if abs(cv2.contourArea(corners.astype(np.float32))) > 0:
            return corners
    raise InputError(f"--chart-box {text!r}: expected {BOX_HELP}")


def box_quads(corners: np.ndarray) -> np.ndarray:
    """The 24 patch outlines (24, 4, 2) inside the patch area whose corners the user gave (perspective
    through the four corners: a tilted chart is followed)."""
    pitch = 1.0 + GAP_RATIO
    width, height = COLUMNS * pitch - GAP_RATIO, ROWS * pitch - GAP_RATIO
    area = np.float32([[0, 0], [width, 0], [width, height], [0, height]])
    H = cv2.getPerspectiveTransform(area, np.float32(corners))
    quads = []
    for i in range(PATCHES):
        r, c = divmod(i, COLUMNS)
        x, y = c * pitch, r * pitch
        square = np.float32([[[x, y], [x + 1, y], [x + 1, y + 1], [x, y + 1]]])
        quads.append(cv2.perspectiveTransform(square, H)[0])
    return np.asarray(quads, dtype=np.float64)


def pointed(image_rgb8: np.ndarray, corners: np.ndarray, where: str) -> Detection:
    """The chart where the user pointed (``--chart-box``); InputError when the box leaves the frame."""
    h, w = image_rgb8.shape[:2]
    if corners.min() < 0 or corners[:, 0].max() > w or corners[:, 1].max() > h:
        raise InputError(f"{where}: --chart-box reaches outside the {w}x{h} frame "
                         f"({np.round(corners, 1).tolist()})")
    return Detection("box", box_quads(corners))


def sample(image01: np.ndarray, quads: np.ndarray) -> Patches:
    """Mean colour of each patch's centre; patches outside the frame or clipped are dropped."""
    h, w = image01.shape[:2]
    colours, usable, dropped = np.zeros((PATCHES, 3)), np.zeros(PATCHES, bool), {}
    for i, quad in enumerate(quads):
        if quad.min() < 0 or quad[:, 0].max() > w - 1 or quad[:, 1].max() > h - 1:
            dropped[i] = "outside the frame"
            continue
        centre = quad.mean(axis=0)
        inner = centre + (quad - centre) * INNER
        mask = np.zeros((h, w), np.uint8)
        cv2.fillConvexPoly(mask, np.round(inner).astype(np.int32), 1)
        pixels = image01[mask.astype(bool)]
        if len(pixels) < 4:
            dropped[i] = "too small in the frame (under 4 pixels)"
            continue
        if np.mean(pixels.max(axis=1) >= HIGH) > CLIPPED_SHARE:
            dropped[i] = "saturated"
            continue
        if np.mean(pixels.max(axis=1) <= LOW) > CLIPPED_SHARE:
            dropped[i] = "crushed to black"
            continue
        colours[i], usable[i] = pixels.mean(axis=0), True
    return Patches(colours, usable, dropped)


def oriented(quads: np.ndarray, patches: Patches, linearise) -> tuple[np.ndarray, Patches]:
    """The chart may be found upside down (same outline): keep the patch order whose colours, brought
    to linear light, fit the reference best with one gain per channel."""
    flipped = Patches(patches.colours[::-1].copy(), patches.usable[::-1].copy(),
                      {PATCHES - 1 - i: why for i, why in patches.dropped.items()})
    if _fit_error(linearise(flipped.colours), flipped.usable) < _fit_error(linearise(patches.colours), patches.usable):
        return quads[::-1].copy(), flipped
    return quads, patches


def _fit_error(linear: np.ndarray, usable: np.ndarray) -> float:
    ref = reference_linear()[usable]
    x = linear[usable]
    gains = (x * ref).sum(axis=0) / np.maximum((x * x).sum(axis=0), 1e-12)
    return float(np.mean((x * gains - ref) ** 2)) if usable.any() else np.inf


def find(image_rgb8: np.ndarray, detector: str = "auto", where: str = "frame",
         box: np.ndarray | None = None) -> Detection:
    """Detect with one detector, or with ``auto``: mcc first (found charts more often and ~10x faster in
    ``bench exposure``), colour-checker-detection when mcc finds nothing; ``box`` (corners from
    ``parse_box``): where the user pointed, no detector."""
    if box is not None:
        return pointed(image_rgb8, box, where)
    order = DETECTORS if detector == "auto" else (detector,)
    if detector not in DETECTORS + ("auto",):
        raise InputError(f"unknown chart detector {detector!r}; use auto, mcc or ccd")
    for name in order:
        found = detect(image_rgb8, name)
        if found is not None:
            return found
    raise ChartNotFound(f"{where}: no ColorChecker 24 found (tried {', '.join(order)}). Reshoot with the whole "
                        "chart in the frame, facing the camera, at least ~1/6 of the frame wide, evenly lit and "
                        "not overexposed; or point at the chart you see: --chart-box " + BOX_HELP)
