"""Which way the things the cabin rig places point in the frame: each one's top, as a unit vector in pixels.

Photo-trained classifiers learnt bottles standing; a bottle lying across a seat is a view they rarely saw.
The yardsticks read such a thing a second time, turned by the quarter turn that brings its top nearest to up
(as a face is aligned before its expression is read), and need to know where its top is: that is geometry the
renderer knows exactly (the rig's placement through the camera), so it goes into the render label beside
the boxes. Only the things on the co-driver seat have a pose the rig fixes; the phone in the hand follows
the hand, and the can is round (its top is noted all the same: a standing can is upright already)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .cabin import CODRIVER_SEAT_OBJECTS

# the thing's own axis towards its top (rigs/cabins/default.toml: the phone's top at local +y, the can and
# the bottle standing on their base along local +z)
TOP_AXIS = {"phone_codriver_seat": (0.0, 1.0, 0.0), "colacan_codriver_seat": (0.0, 0.0, 1.0),
            "colabottle_codriver_seat": (0.0, 0.0, 1.0)}
STEP_M = 0.02    # the top is projected from the thing's origin to a point this far along its axis
FORESHORTENED = 0.2   # an axis shorter in the frame than this share of its side-on length points at the lens


def seat_objects_up(cabin: dict, camera) -> dict[str, list[float]]:
    """{instance: [dx, dy]}: the image direction (x right, y down, unit length) of the top of each thing the
    cabin places on the co-driver seat, through ``camera`` (a ``capture.camera.Camera``). A thing whose
    axis points (almost) at the camera has no direction in the frame and is left out."""
    out = {}
    for name in CODRIVER_SEAT_OBJECTS:
        spec = cabin["codriver_seat"][name]
        origin = np.asarray(spec["position"], dtype=float)
        # Blender's XYZ Euler (rotate about X, then Y, then Z in the world frame): scipy's extrinsic "xyz"
        axis = Rotation.from_euler("xyz", spec["rotation_deg"], degrees=True).apply(TOP_AXIS[name])
        uv = camera.project(np.stack([origin, origin + STEP_M * axis]))
        step = uv[1] - uv[0]
        length = float(np.hypot(*step))
        side_on = STEP_M * camera.fx / float(camera.to_camera(origin)[0, 2])
        if np.isfinite(length) and length > FORESHORTENED * side_on:
            out[name] = [round(float(step[0]) / length, 4), round(float(step[1]) / length, 4)]
    return out
