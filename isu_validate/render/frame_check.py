"""Frames that cannot show the scene: all black, saturated, or without the driver. Such a frame is a
render error: it is recorded as one and never shown to the SUT, whose answers about it would be
failures of the setup, not of the SUT.

Thresholds from measured draft and standard renders of the default rigs (``isu-validate render``):
the darkest legitimate frames (external light LOW, car lights OFF, black T-shirt, anthracite suitcase)
have a luma 99th percentile of 102/255 and a mean of 14; the brightest (HIGH, lights ON, white T-shirt,
yellow suitcase) have 12% of their pixels at 250/255 or above. A camera looking at nothing gives a
99th percentile of 0; a blown-out cabin over 90% saturated pixels."""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

import cv2
import numpy as np

BLACK_P99 = 12              # luma below this at the 99th percentile: black (darkest legitimate: ~100)
SATURATED_LEVEL = 250
SATURATED_SHARE = 0.5       # more than half the pixels at SATURATED_LEVEL or above (brightest legitimate: 0.12)
DRIVER_PARTS = ("driver", "driver_face")


def frame_stats(image: Path | np.ndarray) -> dict:
    """Luma statistics of an 8-bit frame (a path or a BGR/grey array)."""
    if not isinstance(image, np.ndarray):
        image = cv2.imread(str(image), cv2.IMREAD_COLOR)
        if image is None:
            raise ValueError("the rendered frame could not be read back")
    luma = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return {"luma_mean": round(float(luma.mean()), 2), "luma_p99": float(np.percentile(luma, 99)),
            "saturated_share": round(float(np.count_nonzero(luma >= SATURATED_LEVEL)) / luma.size, 4)}


def frame_problem(stats: Mapping, visible: Mapping[str, Mapping], driver_expected: bool = True) -> str | None:
    """Why a scene frame cannot show the scene, with the fix; None when it can (``driver_expected``
    False: a frame rendered without people on purpose, e.g. to time what they cost)."""
    if stats["luma_p99"] < BLACK_P99:
        return (f"black frame: 99% of its pixels are darker than {BLACK_P99}/255 (luma p99 {stats['luma_p99']:g}), "
                f"so the camera sees no lit scene; check the camera rig's pose (--camera/--rig, --extrinsics-from) "
                f"and the cabin rig's [lighting]")
    if stats["saturated_share"] > SATURATED_SHARE:
        return (f"saturated frame: {100 * stats['saturated_share']:.0f}% of its pixels are at "
                f"{SATURATED_LEVEL}/255 or above, so the scene is washed out; check the cabin rig's [lighting] "
                f"(window_light_w, environment_strength) and the camera's exposure")
    if driver_expected and not any(visible.get(p, {}).get("pixels", 0) for p in DRIVER_PARTS):
        return ("the driver is not in the frame (no driver pixels in the segmentation), so no question about the "
                "scene can be judged; check that the camera rig's pose looks at the driver's seat")
    return None
