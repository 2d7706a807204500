"""A renderer double for ``isu-validate dataset`` without Blender (``--renderer-factory
tests.dataset_doubles:renderer``): it paints the scene's hash and writes a seg channel in which the driver,
the driver's face and, when there is one, the suitcase are rectangles of their instance ids.

ISU_TEST_RENDER_DELAY (seconds) slows every frame, so a test can kill a build mid-way;
ISU_TEST_UNUSABLE_WITH_CAN makes every scene with a can on the co-driver seat an unusable frame;
ISU_TEST_HIDE_PHONE hides the phone in the driver's hand (visible share 0.02: occluded) wherever there is one."""
from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path

import numpy as np

from isu_validate.protocols import RenderError, RenderResult
from isu_validate.render.labels import INSTANCE_ID

WIDTH, HEIGHT = 40, 30


class SegPaintRenderer:
    def __init__(self, space):
        self.space = space

    def render(self, scene, out: Path) -> RenderResult:
        import cv2

        out = Path(out)
        canonical = self.space.check(scene)
        digest = hashlib.sha1(self.space.key(canonical).encode()).digest()
        image = np.zeros((HEIGHT, WIDTH, 3), np.uint8) + np.frombuffer(digest[:3], np.uint8)
        cv2.imwrite(str(out), image)
        time.sleep(float(os.environ.get("ISU_TEST_RENDER_DELAY", "0")))
        if os.environ.get("ISU_TEST_UNUSABLE_WITH_CAN") and canonical.get("colacan_codriver_seat") == "YES":
            raise RenderError("unusable frame: black (test double)", image=out)
        ids = np.full((HEIGHT, WIDTH), INSTANCE_ID["cabin"], np.uint16)
        ids[8:28, 22:36] = INSTANCE_ID["driver"]
        ids[2:9, 25:32] = INSTANCE_ID["driver_face"]
        if canonical.get("luggage") == "YES":
            ids[14 + digest[3] % 8:26, 2 + digest[4] % 6:16] = INSTANCE_ID["luggage"]
        seg = out.with_name(out.stem + ".seg.png")
        cv2.imwrite(str(seg), ids)
        hidden = canonical.get("luggage") == "YES" and canonical.get("child_seat") == "YES"
        visibility = {k: (0.05 if hidden else 1.0) for k in ("luggage", "luggage_position", "luggage_colour")
                      if k in canonical and canonical.get("luggage") == "YES"}
        occluded = sorted(visibility) if hidden else []
        if os.environ.get("ISU_TEST_HIDE_PHONE") and canonical.get("phone_position", "NONE") != "NONE":
            visibility["phone_position"] = 0.02
            occluded = sorted([*occluded, "phone_position"])
        return RenderResult(image=out, channels={"seg": seg}, timings={"render_s": 0.0},
                            visibility=visibility, occluded=occluded)

    def close(self) -> None:
        pass


def renderer(space) -> SegPaintRenderer:
    return SegPaintRenderer(space)
