"""The sheet's pictures: the sample's scene rendered for print, and crops around what each feature shows.

A run renders small and fast (the draft preset is 320x240); scaled up to a sheet's width it prints
blurred. So ``recreate`` renders each scene again through the run's camera, cabin and visibility
settings at the ``standard`` preset and at least ``MIN_WIDTH`` pixels wide (about 2 s a scene) into the
sample's ``sheet.png``; ``sim.png`` stays the run's frame, the one the SUT saw and ``agree`` compares.
``--sheet-preset run`` skips the render and prints the run's frame (no Blender).

A crop shows a feature's render parts enlarged. A feature the render hid (``occluded``: the phone
at the ear behind the head) has few or no visible pixels to crop around, so its crop is taken around
where the thing is, hidden or not: its box in the cabin (the renderer's ``bounds``) projected through
the sheet's camera, outlined on the crop. Without that box, the few visible pixels' box; without any,
a marked placeholder.
"""
from __future__ import annotations

import base64
import io
import json
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
from PIL import Image, ImageDraw, UnidentifiedImageError

from ..pairs import Sample
from .guide import Item

SHEET_PRESET = "standard"
RUN_FRAME = "run"            # --sheet-preset run: the run's own frame, not rendered again
MIN_WIDTH = 640
CROP_MARGIN = 0.6   # share of the box added on each side: the hand around the phone, the seat around the child
CROP_MIN_PX = 0.06  # of the picture's width, at least, on each side
CROP_OUT_PX = 200

Box = tuple[float, float, float, float]   # x0, y0, x1, y1 in the picture's pixels


@dataclass
class Picture:
    """What a sheet shows: an image, the camera it was seen through (at its size) and where things are."""
    image: Path
    camera: Any | None                                        # capture.camera.Camera at the image's size
    visible: dict[str, Box] = field(default_factory=dict)     # render instance -> box of its visible pixels
    whole: dict[str, Box] = field(default_factory=dict)       # render instance -> box of all of it, hidden or not
    rendered: bool = False                                    # rendered for the sheet (False: the run's frame)

    @property
    def size(self) -> tuple[int, int]:
        with Image.open(self.image) as img:
            return img.size

    def area(self, parts: tuple[str, ...]) -> float:
        """The share of the picture the visible boxes of ``parts`` span (0 when none is visible)."""
        boxes = [self.visible[p] for p in parts if p in self.visible]
        if not boxes:
            return 0.0
        w = max(b[2] for b in boxes) - min(b[0] for b in boxes)
        h = max(b[3] for b in boxes) - min(b[1] for b in boxes)
        width, height = (self.camera.width, self.camera.height) if self.camera else self.size
        return w * h / (width * height)


@dataclass
class Setup:
    """How the run rendered: what a sheet render must match."""
    camera: Any                  # capture.camera.Camera, the run's (pose from --extrinsics-from applied)
    cabin: str
    space: Any
    min_visible: Mapping[str, float]


class Pictures:
    """Makes each sample's picture: renders at ``preset`` (one renderer per run setup, opened on first use
    and closed by ``close``) or, with ``preset`` ``"run"``, takes the run's frame. ``opener`` is
    ``isu_validate.render.open_renderer`` unless given (tests give a painter)."""

    def __init__(self, preset: str = SHEET_PRESET, opener: Callable | None = None):
        self.preset = preset
        self._opener = opener
        self._renderers: dict[str, Any] = {}
        self._stack = ExitStack()

    def picture(self, sample: Sample, scene: Mapping[str, Any], setup: Setup | None) -> Picture:
        if self.preset == RUN_FRAME or setup is None:
            return _run_frame(sample, setup)
        camera = setup.camera.scaled(max(1.0, MIN_WIDTH / setup.camera.width))
        renderer = self._renderer(camera, setup)
        result = renderer.render(scene, sample.sheet_image)
        label = _read_json(result.channels.get("label"))
        whole = projected_boxes(renderer.bounds(scene), camera) if hasattr(renderer, "bounds") else {}
        return Picture(Path(result.image), camera, _boxes(label), whole, True)

    def close(self) -> None:
        self._stack.close()
        self._renderers.clear()

    def _renderer(self, camera, setup: Setup):
        key = json.dumps([camera.hash, setup.cabin, dict(setup.min_visible)], sort_keys=True)
        if key not in self._renderers:
            opener = self._opener or _default_opener()
            renderer = opener(self.preset, camera=camera, cabin=setup.cabin, space=setup.space,
                              min_visible=dict(setup.min_visible))
            self._stack.callback(renderer.close)
            self._renderers[key] = renderer
        return self._renderers[key]


def _default_opener():
    from ..render import open_renderer
    return open_renderer


def _run_frame(sample: Sample, setup: Setup | None) -> Picture:
    """The run's frame (sim.png) with its render label's boxes; the camera scaled to its size."""
    picture = Picture(sample.sim, None, _boxes(sample.render_label()))
    if setup is not None:
        try:
            width = picture.size[0]
        except (OSError, UnidentifiedImageError):
            return picture
        picture.camera = setup.camera.scaled(width / setup.camera.width)
    return picture


def _read_json(path: Path | None) -> dict:
    try:
        return json.loads(path.read_text()) if path else {}
    except (OSError, ValueError):
        return {}


def _boxes(label: Mapping) -> dict[str, Box]:
    visible = label.get("visible", {}) if isinstance(label, Mapping) else {}
    return {name: tuple(float(v) for v in spec["bbox"]) for name, spec in visible.items()
            if isinstance(spec, Mapping) and len(spec.get("bbox", ())) == 4}


def projected_boxes(bounds: Mapping[str, tuple], camera) -> dict[str, Box]:
    """Each instance's cabin box (min, max corners) projected through ``camera``: the box of its 8 corners
    in front of the camera, clipped to the image; left out when none is in front or it misses the image."""
    out = {}
    for name, (lo, hi) in bounds.items():
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        uv = camera.project(corners)
        uv = uv[np.isfinite(uv).all(axis=1)]
        if not len(uv):
            continue
        x0, y0 = np.clip(uv.min(axis=0), 0, [camera.width - 1, camera.height - 1])
        x1, y1 = np.clip(uv.max(axis=0), 0, [camera.width - 1, camera.height - 1])
        if x1 > x0 and y1 > y0:
            out[name] = (float(x0), float(y0), float(x1), float(y1))
    return out


# ---------------------------------------------------------------------- crops
CROPS_MAX = 7          # one row on the sheet
LARGE_SHARE = 1 / 3    # of the picture's area: a thing this large is clear in the target, no crop


@dataclass
class Crop:
    uri: str | None            # a JPEG data URI; None: nothing to show (a placeholder says why)
    outlined: bool = False     # the hidden thing's place is outlined on it


def sheet_crops(items: list[Item], picture: Picture) -> list[tuple[list[Item], Crop]]:
    """The crops of a sheet, in checklist order, one per set of render parts (gender and emotion share the
    face): every hidden feature's (its place outlined, or a placeholder), then the smallest visible
    things, ``CROPS_MAX`` in all."""
    groups: dict[tuple[str, ...], list[Item]] = {}
    for item in items:
        if item.crop_parts:
            groups.setdefault(item.crop_parts, []).append(item)

    def hidden(parts) -> bool:
        return any(i.hidden is not None for i in groups[parts])

    wanted = [p for p in groups if hidden(p) or 0 < picture.area(p) < LARGE_SHARE]
    keep = set(sorted(wanted, key=lambda p: (not hidden(p), picture.area(p)))[:CROPS_MAX])
    shown = [(groups[p], crop(picture, p, hidden(p)), hidden(p)) for p in groups if p in keep]
    return [(group, c) for group, c, hid in shown if c.uri or hid]


def crop(picture: Picture, parts: tuple[str, ...], hidden: bool) -> Crop:
    """The picture around ``parts``: around all of each part when ``hidden`` and its whole box is known
    (outlined), else around its visible pixels."""
    whole = [picture.whole[p] for p in parts if p in picture.whole] if hidden else []
    boxes = whole or [picture.visible[p] for p in parts if p in picture.visible]
    if not boxes:
        return Crop(None)
    box = (min(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes), max(b[3] for b in boxes))
    try:
        with Image.open(picture.image) as img:
            image = img.convert("RGB")
    except (OSError, UnidentifiedImageError):
        return Crop(None)
    area = _around(box, image.size)
    out = image.crop(area)
    if whole:
        _outline(out, [(b[0] - area[0], b[1] - area[1], b[2] - area[0], b[3] - area[1]) for b in whole])
    scale = CROP_OUT_PX / max(out.size)
    out = out.resize((max(1, round(out.width * scale)), max(1, round(out.height * scale))), Image.LANCZOS)
    buf = io.BytesIO()
    out.save(buf, format="JPEG", quality=88)
    return Crop("data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii"), bool(whole))


def _around(box: Box, size: tuple[int, int]) -> tuple[int, int, int, int]:
    x0, y0, x1, y1 = box
    least = CROP_MIN_PX * size[0]
    mx, my = max(least, (x1 - x0) * CROP_MARGIN), max(least, (y1 - y0) * CROP_MARGIN)
    return (max(0, int(x0 - mx)), max(0, int(y0 - my)), min(size[0], int(x1 + mx + 1)), min(size[1], int(y1 + my + 1)))


def _outline(image: Image.Image, boxes: list[Box]) -> None:
    """A dashed yellow-on-black box where the hidden thing is."""
    draw = ImageDraw.Draw(image)
    width = max(2, image.width // 120)
    for x0, y0, x1, y1 in boxes:
        edges = [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]
        for (ax, ay), (bx, by) in edges:
            steps = max(1, int(max(abs(bx - ax), abs(by - ay)) // (4 * width)))
            for k in range(0, steps, 2):
                a = (ax + (bx - ax) * k / steps, ay + (by - ay) * k / steps)
                b = (ax + (bx - ax) * (k + 1) / steps, ay + (by - ay) * (k + 1) / steps)
                draw.line([a, b], fill=(0, 0, 0), width=width + 2)
                draw.line([a, b], fill=(255, 214, 0), width=width)
