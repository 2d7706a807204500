"""``exposure chart``: render a virtual ColorChecker where the real one stood.

The chart's pose comes from its patches found in the real frame (PnP on the patch centres through the
camera file's lens, then into the cabin through the camera's registered pose); the renderer shows a
self-lit board textured with the chart's reference colours there (``render_board``), seen by the same
camera without its imaging model, so the render holds the colours the renderer makes of the chart."""
from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from . import chart
from .colour_align import read_rgb8
from .colour_fit import srgb_decode, srgb_encode

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


def chart_pose(rig, centres_px: np.ndarray, pitch_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(R_cabin_from_board, cabin position of the board origin) from the patch centres in the frame."""
    objects, _ = board_layout(pitch_m)
    rays = rig.rays(centres_px)                   # undistorted: any lens model, then a unit pinhole
    ok, rvec, tvec = cv2.solvePnP(objects, rays.astype(np.float64), np.eye(3), None, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        raise ValueError("the chart's pose could not be solved from its patches")
    R_cam_from_board = cv2.Rodrigues(rvec)[0]
    return rig.R @ R_cam_from_board, rig.R @ tvec.ravel() + rig.t


def render_virtual_chart(real_path: str | Path, camera: str | Path, out: str | Path, preset: str = "standard",
                         pitch_m: float = DEFAULT_PITCH_M, detector: str = "auto") -> dict:
    from isu_validate.render import load_camera, render_board
    rig = load_camera(camera)
    image = read_rgb8(real_path)
    if image.shape[1] != rig.width or image.shape[0] != rig.height:
        raise ValueError(f"{real_path} is {image.shape[1]}x{image.shape[0]} but the camera file {camera} is "
                         f"{rig.width}x{rig.height}; use the camera file of the camera that took the frame")
    found = chart.find(image, detector, str(real_path))
    quads, _ = chart.oriented(found.quads, chart.sample(image.astype(np.float32) / 255.0, found.quads), srgb_decode)
    R, t = chart_pose(rig, quads.mean(axis=1), pitch_m)
    _, size = board_layout(pitch_m)
    with tempfile.TemporaryDirectory(prefix="isu-chart-") as tmp:
        texture = Path(tmp) / "colorchecker.png"
        encoded = (srgb_encode(chart.chart_image(PATCH_PX, GAP_PX)) * 255 + 0.5).astype(np.uint8)
        cv2.imwrite(str(texture), cv2.cvtColor(encoded, cv2.COLOR_RGB2BGR))
        render_board(texture, size, (R, t), out, camera=replace(rig, imaging=None), preset=preset)
    return {"real": str(real_path), "sim": str(out), "detector": found.detector, "pitch_m": pitch_m,
            "board_rotation": R.tolist(), "board_position": t.tolist()}
