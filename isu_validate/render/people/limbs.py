"""Analytic inverse kinematics for anny's two-segment limbs (shoulder-elbow-wrist, hip-knee-ankle).

The limb is first evaluated with its own bones at rest (it follows the posed torso); from that
evaluation's joint positions the upper bone is turned so the elbow (knee) lands where a two-bone
solution puts it, keeping the joint's hinge axis, then the lower bone is bent about that hinge so
the end reaches its target. Exact up to the few millimetres by which anny's twist bones sit off the
limb's axis; ``solve`` repeats with the measured miss (two passes bring it under 1 mm)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skeleton import Posed, align, delta_for, rotation, swing_to


@dataclass(frozen=True)
class Limb:
    upper: str          # bone turned at the root joint (upperarm01 / upperleg01)
    lower: str          # bone bent at the middle joint (lowerarm01 / lowerleg01)
    end: str            # bone whose head is the end joint (wrist / foot)
    twist: str | None   # the lower segment's twist bone (lowerarm02), or None
    parent: str         # the upper bone's parent

    @staticmethod
    def arm(side: str) -> "Limb":
        return Limb(f"upperarm01.{side}", f"lowerarm01.{side}", f"wrist.{side}", f"lowerarm02.{side}",
                    f"shoulder01.{side}")

    @staticmethod
    def leg(side: str) -> "Limb":
        return Limb(f"upperleg01.{side}", f"lowerleg01.{side}", f"foot.{side}", None, f"pelvis.{side}")


def elbow_position(root, target, l1: float, l2: float, pole) -> tuple[np.ndarray, np.ndarray]:
    """(middle joint, reachable end) of a two-segment chain from root towards target, bending to pole."""
    span = target - root
    d = float(np.clip(np.linalg.norm(span), abs(l1 - l2) + 1e-4, l1 + l2 - 1e-4))
    u = span / np.linalg.norm(span)
    p = pole - u * (pole @ u)
    p /= np.linalg.norm(p)
    cos_a = (l1 * l1 + d * d - l2 * l2) / (2 * l1 * d)
    mid = root + (u * cos_a + p * np.sqrt(max(0.0, 1 - cos_a * cos_a))) * l1
    return mid, root + u * d


def reach(limb: Limb, rest: Posed, target, pole, end_rotation: np.ndarray | None = None,
          twist_share: float = 0.5) -> dict[str, np.ndarray]:
    """Pose deltas of the limb's bones that put its end joint at ``target`` (as far as it reaches),
    bending towards ``pole``; with ``end_rotation`` (a world rotation for the end bone, relative to
    following the forearm unchanged... given as the end bone's wanted world delta G) the end bone is
    turned to it, ``twist_share`` of its twist about the forearm taken by the twist bone."""
    S, E, W = rest.head(limb.upper), rest.head(limb.lower), rest.head(limb.end)
    G_p = rest.rot(limb.parent)
    u, f = E - S, W - E
    hinge = np.cross(u, f)
    E2, W2 = elbow_position(S, np.asarray(target, float), np.linalg.norm(u), np.linalg.norm(f), np.asarray(pole, float))
    hinge2 = np.cross(E2 - S, W2 - E2)
    if np.linalg.norm(hinge2) < 1e-9:   # fully stretched: keep the hinge as turned by the swing
        hinge2 = swing_to(u, E2 - S) @ hinge
    Q = align(u, hinge, E2 - S, hinge2)
    bend = swing_to(Q @ f, W2 - E2)
    G_upper, G_lower = Q @ G_p, bend @ Q @ G_p
    deltas = {limb.upper: delta_for(G_p, Q), limb.lower: delta_for(G_upper, bend)}
    if end_rotation is not None:
        X = end_rotation @ G_lower.T          # what the end bone turns by in the world, past the forearm
        axis = (W2 - E2) / np.linalg.norm(W2 - E2)
        twist_angle = _twist_angle(X, axis)
        G_twist = G_lower
        if limb.twist:
            T = rotation(axis, twist_angle * twist_share)
            deltas[limb.twist] = delta_for(G_lower, T)
            G_twist = T @ G_lower
        D = np.eye(4)
        D[:3, :3] = G_twist.T @ end_rotation
        deltas[limb.end] = D
    return deltas


def _twist_angle(X: np.ndarray, axis: np.ndarray) -> float:
    """The twist of rotation X about ``axis`` (swing-twist decomposition)."""
    from scipy.spatial.transform import Rotation
    q = Rotation.from_matrix(X).as_quat()      # x, y, z, w
    proj = axis * (q[:3] @ axis)
    return float(2 * np.arctan2(np.linalg.norm(proj) * np.sign(proj @ axis), q[3]))
