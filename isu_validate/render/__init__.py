"""Rendering scenes with Blender: a warm worker process, camera and cabin rigs, presets, cache.

Host-side modules never import bpy; only ``isu_validate.render.blender`` (run inside the worker
subprocess) does. The search's evaluation calls ``open_renderer(...)`` and then the ``Renderer``
protocol of ``isu_validate.protocols``. The camera a render looks through is ``capture.camera``'s
``Camera`` (``load_camera``); ``camera.py`` here is what Blender renders for it."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from capture.camera import Camera

from .cabin import CabinRigError, load_cabin
from .camera import pinhole_plan
from .presets import PRESETS, Preset, get_preset
from .renderer import DEFAULTS, RENDERER_VERSION, BlenderRenderer


def open_renderer(preset: "str | Preset" = "draft", camera: str | os.PathLike | Camera = "default",
                  cabin: str | os.PathLike = "default", channels: Sequence[str] | str = (),
                  cache_dir: str | os.PathLike | None = None, log_dir: str | os.PathLike | None = None,
                  timeout_s: float = 240.0, space=None, threads: int = 0,
                  extrinsics_from: str | os.PathLike | Camera | None = None,
                  min_visible: Mapping[str, float] | None = None, device: str | None = "auto") -> BlenderRenderer:
    """A renderer for one process. Its Blender worker starts on the first render (each process of a
    pool gets its own); ``close()`` stops it. ``channels``: any of "seg", "depth", "exr".

    A camera file whose pose was never registered is refused (CameraFileError) unless
    ``extrinsics_from`` names a registered rig to take the pose from. ``min_visible`` overrides the
    space's per-feature visibility thresholds ({feature or "*": share}). ``device``: Cycles' compute device,
    ``auto|cpu|optix|cuda|hip|oneapi|metal`` (``render/gpu.py``; None keeps a ``Preset``'s own); an absent
    GPU falls back to the CPU with one line on stderr.

        with open_renderer(preset="draft", space=space) as renderer:      # one warm worker, many scenes
            frame = renderer.render(scene, "scene.png")   # frame.image, frame.visibility, frame.occluded
    """
    return BlenderRenderer(preset, camera, cabin, channels, cache_dir, log_dir, timeout_s, space, threads,
                           extrinsics_from, min_visible, device=device)


def render_board(image_path: str | os.PathLike, board_size_m: tuple[float, float], pose, out: str | os.PathLike,
                 camera: str | os.PathLike | Camera = "default", preset: str = "calibration",
                 scene: Mapping[str, Any] | None = None, renderer: BlenderRenderer | None = None,
                 channels: Sequence[str] = ()):
    """Render a flat, self-lit textured board (e.g. a ChArUco image) through a camera rig.

    The image spans the board's [0, w] x [0, h] metres; board frame as OpenCV's object points: origin
    at the image's top-left corner, x along its columns, y along its rows, z into the board.
    ``pose`` = (R_cabin_from_board 3x3, t = cabin position of the board origin). ``scene`` None shows the
    empty cabin (no driver). Pass an open ``renderer`` to render many views with one warm worker."""
    R, t = np.asarray(pose[0], float), np.asarray(pose[1], float)
    extras = {"board": {"image": str(Path(image_path).resolve()), "size_m": [float(v) for v in board_size_m],
                        "rotation": R.tolist(), "position": t.tolist()}}
    own = renderer is None
    renderer = renderer or open_renderer(preset, camera, channels=channels)
    try:
        return renderer.render_extras(scene, Path(out), extras)
    finally:
        if own:
            renderer.close()


__all__ = ["BlenderRenderer", "CabinRigError", "DEFAULTS", "PRESETS", "Preset", "RENDERER_VERSION", "get_preset",
           "load_cabin", "open_renderer", "pinhole_plan", "render_board"]
