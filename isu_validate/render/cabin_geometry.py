"""Solid shapes of the procedural cabin that people touch (seats, steering wheel), in the cabin frame,
with signed distances: the Blender builder makes its meshes from them, the people's posing sits
bodies on them, and tests measure interpenetration against them. No bpy here."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Box:
    """An oriented box: centre, full size along its local axes, rotation (columns = local axes)."""
    name: str
    centre: tuple
    size: tuple
    R: np.ndarray
    rounded: float = 0.0     # bevel as a share of the unit cube (the rendered box lies inside this one)

    def sdf(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m) of each point to the (sharp) box: negative inside."""
        local = (np.asarray(points, float) - np.asarray(self.centre)) @ self.R
        q = np.abs(local) - np.asarray(self.size) / 2
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
        return outside + np.minimum(q.max(axis=-1), 0.0)

    def push_out(self, points: np.ndarray, axis: int, gap: float) -> float:
        """How far to move the points along the box's local axis ``axis`` (positive direction) for all of
        them to clear its face on that side by ``gap`` (0 when none is closer than ``gap``)."""
        points = np.asarray(points, float)
        near = self.sdf(points) < gap
        if not near.any():
            return 0.0
        local = (points[near] - np.asarray(self.centre)) @ self.R
        return float(max(0.0, (self.size[axis] / 2 + gap - local[:, axis]).max()))


def _along_and_off(points: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each point's signed distance along the unit ``axis`` from ``origin``, and its distance from that axis."""
    q = np.asarray(points, float) - origin
    h = q @ axis
    return h, np.linalg.norm(q - h[..., None] * axis, axis=-1)


@dataclass(frozen=True)
class Torus:
    """The steering wheel's rim: centre, unit normal of its plane, major and tube radius."""
    name: str
    centre: np.ndarray
    normal: np.ndarray
    radius: float
    tube: float

    def sdf(self, points: np.ndarray) -> np.ndarray:
        h, off = _along_and_off(points, self.centre, self.normal)
        return np.hypot(off - self.radius, h) - self.tube


@dataclass(frozen=True)
class Capsule:
    """A cylinder with round ends (spokes, hub, column: conservative stand-ins for their shapes)."""
    name: str
    a: np.ndarray
    b: np.ndarray
    radius: float

    def sdf(self, points: np.ndarray) -> np.ndarray:
        p = np.asarray(points, float)
        ab = self.b - self.a
        t = np.clip(((p - self.a) @ ab) / (ab @ ab), 0.0, 1.0)
        return np.linalg.norm(p - (self.a + t[..., None] * ab), axis=-1) - self.radius


@dataclass(frozen=True)
class Cylinder:
    """A capped cylinder from its base centre along ``axis`` (a unit vector): a can in the hand."""
    name: str
    base: np.ndarray
    axis: np.ndarray
    radius: float
    height: float

    def sdf(self, points: np.ndarray) -> np.ndarray:
        h, off = _along_and_off(points, self.base, self.axis)
        radial = off - self.radius
        along = np.abs(h - self.height / 2) - self.height / 2
        outside = np.hypot(np.maximum(radial, 0.0), np.maximum(along, 0.0))
        return outside + np.minimum(np.maximum(radial, along), 0.0)


@dataclass(frozen=True)
class Lathe:
    """A solid of revolution: the (radius, height) ``profile`` (from the axis at the base round to the axis
    at the top) turned round ``axis`` from ``base``: a drink in the hand."""
    name: str
    base: np.ndarray
    axis: np.ndarray
    profile: tuple

    def sdf(self, points: np.ndarray) -> np.ndarray:
        """Signed distance to the profile's outline in each point's (radius, height) half-plane (the axis is no
        surface): exact for a solid of revolution; negative inside."""
        h, off = _along_and_off(points, self.base, self.axis)
        q = np.stack([off, h], axis=-1)[:, None, :]                  # points x 1 x 2
        a = np.asarray(self.profile[:-1], float)[None]               # 1 x edges x 2
        b = np.asarray(self.profile[1:], float)[None]
        ab = b - a
        t = np.clip(((q - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-18), 0.0, 1.0)
        distance = np.linalg.norm(q - (a + t[..., None] * ab), axis=-1).min(axis=1)
        # inside: a ray from the point outwards in radius crosses the outline an odd number of times
        za, zb = a[..., 1], b[..., 1]
        spans = (za <= q[..., 1]) != (zb <= q[..., 1])
        r_cross = a[..., 0] + (q[..., 1] - za) / np.where(zb == za, 1.0, zb - za) * ab[..., 0]
        inside = ((spans & (r_cross > q[..., 0])).sum(axis=1) % 2) == 1
        return np.where(inside, -distance, distance)


def rot_y(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


RIM_TUBE = 0.12   # tube radius of the rim as a share of the wheel's radius
PHONE_SIZE = (0.074, 0.152, 0.0085)   # the smartphone: width (local x), length (y), thickness (z, screen on +z)


def phone_box(centre, R) -> Box:
    """The phone held or lying at ``centre``, turned by ``R``: what fingers close on."""
    return Box("phone", tuple(np.asarray(centre, float)), PHONE_SIZE, np.asarray(R, float), rounded=0.15)


CAN_RADIUS, CAN_HEIGHT = 0.033, 0.116   # the 330 ml can (on the co-driver seat, or held to drink from)


def can_cylinder(centre, R) -> Cylinder:
    """The can held at ``centre`` (its middle), its axis (base to top) along ``R``'s local z."""
    axis = np.asarray(R, float)[:, 2]
    return Cylinder("can", np.asarray(centre, float) - axis * CAN_HEIGHT / 2, axis, CAN_RADIUS, CAN_HEIGHT)


# The drinks a hand holds (isu-diverse's `drink`): (radius, height) outlines in the can's frame (its base at 0,
# its top at CAN_HEIGHT), each about the can's radius where the hand closes round the can's middle, so that one
# grip (``can_cylinder``) holds them all. A cup's rim is wider than a can's top and a bottle reaches lower: the
# tests measure each against the face it is held to (tests/test_people.py).
DRINK_PROFILES = {
    "CAN": ((0.0, 0.004), (0.026, 0.0), (0.031, 0.003), (CAN_RADIUS, 0.010), (CAN_RADIUS, 0.104), (0.0295, 0.113),
            (0.0285, CAN_HEIGHT), (0.0, CAN_HEIGHT)),
    # a 240 ml paper or foam cup: tapered, a rolled rim, the coffee 1.5 cm below it
    "CUP": ((0.0, 0.010), (0.0255, 0.008), (0.0385, 0.100), (0.0400, 0.101), (0.0400, 0.104), (0.0375, 0.105),
            (0.0360, 0.098), (0.0345, 0.088), (0.0, 0.088)),
    # the same cup under a take-away lid with a raised sipping rim
    "COFFEE": ((0.0, 0.010), (0.0255, 0.008), (0.0385, 0.100), (0.0405, 0.101), (0.0405, 0.106), (0.0340, 0.109),
               (0.0320, 0.113), (0.0, 0.113)),
    # a 500 ml water bottle held round its upper body: the cap at the lips, the rest below the hand
    "WATER": ((0.0, -0.066), (0.026, -0.066), (0.0310, -0.060), (0.0310, 0.072), (0.0270, 0.086), (0.0160, 0.096),
              (0.0125, 0.099), (0.0125, 0.102), (0.0150, 0.102), (0.0150, 0.116), (0.0, 0.116)),
    # a steel travel mug under a black lid with its sipping spout
    "MUG": ((0.0, -0.050), (0.0295, -0.050), (0.0335, -0.046), (0.0335, 0.092), (0.0350, 0.094), (0.0350, 0.106),
            (0.0300, 0.112), (0.0, 0.113)),
}


def drink_solid(kind: str, centre, R) -> Lathe:
    """The drink ``kind`` held as ``can_cylinder`` holds the can (its middle at ``centre``, its top along R's z)."""
    axis = np.asarray(R, float)[:, 2]
    return Lathe(kind, np.asarray(centre, float) - axis * CAN_HEIGHT / 2, axis, DRINK_PROFILES[kind])


CARRIER_RECLINE_DEG = 35.0   # the rear-facing carrier's back plate, from the horizontal
CHILD_SEAT_PADS = ("cs_cushion", "cs_backpad", "cs_platepad")   # fabric; the other parts are the plastic shell


def child_seat_boxes(front_facing: bool) -> list[Box]:
    """The child seat's shell and pads in its local frame (facing +x, origin at the centre of its base),
    in the order Blender builds them. Front-facing: an upright booster with
    a tall back and side wings; rear-facing: a reclined infant carrier (its carry handle, which the
    child never touches, is built in Blender only)."""
    if front_facing:
        tilt = rot_y(-0.12)
        boxes = [Box("cs_base", (0.0, 0.0, 0.07), (0.42, 0.42, 0.14), np.eye(3), 0.1),
                 Box("cs_cushion", (0.03, 0.0, 0.16), (0.34, 0.32, 0.06), np.eye(3), 0.3),
                 Box("cs_back", (-0.17, 0.0, 0.44), (0.08, 0.40, 0.62), tilt, 0.2),
                 Box("cs_backpad", (-0.12, 0.0, 0.42), (0.03, 0.30, 0.52), tilt, 0.3)]
        for side in (1, -1):
            boxes += [Box(f"cs_wing{side}", (-0.06, side * 0.20, 0.33), (0.26, 0.05, 0.34), np.eye(3), 0.2),
                      Box(f"cs_headwing{side}", (-0.12, side * 0.17, 0.66), (0.18, 0.05, 0.20), np.eye(3), 0.2)]
        return boxes
    recline = rot_y(-math.radians(CARRIER_RECLINE_DEG))
    return [Box("cs_base", (0.0, 0.0, 0.06), (0.46, 0.40, 0.12), np.eye(3), 0.1),
            Box("cs_plate", (0.04, 0.0, 0.26), (0.56, 0.38, 0.06), recline, 0.2),
            Box("cs_platepad", (0.02, 0.0, 0.29), (0.50, 0.30, 0.03), recline, 0.3),
            Box("cs_side1", (0.02, 0.19, 0.30), (0.52, 0.04, 0.20), recline, 0.2),
            Box("cs_side-1", (0.02, -0.19, 0.30), (0.52, 0.04, 0.20), recline, 0.2)]


def pitch(box: Box) -> float:
    """The angle about y of a box that turns about y only (as Blender's Euler y)."""
    return math.atan2(-box.R[2, 0], box.R[0, 0])


def seat_boxes(name: str, seat: dict) -> list[Box]:
    """Cushion, base, tilted backrest and headrest(s) from the rig's cushion top-centre point."""
    cx, cy, cz = seat["cushion"]
    w, d, bh = seat["width"], seat["depth"], seat["back_height"]
    tilt = math.radians(seat["back_tilt_deg"])
    R = rot_y(-tilt)
    back_base = np.array([cx - d / 2 + 0.05, cy, cz])
    back_dir = np.array([-math.sin(tilt), 0, math.cos(tilt)])
    back_centre = back_base + back_dir * (bh / 2) + np.array([-0.06, 0, 0])
    boxes = [Box(f"{name}_cushion", (cx, cy, cz - 0.07), (d, w, 0.14), np.eye(3), 0.18),
             Box(f"{name}_base", (cx, cy, (cz - 0.14) / 2), (d * 0.8, w * 0.8, cz - 0.14), np.eye(3)),
             Box(f"{name}_back", tuple(back_centre), (0.13, w, bh), R, 0.18)]
    heads = [cy] if w < 0.8 else [cy - w / 3, cy + w / 3, cy]
    for i, hy in enumerate(heads):
        top = back_base + back_dir * (bh + 0.1) + np.array([-0.07, hy - cy, 0])
        boxes.append(Box(f"{name}_headrest{i}", tuple(top), (0.1, 0.26, 0.18), R, 0.3))
    return boxes


def wheel_frame(wheel: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(centre, lateral axis, up-in-rim-plane axis, normal towards the driver) of the steering wheel.
    As in a real car, the rim's top leans away from the driver (``tilt_deg`` from vertical) and its face
    turns up towards the chest; seen from beside the car, its face shows as an open ring."""
    tilt = math.radians(wheel["tilt_deg"])
    return (np.asarray(wheel["centre"], float), np.array([0.0, 1.0, 0.0]),
            np.array([math.sin(tilt), 0.0, math.cos(tilt)]), np.array([-math.cos(tilt), 0.0, math.sin(tilt)]))


def wheel_solids(wheel: dict) -> list:
    """Rim, hub, spokes and column of the steering wheel, as built by the Blender cabin."""
    centre, e_y, e_up, normal = wheel_frame(wheel)
    r = wheel["radius"]
    solids = [Torus("wheel_rim", centre, normal, r, r * RIM_TUBE),
              Capsule("wheel_hub", centre - normal * 0.03, centre + normal * 0.03, r * 0.35),
              Capsule("wheel_column", centre - normal * 0.02, centre - normal * 0.3, 0.04)]
    for k, ang in enumerate((90, 270, 180)):
        a = math.radians(ang)
        solids.append(Capsule(f"wheel_spoke{k}", centre, centre + (e_y * math.cos(a) + e_up * math.sin(a)) * r, 0.03))
    return solids


def rim_point(wheel: dict, clock_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A point on the rim's centre line at an angle from 3 o'clock (counter-clockwise as the driver
    sees it, towards +y = the driver's left), with the rim's tangent there and the outward radial."""
    centre, e_y, e_up, _ = wheel_frame(wheel)
    a = math.radians(clock_deg)
    radial = -e_y * math.cos(a) + e_up * math.sin(a)     # 3 o'clock is the driver's right (-y)
    tangent = e_y * math.sin(a) + e_up * math.cos(a)
    return centre + radial * wheel["radius"], tangent, radial
