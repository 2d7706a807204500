"""``exposure chart``: render a virtual ColorChecker where the real one stood.

The chart's pose in the cabin comes from the real frame (``capture.camera_model.virtual_chart``); the
renderer shows a self-lit board textured with the chart's reference colours there (``render_board``), seen
by the same camera without its imaging model, so the render holds the colours the renderer makes of the chart."""
from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import cv2

from capture.camera import load_camera
from capture.camera_model import virtual_chart
from capture.camera_model.colour_align import read_rgb8

from ..errors import InputError
from . import render_board


def render_virtual_chart(real_path: str | Path, camera: str | Path, out: str | Path, preset: str = "standard",
                         pitch_m: float = virtual_chart.DEFAULT_PITCH_M, detector: str = "auto",
                         box=None) -> dict:
    rig = load_camera(camera)
    image = read_rgb8(real_path)
    if image.shape[1] != rig.width or image.shape[0] != rig.height:
        raise InputError(f"{real_path} is {image.shape[1]}x{image.shape[0]} but the camera file {camera} is "
                         f"{rig.width}x{rig.height}; use the camera file of the camera that took the frame")
    R, t, found_by = virtual_chart.locate(image, rig, pitch_m, detector, str(real_path), box)
    _, size = virtual_chart.board_layout(pitch_m)
    with tempfile.TemporaryDirectory(prefix="isu-chart-") as tmp:
        texture = Path(tmp) / "colorchecker.png"
        cv2.imwrite(str(texture), cv2.cvtColor(virtual_chart.texture(), cv2.COLOR_RGB2BGR))
        render_board(texture, size, (R, t), out, camera=replace(rig, imaging=None), preset=preset)
    return {"real": str(real_path), "sim": str(out), "detector": found_by, "pitch_m": pitch_m,
            "board_rotation": R.tolist(), "board_position": t.tolist()}
