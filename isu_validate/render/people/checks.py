"""Measurements of a posed person against the cabin, from the cached state files alone (no anny): how
far the body keeps from the seat and the steering wheel, how the belt lies on the body, whether the
phone sits in the palm. Tests assert on them; ``isu-validate people check`` prints them for every body."""
from __future__ import annotations

import numpy as np

from ..cabin_geometry import DRINK_PROFILES, can_cylinder, drink_solid, phone_box, seat_boxes, wheel_solids
from .seated import shifted_seat
from .surface import Surface

LIES_ON = 0.015     # a strap point this close to the body rests on it


def driver_measures(state: dict, topology: dict, cabin: dict) -> dict[str, float]:
    """Clearances (m, negative = inside) and belt/phone figures of one posed driver."""
    v = state["vertices"].astype(np.float64)
    hands = topology["hands"].astype(bool)
    seat = shifted_seat(cabin["seats"]["driver"], float(state["seat_shift"]))
    out = {}
    for solid in seat_boxes("driver_seat", seat):
        out[f"clear_{solid.name.split('_', 2)[-1]}"] = float(solid.sdf(v).min())
    wheel = wheel_solids(cabin["steering_wheel"])
    out["clear_wheel_body"] = float(min(s.sdf(v[~hands]).min() for s in wheel))
    out["clear_wheel_hands"] = float(min(s.sdf(v[hands]).min() for s in wheel))
    out.update(belt_measures(state, topology))
    if "phone_centre" in state:
        out["phone_to_palm"] = float(np.linalg.norm(v[hands] - state["phone_centre"], axis=1).min())
        out.update(phone_grip_measures(v[hands], state["phone_centre"], state["phone_rotation"]))
    if "can_centre" in state:
        can = can_cylinder(state["can_centre"], state["can_rotation"])
        d = can.sdf(v[hands])
        out.update(can_clear_hand=float(d.min()), can_touch=float((d < 0.005).sum()),
                   can_clear_body=float(can.sdf(v[~hands]).min()))
        drinks = drink_measures(state, topology).values()    # isu-diverse's drinks held there: the worst
        out.update(drinks_clear_hand=min(d["clear_hand"] for d in drinks),
                   drinks_clear_body=min(d["clear_body"] for d in drinks))
    return out


def drink_measures(state: dict, topology: dict) -> dict[str, dict[str, float]]:
    """Per drink of ``cabin_geometry.DRINK_PROFILES`` held where the state's can is: its deepest point into
    the hand and into the rest of the body (m, negative = inside)."""
    v = state["vertices"].astype(np.float64)
    hands = topology["hands"].astype(bool)
    out = {}
    for kind in DRINK_PROFILES:
        solid = drink_solid(kind, state["can_centre"], state["can_rotation"])
        out[kind] = {"clear_hand": float(solid.sdf(v[hands]).min()), "clear_body": float(solid.sdf(v[~hands]).min())}
    return out


def phone_grip_measures(hand: np.ndarray, centre, rotation) -> dict[str, float]:
    """How the hand holds the phone: its deepest point into the phone (negative = inside), and how many
    of its vertices touch the phone's screen half (fingers or thumb round an edge; none when the phone
    only lies on an open palm)."""
    box = phone_box(centre, rotation)
    d = box.sdf(hand)
    front = (hand - np.asarray(centre, float)) @ np.asarray(rotation, float)[:, 2] > 0
    return {"phone_clear_hand": float(d.min()), "phone_front_touch": float(((d < 0.005) & front).sum())}


def belt_measures(state: dict, topology: dict) -> dict[str, float]:
    """For each strap: its deepest point into the body (the centre line's signed distance to the
    torso, pelvis and thighs; negative = through the body) and the share of its points resting on it."""
    surface = Surface(state["vertices"], topology["faces"], topology["carriers"].astype(bool))
    out = {}
    for strap in ("belt_diagonal", "belt_lap"):
        d = surface.distance(state[strap])
        inner = d[2:-2]                        # the ends are the anchor and the buckle
        out[f"{strap}_min"] = float(inner.min())
        out[f"{strap}_resting"] = float((inner < LIES_ON).mean())
    return out


def child_measures(state: dict, front_facing: bool, anchor) -> dict[str, float]:
    from .child import clearances
    from .skeleton import Posed
    posed = Posed(state["vertices"], np.zeros((0, 3)), np.zeros((0, 3, 3)), [])
    return {f"clear_{k}": v for k, v in clearances(posed, front_facing, anchor).items()}
