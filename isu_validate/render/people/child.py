"""The child in the child seat: a toddler anny body sitting upright in the front-facing seat (two and a
half years old), or a one-year-old lying reclined in the rear-facing carrier (its back on the carrier's
inclined plate, facing the rear), hands on the lap or the belly.

The seat's surfaces are ``cabin_geometry.child_seat_boxes``, which Blender builds too (local frame: the seat faces
+x, origin at the centre of its base, placed at the cabin rig's ``anchors.child_seat``)."""
from __future__ import annotations

import math

import numpy as np

from ..cabin_geometry import CARRIER_RECLINE_DEG, child_seat_boxes
from .limbs import Limb, reach
from .regions import bone_weights
from .skeleton import Body, Posed, rigid, rot_x, rot_z, rotation

GAP = 0.004
HIPS_ON_PLATE = -0.13      # the lying child's hip joints this far from the plate's middle, down the slope (m)


def _seated_legs() -> dict:
    """Sitting: thighs forward along the cushion, shins hanging over its edge."""
    d = {}
    for side, out in (("L", 1.0), ("R", -1.0)):
        d[f"upperleg01.{side}"] = rot_x(-82.0) @ rotation((0, 1, 0), math.radians(-6 * out))
        d[f"lowerleg01.{side}"] = rot_x(75.0)
        d[f"foot.{side}"] = rot_x(-10.0)
    return d


def _lying_legs() -> dict:
    """Lying in the carrier: hips and knees bent (legs drawn up)."""
    d = {}
    for side, out in (("L", 1.0), ("R", -1.0)):
        d[f"upperleg01.{side}"] = rot_x(-70.0) @ rotation((0, 1, 0), math.radians(-10 * out))
        d[f"lowerleg01.{side}"] = rot_x(75.0)
    return d


def _hands_on_lap(posed: Posed, front_facing: bool) -> dict:
    """Arms by inverse kinematics: hands resting on the thighs (sitting) or on the belly (lying)."""
    deltas = {}
    for side in ("L", "R"):
        hip, knee = posed.head(f"upperleg01.{side}"), posed.head(f"lowerleg01.{side}")
        centre = posed.head("root")
        outward = posed.head(f"upperarm01.{side}") - centre
        if front_facing:
            target = hip + 0.55 * (knee - hip) + np.array([0.0, 0.0, 0.06]) + (centre - hip) * np.array([0, 0.3, 0])
            pole = np.array([0.0, 0.0, -1.0]) + outward * 4.0          # elbows down by the sides
        else:
            up = posed.head("spine01") - centre
            front = np.cross(posed.head("upperarm01.L") - posed.head("upperarm01.R"), up)
            front /= np.linalg.norm(front)
            target = centre + 0.45 * up + front * 0.07 + (hip - centre) * 0.6
            pole = outward * 6.0 + front * 0.3                         # elbows out, off the plate
        deltas.update(reach(Limb.arm(side), posed, target, pole))
    return deltas


def pose_child(body: Body, front_facing: bool, anchor) -> Posed:
    """The child posed in its seat, in the cabin frame (the seat at ``anchor``, unturned)."""
    anchor = np.asarray(anchor, float)
    boxes = {b.name: b for b in child_seat_boxes(front_facing)}
    lower_legs = bone_weights(body.model, ("lowerleg", "foot", "toe")) > 0.5
    if front_facing:
        turn = rot_z(90.0) @ rot_x(-7.0)                 # faces +x, leaning on the back pad
        t = np.array([-0.02, 0.0, 0.26])
        legs = _seated_legs()
    else:
        # the body's up along the plate towards +x, its front along the plate's normal (up and back)
        turn = rotation((0, 1, 0), math.radians(90.0 - CARRIER_RECLINE_DEG)) @ rot_z(-90.0)
        t = np.array([0.0, 0.0, 0.40])
        legs = _lying_legs()
    deltas = {b: rigid(R) for b, R in legs.items()}
    deltas.update({"neck01": rigid(rot_x(3.0)), "head": rigid(rot_x(3.0))})
    for _ in range(5):   # arms follow the body, the body rests where arms and legs let it: settle in turns
        posed = body.evaluate({**deltas, "root": rigid(turn, anchor + t)})
        deltas_arms = _hands_on_lap(posed, front_facing)
        posed = body.evaluate({**deltas, **deltas_arms, "root": rigid(turn, anchor + t)})
        t = t + _settle(posed.vertices - anchor, boxes, front_facing, lower_legs, posed.head("root") - anchor)
    return body.evaluate({**deltas, **deltas_arms, "root": rigid(turn, anchor + t)})


def _settle(local: np.ndarray, boxes: dict, front_facing: bool, lower_legs: np.ndarray, hips) -> np.ndarray:
    """The shift that rests the child GAP above the seat surfaces it leans on (calves that would cut
    into the cushion's front move the child forward rather than up)."""
    if front_facing:
        upper = local[~lower_legs]
        dz = GAP - min(boxes["cs_cushion"].sdf(upper).min(), boxes["cs_base"].sdf(upper).min())
        lifted = local + np.array([0.0, 0.0, dz])
        back = boxes["cs_backpad"]
        dx = (GAP - min(back.sdf(lifted).min(), boxes["cs_back"].sdf(lifted).min())) / back.R[0, 0]
        calves = lifted[lower_legs] + np.array([dx, 0.0, 0.0])
        dx += max(boxes["cs_cushion"].push_out(calves, 0, GAP), boxes["cs_base"].push_out(calves, 0, GAP))
        return np.array([dx, 0.0, dz])
    # lying: slide down the plate until the hips are near its lower end, then rest the back on it
    pad = boxes["cs_platepad"]
    along, normal = pad.R[:, 0], pad.R[:, 2]
    slide = along * (HIPS_ON_PLATE - (hips - np.asarray(pad.centre)) @ along)
    moved = local + slide
    lift = GAP - min(pad.sdf(moved).min(), boxes["cs_plate"].sdf(moved).min())
    return slide + normal * lift


def clearances(posed: Posed, front_facing: bool, anchor) -> dict[str, float]:
    local = posed.vertices - np.asarray(anchor, float)
    return {b.name: float(b.sdf(local).min()) for b in child_seat_boxes(front_facing)}
