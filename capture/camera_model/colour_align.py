"""``exposure colour``: a ColorChecker in a real frame and in a render of it -> the colour correction.

The render is a frame with a virtual chart at the same place (``exposure chart`` renders one from the
standard's reflectances), its linear EXR, or ``reference`` (the reference colours themselves, no render)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from isu_validate.errors import InputError, InputNotFound
from isu_validate.srgb import srgb_decode, srgb_encode_float

from . import chart
from .colour_fit import ColourFit, fit_colour
from .model import Response


@dataclass
class ChartReading:
    source: str
    detector: str | None
    patches: chart.Patches
    linear: np.ndarray            # (24, 3) linear RGB of the patches
    seconds: float = 0.0


def read_rgb8(path: str | Path) -> np.ndarray:
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        if not Path(path).exists():
            raise InputNotFound(f"{path} does not exist")
        raise InputError(f"{path} cannot be read as an image (corrupt or not an image)")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def read_real(path: str | Path, response: Response | None, detector: str = "auto",
              box: np.ndarray | None = None) -> ChartReading:
    """The chart in a real frame: found by ``detector``, or where ``box`` (``chart.parse_box``) says."""
    image = read_rgb8(path)
    found = chart.find(image, detector, str(path), box)
    to_linear = response.to_linear if response is not None else srgb_decode
    _, patches = chart.oriented(found.quads, chart.sample(image.astype(np.float32) / 255.0, found.quads), to_linear)
    return ChartReading(str(path), found.detector, patches, to_linear(patches.colours), found.seconds)


def read_sim(spec: str | Path, detector: str = "auto") -> ChartReading:
    """A render (PNG: sRGB; EXR: linear, detected on its sRGB encoding) or ``reference``."""
    if str(spec) == "reference":
        ref = chart.reference_linear()
        return ChartReading("reference", None, chart.Patches(srgb_encode_float(ref), np.ones(chart.PATCHES, bool)), ref)
    linear = None
    if str(spec).lower().endswith(".exr"):
        from .develop import read_linear
        linear = read_linear(spec)
        image = (srgb_encode_float(linear) * 255.0 + 0.5).astype(np.uint8)
    else:
        image = read_rgb8(spec)
    found = chart.find(image, detector, str(spec))
    quads, patches = chart.oriented(found.quads, chart.sample(image.astype(np.float32) / 255.0, found.quads),
                                    srgb_decode)
    values = srgb_decode(patches.colours)
    if linear is not None:   # the EXR's own values at the patches, unquantised
        values = chart.sample(np.clip(linear, 0.0, 1.0), quads).colours
    return ChartReading(str(spec), found.detector, patches, values, found.seconds)


def align(real: ChartReading, sim: ChartReading, response: Response | None) -> tuple[ColourFit, dict]:
    usable = real.patches.usable & sim.patches.usable
    fit = fit_colour(sim.linear, real.patches.colours, usable, response)
    report = {**fit.to_dict(), "real": real.source, "sim": sim.source,
              "detector": {"real": real.detector, "sim": sim.detector},
              "patches": {"real": real.patches.counts(), "sim": sim.patches.counts(), "used": int(usable.sum()),
                          "dropped": int(chart.PATCHES - usable.sum())},
              "response": "the camera file's" if response is not None else "sRGB (no [response] in the camera file)"}
    return fit, report
