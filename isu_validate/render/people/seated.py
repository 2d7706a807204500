"""The driver's pose in the cabin rig: seated on the driver's seat (resting on the cushion and the
backrest, clear of both; the seat slid on its track until the wheel is in reach),
feet towards the pedals, hands on the steering wheel at ten and two, or
one hand holding the phone at one of the rig's phone positions P1-P10 (reached by inverse kinematics,
the phone placed in the posed palm), and a free hand off the wheel at one of the rig's hand positions
(on the lap, at the console, at the face, a can to the mouth...: what hands do besides holding a phone), the
head turned to where the driver looks (the road, down at the hands, the passenger, the mirror) with what is
held at the head turning with it.

anny's frame (Z up, the body faces -Y, its left is +X) is turned into the cabin's (x forward, y left,
z up) by the root bone's world pose, so every joint is solved directly in cabin coordinates."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..cabin_geometry import CAN_RADIUS, PHONE_SIZE, RIM_TUBE, can_cylinder, phone_box, rim_point, seat_boxes
from .hands import FINGERS, HandFrame, close_on, hand_frame, turn_to, wrap
from .limbs import Limb, reach
from .regions import bone_weights
from .skeleton import Body, Posed, align, delta_for, rigid, rot_x, rot_z, rotation

GAP = 0.004              # clearance between the body and the seat it rests on (m)
RECLINE_DEG = 14.0       # the torso leans back with the backrest (17 deg): a little upright of it
GRIP_CLOCK = {"L": 150.0, "R": 30.0}   # ten and two: angles from three o'clock
PHONE_ALONG = 0.85                     # the phone's middle lies across the palm this far from wrist to knuckles
PHONE_SHIFT = 0.03                     # ... and this far towards its top from the hand's middle (m)
CAN_ALONG = 0.7                        # a held can's axis crosses the hand this far from wrist to knuckles
PALM_HALF = 0.014                      # from the hand's axis to the palm's surface (m)
GRIP_PALM = 0.036                      # the hand's axis this far off the rim's surface (m)
GRIP_ALONG = 0.55                      # the rim crosses the hand this far from wrist to knuckles
# the forearm comes to the rim from below and behind, rising this steeply (forward and up in the cabin frame):
# elbows low, as drivers hold a wheel whose face turns up to them
FOREARM_RISE = np.array([math.cos(math.radians(50.0)), 0.0, math.sin(math.radians(50.0))])
SKIN_GAP = 0.016                       # finger joints wrap this far outside the rim (half a finger's thickness)
ANKLE_HEIGHT = 0.11      # ankle joints above the floor (heels on it)
PEDAL_X = 0.56           # feet no further forward than the pedals (the footwell ends at the dashboard)
PHONE_THICKNESS = PHONE_SIZE[2]
SIDE = {"left": "L", "right": "R"}      # the driver's left hand is anny's .L (towards cabin +y)
SEAT_TRACK = (-0.08, 0.22)   # the seat slides this far back/forward to fit the driver (m)
REACH = 0.86                 # shoulder to palm at this share of the arm's length: elbows a little bent
HEAD_SHARE = 0.8             # the head turns this share of the way to what the driver looks at (the eyes the rest)
HEAD_MAX_DEG = {"yaw": 60.0, "down": 35.0, "up": 15.0}   # ... at most this far from looking at the road
HOLDING_MAX_DEG = {"yaw": 30.0, "down": 15.0, "up": 15.0}   # ... less far with a hand at the head, which turns
                                                            # with it (further, the elbow meets the backrest)
NECK_SHARES = {"neck01": 0.3, "neck02": 0.3, "head": 0.4}  # how the turn is spread down the neck
FACING = np.array([0.0, -1.0, 0.0])   # where anny's head faces in its reference pose


@dataclass
class DriverPose:
    posed: Posed
    deltas: dict
    phone: tuple[np.ndarray, np.ndarray] | None      # (centre, 3x3 rotation) of the phone in the hand
    head_centre: np.ndarray
    seat_shift: float     # how far the seat was slid forward on its track (m)
    can: tuple[np.ndarray, np.ndarray] | None = None  # (centre, 3x3 rotation, local z base to top) of a held can


def anny_to_cabin() -> np.ndarray:
    """anny forward (-Y) -> cabin +x, anny left (+X) -> cabin +y."""
    return rot_z(90.0)


def seat_and_pose(body: Body, rig: dict, phone_position: str = "NONE", hands: str = "WHEEL",
                  gaze: str = "ROAD", phone_tilt: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> DriverPose:
    """Seat the body, slide the seat on its track until the wheel is in reach, turn the head to ``gaze`` (a rig
    gaze target; ROAD: eyes on the road), then place the hands: ``hands`` names a rig hand position for one hand
    (WHEEL: both on the wheel); the phone's hand wins. ``phone_tilt`` (tip, roll, turn in degrees) turns the
    phone in the hand from the rig's angle (``tilted``), the hand turning with it."""
    free = rig.get("hand_positions", {}).get(hands)
    if hands != "WHEEL" and free is None:
        raise ValueError(f"the cabin rig has no [hand_positions.{hands}]; known: WHEEL, "
                         f"{', '.join(rig.get('hand_positions', {})) or 'none'} (see rigs/cabins/default.toml)")
    look = rig.get("gaze_targets", {}).get(gaze)
    if gaze != "ROAD" and look is None:
        raise ValueError(f"the cabin rig has no [gaze_targets.{gaze}]; known: ROAD, "
                         f"{', '.join(rig.get('gaze_targets', {})) or 'none'} (see rigs/cabins/default.toml)")
    shift = 0.0
    for _ in range(2):    # sliding the seat can move the driver on the cushion: measure again once
        deltas, rest = _sit(body, rig, shift)
        shift = float(np.clip(shift + _track_shift(rest, rig), *SEAT_TRACK))
    deltas, rest = _sit(body, rig, shift)
    head_centre = _head_centre(rest)
    spec = tilted(rig["phone_positions"].get(phone_position), phone_tilt)
    if look:
        at_head = any(s and s["relative_to"] == "head" for s in (spec, free))
        turn, neck = _head_turn(rest, deltas, body.parent, _gaze_point(rest, look, (spec, free), rig, head_centre),
                                HOLDING_MAX_DEG if at_head else HEAD_MAX_DEG)
        deltas = {**deltas, **neck}
        rest = body.evaluate(deltas)
        head_centre = _head_centre(rest, turn)
        spec, free = _turned(spec, turn), _turned(free, turn)
    grips = {side: _wheel_grip(rest, side, rig) for side in ("L", "R")}
    if free:
        grips[SIDE[free["hand"]]] = _free_grip(rest, SIDE[free["hand"]], free, rig, head_centre)
    if spec:
        grips[SIDE[spec["hand"]]] = _phone_grip(rest, SIDE[spec["hand"]], spec, rig, head_centre)
    for _ in range(2):   # anny's twist bones sit a few mm off the arm's axis: correct by the measured miss
        arm = {}
        for side, grip in grips.items():
            arm.update(_arm(rest, side, grip))
        posed = body.evaluate({**deltas, **arm})
        for side, grip in grips.items():
            grip.palm_target = grip.palm_target + grip.palm_target - hand_frame(posed, side).palm(grip.along)
    # hands close round the rim, the phone or the can, measured on the posed hand with straight fingers
    straight = body.evaluate({**deltas, **{b: m for b, m in arm.items() if not b.startswith("finger")}})
    phone = can = None
    for side, grip in grips.items():
        if grip.holds == "wheel":
            point, tangent, _ = rim_point(rig["steering_wheel"], GRIP_CLOCK[side])
            arm.update(wrap(straight, side, point, tangent, rig["steering_wheel"]["radius"] * RIM_TUBE + SKIN_GAP))
        elif grip.holds == "phone":
            frame = hand_frame(straight, side)
            phone = _phone_in(frame, spec, _palm_skin(straight, frame, side, body.model))
            arm.update(close_on(straight, side, phone_box(*phone).sdf, frame.p))
        elif grip.holds == "can":
            frame = hand_frame(straight, side)
            can = _can_in(frame, _palm_skin(straight, frame, side, body.model, CAN_ALONG, CAN_RADIUS))
            arm.update(close_on(straight, side, can_cylinder(*can).sdf, frame.p))
    posed = body.evaluate({**deltas, **arm})
    return DriverPose(posed, {**deltas, **arm}, phone, head_centre, shift, can)


def shifted_seat(seat: dict, shift: float) -> dict:
    """The driver's seat slid ``shift`` metres forward on its track."""
    cx, cy, cz = seat["cushion"]
    return {**seat, "cushion": [cx + shift, cy, cz]}


def _sit(body: Body, rig: dict, shift: float) -> tuple[dict, Posed]:
    """Torso and legs seated on the (shifted) seat: resting on the cushion and against the backrest."""
    seat = shifted_seat(rig["seats"]["driver"], shift)
    boxes = {b.name.split("_", 2)[-1]: b for b in seat_boxes("driver_seat", seat)}
    base = _torso(RECLINE_DEG)
    turn = anny_to_cabin() @ rot_x(-RECLINE_DEG)
    t = np.array([seat["cushion"][0] - 0.12, seat["cushion"][1], seat["cushion"][2] + 0.10])
    lower_legs = bone_weights(body.model, ("lowerleg", "foot", "toe")) > 0.5
    for _ in range(4):   # legs follow the hips, the hips rest on what the legs leave: settle in turns
        deltas = {**base, "root": rigid(turn, t)}
        deltas.update(_legs(body.evaluate(deltas), rig))
        t = t + _settle(body.evaluate(deltas).vertices, boxes, lower_legs)
    deltas = {**base, "root": rigid(turn, t)}
    deltas.update(_legs(body.evaluate(deltas), rig))
    return deltas, body.evaluate(deltas)


def _track_shift(rest: Posed, rig: dict) -> float:
    """How far forward the seat must slide for both palms to reach their grips at REACH of the arm."""
    need = -np.inf
    for side in ("L", "R"):
        S, E, W = (rest.head(f"{b}.{side}") for b in ("upperarm01", "lowerarm01", "wrist"))
        arm = np.linalg.norm(E - S) + np.linalg.norm(W - E) + GRIP_ALONG * hand_frame(rest, side).length
        grip = _wheel_grip(rest, side, rig).palm_target
        d = grip - S
        along = np.sqrt(max((REACH * arm) ** 2 - d[1] ** 2 - d[2] ** 2, 0.0))
        need = max(need, d[0] - along)
    return float(need)


# ---------------------------------------------------------------------- torso, legs, seat
SLUMP_DEG = 10.0   # the upper back rounds forward this much over three vertebrae


def _torso(recline: float) -> dict:
    """Spine and neck: a slight slump of the upper back, the neck bringing the head back level, eyes
    on the road (the rest of the recline taken out over neck and head)."""
    level = recline - SLUMP_DEG
    d = {"spine03": rot_x(0.4 * SLUMP_DEG), "spine02": rot_x(0.4 * SLUMP_DEG), "spine01": rot_x(0.2 * SLUMP_DEG),
         "neck01": rot_x(0.5 * level), "neck02": rot_x(0.3 * level), "head": rot_x(0.2 * level)}
    return {bone: rigid(R) for bone, R in d.items()}


def _legs(rest: Posed, rig: dict) -> dict:
    """Both legs from the hips to ankles above the floor towards the pedals, knees up, feet forward."""
    deltas = {}
    for side in ("L", "R"):
        limb = Limb.leg(side)
        hip = rest.head(limb.upper)
        l1 = np.linalg.norm(rest.head(limb.lower) - hip)
        l2 = np.linalg.norm(rest.head(limb.end) - rest.head(limb.lower))
        dz = hip[2] - ANKLE_HEIGHT
        forward = math.sqrt(max((0.9 * (l1 + l2)) ** 2 - dz * dz, 0.05))
        ankle = np.array([min(hip[0] + forward, PEDAL_X), hip[1] + (0.03 if side == "L" else -0.03), ANKLE_HEIGHT])
        foot_dir = rest.head(f"toe3-1.{side}") - rest.head(f"foot.{side}")
        Z = align(foot_dir, np.array([0.0, 1.0, 0.0]), np.array([0.9, 0.0, -0.42]), np.array([0.0, 1.0, 0.0]))
        deltas.update(reach(limb, rest, ankle, pole=np.array([1.0, 0.0, 1.0]),
                            end_rotation=Z @ rest.rot(limb.end)))
    return deltas


def _settle(vertices: np.ndarray, boxes: dict, lower_legs: np.ndarray) -> np.ndarray:
    """The shift that puts the body GAP above the cushion and GAP in front of the backrest/headrest.
    Calves that would cut into the cushion's front (a short driver on a deep cushion) move the driver
    forward on the cushion, away from the backrest, rather than lifting the whole body."""
    cushion, back = boxes["cushion"], boxes["back"]
    rests = [b for name, b in boxes.items() if name == "back" or name.startswith("headrest")]
    upper = vertices[~lower_legs]
    dz = GAP - cushion.sdf(upper).min()
    normal = back.R[:, 0]                                  # the backrest's front normal
    lifted = vertices + np.array([0.0, 0.0, dz])
    dx = (GAP - min(b.sdf(lifted).min() for b in rests)) / normal[0]
    calves = lifted[lower_legs] + np.array([dx, 0.0, 0.0])
    dx += cushion.push_out(calves, 0, GAP)
    return np.array([dx, 0.0, dz])


def _head_centre(posed: Posed, turn: np.ndarray | None = None) -> np.ndarray:
    """Centre of the head: midway between the ears, at eye level, a little behind the eyes (``turn``: how the
    head is turned from looking at the road)."""
    behind = np.array([-0.07, 0.0, -0.01])
    return _eyes(posed) + (behind if turn is None else turn @ behind)


def _eyes(posed: Posed) -> np.ndarray:
    """Midway between the eyes."""
    return (posed.head("eye.L") + posed.head("eye.R")) / 2


# ---------------------------------------------------------------------- where the driver looks
def _gaze_point(rest: Posed, look: dict, held: tuple, rig: dict, head_centre: np.ndarray) -> np.ndarray:
    """The point a rig gaze target looks at: with ``at_hands``, the phone or else the free hand when it is held
    below the head (``held``: the phone position's and the hand position's specs, None when not used)."""
    if look.get("at_hands"):
        for spec in held:
            if spec and spec["relative_to"] != "head":
                return _reference(rest, spec, rig, head_centre) + np.asarray(spec["offset"], float)
    return _reference(rest, look, rig, head_centre) + np.asarray(look["offset"], float)


def _head_turn(rest: Posed, deltas: dict, parent: dict, target: np.ndarray,
               max_deg: dict) -> tuple[np.ndarray, dict]:
    """The head's world rotation towards ``target`` (HEAD_SHARE of the way: first down or up, then round the
    vertical, within ``max_deg``) and the neck and head deltas that make it, spread over NECK_SHARES on top of
    the seated ones (every share about the same axis, so each bone adds its own share: skeleton.delta_for)."""
    from scipy.spatial.transform import Rotation
    face, want = rest.rot("head") @ FACING, _unit(target - _eyes(rest))
    limit = {k: math.radians(v) for k, v in max_deg.items()}
    yaw = np.clip(HEAD_SHARE * _wrapped(_heading(want) - _heading(face)), -limit["yaw"], limit["yaw"])
    pitch = np.clip(HEAD_SHARE * (_elevation(want) - _elevation(face)), -limit["down"], limit["up"])
    turn = rotation((0, 0, 1), yaw) @ rotation(np.cross(face, (0.0, 0.0, 1.0)), pitch)
    axis_angle = Rotation.from_matrix(turn).as_rotvec()
    neck = {}
    for bone, share in NECK_SHARES.items():
        D = np.asarray(deltas.get(bone, np.eye(4)), float).copy()
        Q = Rotation.from_rotvec(share * axis_angle).as_matrix()
        D[:3, :3] = delta_for(rest.rot(parent[bone]), Q)[:3, :3] @ D[:3, :3]
        neck[bone] = D
    return turn, neck


def tilted(spec: dict | None, tilt_deg) -> dict | None:
    """A phone position turned in the hand from the rig's angle by ``tilt_deg`` = (tip, roll, turn) degrees: about
    the phone's width (its top towards the screen's side), its length and its screen's normal (in the screen's
    plane), each scaled by the position's ``tilt`` shares (at the ear the phone lies against the cheek: it only
    turns along it). Real drivers hold a phone at any angle; the rig's is one of them."""
    if not spec or not any(tilt_deg):
        return spec
    tip, roll, turn = (float(d) * share for d, share in zip(tilt_deg, spec.get("tilt", (1.0, 1.0, 1.0))))
    local = rot_z(turn) @ rot_x(tip) @ rotation((0, 1, 0), math.radians(roll))
    return {**spec, "rotation": _spec_rotation(spec) @ local}


def _turned(spec: dict | None, turn: np.ndarray) -> dict | None:
    """A phone or hand position held at the head, turned with it: its offset, directions and rotation."""
    if not spec or spec["relative_to"] != "head":
        return spec
    out = {**spec, "offset": turn @ np.asarray(spec["offset"], float)}
    out.update({k: turn @ np.asarray(spec[k], float) for k in ("palm", "fingers") if k in spec})
    if "rotation_deg" in spec:
        out["rotation"] = turn @ _spec_rotation(spec)
    return out


def _heading(v: np.ndarray) -> float:
    return float(np.arctan2(v[1], v[0]))


def _elevation(v: np.ndarray) -> float:
    return float(np.arctan2(v[2], np.hypot(v[0], v[1])))


def _wrapped(angle: float) -> float:
    return float((angle + np.pi) % (2 * np.pi) - np.pi)


# ---------------------------------------------------------------------- hands and arms
@dataclass
class Grip:
    """Where a hand goes: a point on the hand's axis (``along`` its length from the wrist) to put at
    ``palm_target``, the hand's wanted world rotation delta and its turned long axis; the fingers close
    afterwards, on the posed hand (``wrap`` on the rim, ``close_on`` on the phone)."""
    palm_target: np.ndarray
    G_hand: np.ndarray
    a: np.ndarray
    along: float
    holds: str            # "wheel", "phone", "can" or "nothing" (an open hand: its fingers stay straight)


def _wheel_grip(rest: Posed, side: str, rig: dict) -> Grip:
    """A fist round the rim at ten (left hand) or two (right hand): the knuckle line along the rim,
    the palm against its outer side, fingers wrapping to the front (closed round it by ``wrap``)."""
    point, tangent, radial = rim_point(rig["steering_wheel"], GRIP_CLOCK[side])
    a = _unit(FOREARM_RISE * 0.75 - radial * 0.35)      # from the wrist up over the rim towards the dashboard
    a = _unit(a - tangent * (a @ tangent))
    p = _unit(np.cross(a, tangent))
    if p @ (-radial) < 0:                               # the palm faces the wheel's centre
        p = -p
    tube = rig["steering_wheel"]["radius"] * RIM_TUBE
    return _grip(rest, side, a, p, point - p * (tube + GRIP_PALM), GRIP_ALONG, "wheel")


def _phone_grip(rest: Posed, side: str, spec: dict, rig: dict, head_centre: np.ndarray) -> Grip:
    """The phone's back in the palm, its lower half in the hand: the hand lies across the phone's width,
    pointing away from the shoulder (a right hand reading closes round the phone's left edge, seen from
    the screen) or as near the rig's ``fingers`` direction as it can, the phone's top beyond the hand."""
    R = _spec_rotation(spec)
    xp, yp, zp = R[:, 0], R[:, 1], R[:, 2]
    centre = _reference(rest, spec, rig, head_centre) + np.asarray(spec["offset"], float)
    away = np.asarray(spec.get("fingers", centre - rest.head(f"upperarm01.{side}")), float)
    a = xp if xp @ away > 0 else -xp
    palm = centre - zp * (PHONE_THICKNESS / 2 + PALM_HALF) - yp * PHONE_SHIFT
    return _grip(rest, side, a, zp, palm, PHONE_ALONG, "phone")


def _free_grip(rest: Posed, side: str, spec: dict, rig: dict, head_centre: np.ndarray) -> Grip:
    """A hand off the wheel: the palm's middle at the rig's point, facing ``palm``, the fingers towards
    ``fingers``; empty, or holding what the rig's ``holds`` says (a can: ``_can_in``)."""
    p = _unit(spec["palm"])
    a = np.asarray(spec["fingers"], float)
    a = _unit(a - p * (a @ p))
    centre = _reference(rest, spec, rig, head_centre) + np.asarray(spec["offset"], float)
    return _grip(rest, side, a, p, centre - p * PALM_HALF, GRIP_ALONG, spec.get("holds", "nothing"))


def _reference(rest: Posed, spec: dict, rig: dict, head_centre: np.ndarray) -> np.ndarray:
    """The point a rig hand or phone position's offset is measured from."""
    if spec["relative_to"] == "head":
        return head_centre
    if spec["relative_to"] == "shoulder":
        return (rest.head("upperarm01.L") + rest.head("upperarm01.R")) / 2
    return np.asarray(rig["steering_wheel"]["centre"], float)


def _grip(rest, side, a, p, palm_target, along, holds) -> Grip:
    frame = hand_frame(rest, side)
    Z = turn_to(frame, a, p)
    return Grip(palm_target, Z @ rest.rot(f"wrist.{side}"), Z @ frame.a, along, holds)


def _arm(rest: Posed, side: str, grip: Grip) -> dict:
    wrist_target = grip.palm_target - grip.a * (grip.along * hand_frame(rest, side).length)
    outward = 1.0 if side == "L" else -1.0
    pole = np.array([-0.3, 0.7 * outward, -1.0])       # elbows down, a little out and back
    return reach(Limb.arm(side), rest, wrist_target, pole, end_rotation=grip.G_hand)


def _phone_in(frame: HandFrame, spec: dict, palm_skin: float) -> tuple[np.ndarray, np.ndarray]:
    """The phone on the posed palm's skin (as ``_phone_grip`` put it), turned as the rig says."""
    R = _spec_rotation(spec)
    return frame.palm(PHONE_ALONG, palm_skin + PHONE_THICKNESS / 2) + R[:, 1] * PHONE_SHIFT, R


def _can_in(frame: HandFrame, palm_skin: float) -> tuple[np.ndarray, np.ndarray]:
    """The can's body on the posed palm's skin across the hand, its top towards the thumb (local z)."""
    z = frame.t                       # unit, square to the palm's normal (hands.hand_frame)
    R = np.column_stack([frame.p, np.cross(z, frame.p), z])
    return frame.palm(CAN_ALONG, palm_skin + CAN_RADIUS), R


def _palm_skin(posed: Posed, frame: HandFrame, side: str, model, along: float = PHONE_ALONG,
               half: float = PHONE_SIZE[0] / 2) -> float:
    """How far the palm's skin stands off the hand's axis where a held thing lies, ``along`` the hand and
    ``half`` its width either side (the pads at the knuckles stand out further than the middle of the
    palm, PALM_HALF)."""
    bones = [f"metacarpal{k}.{side}" for k in (1, 2, 3, 4)] + [f"finger{k}-1.{side}" for k in FINGERS]
    palm = bone_weights(model, tuple(bones)) > 0.5
    local = posed.vertices[palm].astype(float) - frame.wrist
    share = local @ frame.a / frame.length
    under = np.abs(share - along) < half / frame.length
    skin = (local[under] @ frame.p).max() if under.any() else PALM_HALF
    return float(max(PALM_HALF, skin) + 0.0005)


# ---------------------------------------------------------------------- helpers
def _spec_rotation(spec: dict) -> np.ndarray:
    """A phone position's rotation: the rig's Euler angles, or as turned with the head (``_turned``)."""
    return spec["rotation"] if "rotation" in spec else _euler_xyz(spec["rotation_deg"])


def _euler_xyz(degrees) -> np.ndarray:
    """Blender's XYZ Euler rotation (X first, then Y, then Z, about world axes)."""
    x, y, z = (rotation(axis, math.radians(a)) for axis, a in zip(np.eye(3), degrees))
    return z @ y @ x


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)

