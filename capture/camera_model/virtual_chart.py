"""The virtual ColorChecker of ``exposure chart``: the chart's board, texture and pose where the real one stood.

Pure chart geometry and data. The pose comes from the chart's patches found in the real frame (PnP on the
patch centres through the camera file's lens, then into the cabin through the camera's registered pose);
the renderer draws the board there (``isu_validate/render/virtual_chart.py``)."""
from __future__ import annotations

import cv2
import numpy as np

from isu_validate.errors import InputError
from isu_validate.srgb import srgb_decode, srgb_encode_float

from . import chart

PATCH_PX, GAP_PX = 60, 12
DEFAULT_PITCH_M = 0.0445      # centre-to-centre patch distance of a ColorChecker Classic (measure yours)


def board_layout(pitch_m: float) -> tuple[np.ndarray, tuple[float, float]]:
    """Patch centres (24, 3) in the board frame (metres; x along columns, y down rows) and its size."""
    m_per_px = pitch_m / (PATCH_PX + GAP_PX)
    centres = []
    for i in range(chart.PATCHES):
        r, c = divmod(i, chart.COLUMNS)
        centres.append([(GAP_PX + c * (PATCH_PX + GAP_PX) + PATCH_PX / 2) * m_per_px,
                        (GAP_PX + r * (PATCH_PX + GAP_PX) + PATCH_PX / 2) * m_per_px, 0.0])
    h, w = chart.chart_image(PATCH_PX, GAP_PX).shape[:2]
    return np.array(centres), (w * m_per_px, h * m_per_px)


def texture() -> np.ndarray:
    """The board's image (RGB, 8-bit): the chart's reference colours, sRGB-encoded as renders are."""
    return (srgb_encode_float(chart.chart_image(PATCH_PX, GAP_PX)) * 255 + 0.5).astype(np.uint8)


def chart_pose(rig, centres_px: np.ndarray, pitch_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(R_cabin_from_board, cabin position of the board origin) from the patch centres in the frame."""
    objects, _ = board_layout(pitch_m)
    rays = rig.rays(centres_px)                   # undistorted: any lens model, then a unit pinhole
    ok, rvec, tvec = cv2.solvePnP(objects, rays.astype(np.float64), np.eye(3), None, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        raise InputError("the chart's pose could not be solved from its patches")
    R_cam_from_board = cv2.Rodrigues(rvec)[0]
    return rig.R @ R_cam_from_board, rig.R @ tvec.ravel() + rig.t


def locate(image: np.ndarray, rig, pitch_m: float, detector: str = "auto",
           where: str = "", box: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, str]:
    """(R_cabin_from_board, board origin, the detector that found it, or "box" where the user pointed) of the
    chart in an RGB frame (8-bit) taken by the camera ``rig``."""
    found = chart.find(image, detector, where, box)
    quads, _ = chart.oriented(found.quads, chart.sample(image.astype(np.float32) / 255.0, found.quads), srgb_decode)
    R, t = chart_pose(rig, quads.mean(axis=1), pitch_m)
    return R, t, found.detector
