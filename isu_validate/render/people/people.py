"""The host side of the people: for a scene, the files the Blender worker swaps into its persistent
person meshes (a topology per kind of person, a posed state per body, pose and expression).

Everything is looked up in the on-disk store first; only a miss loads anny (about 0.9 GB, once per
process) and poses the body (IK, seat fit, belt) - the pose without the face once per body and phone
position, the face per expression on top of it."""
from __future__ import annotations

import contextlib
import hashlib
import json
from pathlib import Path

import numpy as np

from . import accessories, belt, child, creases, expressions, garments, hair, regions, seated
from .model import load_model
from .phenotype import child_phenotype, driver_phenotype
from .skeleton import Body
from .store import PeopleStore, entry_key, load_entry

KINDS = ("male", "female", "child")
JOINTS = ("root", "spine01", "neck01", "head")    # bone heads a state keeps (for measuring a pose)
HAIR_STYLE = {"male": "short", "female": "bob", "child": "short"}   # a scene's BY_GENDER (and the child's)
TILT_FEATURES = ("phone_tip", "phone_roll", "phone_turn")   # the phone turned in the hand (seated.tilted), degrees
NO_TILT = (0.0, 0.0, 0.0)


def hair_style_of(f: dict, kind: str) -> str:
    """The driver's hair style: the scene's ``driver_hair_style`` (SHORT, BOB, BUZZ), else by gender."""
    style = f.get("driver_hair_style", "BY_GENDER")
    return HAIR_STYLE[kind] if style == "BY_GENDER" else style.lower()


def rig_part_hash(cabin: dict, parts: tuple[str, ...]) -> str:
    """Identifies the parts of a cabin rig a pose depends on (seats, wheel, belt hardware...)."""
    content = {p: _dig(cabin, p) for p in parts}
    return hashlib.sha256(json.dumps(content, sort_keys=True, default=str).encode()).hexdigest()[:16]


_DRIVER_RIG = ("seats.driver", "steering_wheel", "seat_belt", "phone_positions", "hand_positions", "gaze_targets")
_CHILD_RIG = ("anchors.child_seat",)


class People:
    def __init__(self, cabin: dict, store: PeopleStore | None = None):
        self.cabin, self.store = cabin, store or PeopleStore()
        self.driver_rig = rig_part_hash(cabin, _DRIVER_RIG)
        self.child_rig = rig_part_hash(cabin, _CHILD_RIG)
        self.misses = 0           # entries posed by this process (each a miss of the store)

    # ------------------------------------------------------------------ what the worker gets
    def for_scene(self, f: dict, with_driver: bool = True) -> dict:
        """{"driver": {...} | None, "child": {...} | None}: topology and state files for the worker."""
        out = {"driver": None, "child": None}
        if with_driver:
            kind = "female" if f["driver_gender"] == "FEMALE" else "male"
            style = hair_style_of(f, kind)
            state = self.driver_state(f["driver_gender"], f["driver_height"], f["driver_weight"],
                                      f["driver_emotion"], f["phone_position"], style, f.get("driver_hands", "WHEEL"),
                                      f.get("driver_gaze", "ROAD"), phone_tilt_of(f))
            top = f.get("driver_top", "TSHIRT")
            out["driver"] = {"topology": str(self.topology(kind, style)), "state": str(state), "kind": kind,
                             "outfit": str(self.outfit(kind, style, top)),
                             "dressed": str(self.dressed(kind, style, top, state))}
        if f.get("child_seat") == "YES" and f.get("child") == "YES":
            front = f["child_seat_orientation"] == "FRONT_FACING"
            out["child"] = {"topology": str(self.topology("child")), "state": str(self.child_state(front)),
                            "kind": "child", "front_facing": front}
        return out

    # ------------------------------------------------------------------ entries
    def topology(self, kind: str, style: str | None = None):
        style = style or HAIR_STYLE[kind]
        key = entry_key("topology", {"person": kind, "hair": style})
        found = self.store.get("topology", key)
        if found:
            return found
        with _posing(self):
            return self.store.put("topology", key, _topology(kind, style))

    def driver_state(self, gender: str, height: str, weight: str, emotion: str, phone_position: str,
                     style: str | None = None, hands: str = "WHEEL", gaze: str = "ROAD",
                     phone_tilt: tuple[float, float, float] = NO_TILT):
        kind = "female" if gender == "FEMALE" else "male"
        style = style or HAIR_STYLE[kind]
        phone_tilt = tuple(round(float(d), 1) for d in phone_tilt)   # the key and the pose: to a tenth of a degree
        inputs = {"rig": self.driver_rig, "gender": gender, "height": height, "weight": weight,
                  "emotion": emotion, "phone_position": phone_position, "hair": style, "hands": hands,
                  **_gaze_input(gaze), **_tilt_input(phone_tilt)}
        key = entry_key("driver", inputs)
        found = self.store.get("driver", key)
        if found:
            return found
        with _posing(self):
            pose = self._driver_pose(gender, height, weight, phone_position, hands, gaze, phone_tilt)
            topo = load_entry(self.topology(kind, style))
            phenotype, deltas = driver_phenotype(gender, height, weight), _deltas_from(pose)
            posed = Body(load_model(), phenotype, expressions.facial_actions(emotion)).evaluate(deltas)
            rest = Body(load_model(), phenotype, expressions.facial_actions("NEUTRAL")).evaluate(deltas)
            face = np.zeros(len(rest.vertices), bool)
            face[topo["faces"][topo["head"]]] = True
            crease = creases.crease_field(topo["faces"], rest.vertices.astype(np.float64),
                                          posed.vertices.astype(np.float64), face)
            state = {**_surface_state(posed, topo), "crease": crease,
                     **{k: pose[k] for k in pose if not k.startswith("d_")}}
            return self.store.put("driver", key, state)

    def outfit(self, kind: str, style: str, top: str):
        """The garments of a driver in ``top`` and trousers and the accessories, cut and modelled on the rest
        body of the kind (the cap over the hair of the style)."""
        key = entry_key("outfit", {"person": kind, "hair": style, "top": top})
        found = self.store.get("outfit", key)
        if found:
            return found
        with _posing(self):
            return self.store.put("outfit", key, _outfit(kind, style, top, load_entry(self.topology(kind, style))))

    def dressed(self, kind: str, style: str, top: str, state):
        """The outfit on a posed driver: the garments' and accessories' vertices, the belt lying on the clothes."""
        key = entry_key("dressed", {"state": Path(state).stem, "hair": style, "top": top})
        found = self.store.get("dressed", key)
        if found:
            return found
        outfit = load_entry(self.outfit(kind, style, top))
        return self.store.put("dressed", key, _dressed(outfit, load_entry(self.topology(kind, style)),
                                                       load_entry(state)))

    def child_state(self, front_facing: bool):
        key = entry_key("child", {"rig": self.child_rig, "front_facing": front_facing})
        found = self.store.get("child", key)
        if found:
            return found
        with _posing(self):
            topo = load_entry(self.topology("child"))
            body = Body(load_model(), child_phenotype("FRONT_FACING" if front_facing else "REAR_FACING"),
                        expressions.facial_actions("NEUTRAL"))
            posed = child.pose_child(body, front_facing, self.cabin["anchors"]["child_seat"])
            return self.store.put("child", key, _surface_state(posed, topo))

    def _driver_pose(self, gender, height, weight, phone_position, hands: str = "WHEEL", gaze: str = "ROAD",
                     phone_tilt: tuple[float, float, float] = NO_TILT) -> dict:
        """The expression-free pose (bone deltas), belt straps and phone placement of a driver."""
        key = entry_key("driver-pose", {"rig": self.driver_rig, "gender": gender, "height": height,
                                        "weight": weight, "phone_position": phone_position, "hands": hands,
                                        **_gaze_input(gaze), **_tilt_input(phone_tilt)})
        found = self.store.load("driver-pose", key)
        if found:
            return found
        model = load_model()
        body = Body(model, driver_phenotype(gender, height, weight))
        dp = seated.seat_and_pose(body, self.cabin, phone_position, hands, gaze, phone_tilt)
        faces = model.faces.cpu().numpy()
        hardware = dict(self.cabin["seat_belt"])
        for part in ("buckle", "lap_anchor"):     # mounted on the seat: they slide with it
            hardware[part] = np.asarray(hardware[part], float) + np.array([dp.seat_shift, 0.0, 0.0])
        diagonal, lap = belt.lay_belt(dp.posed, faces, belt.carrier_mask(model), hardware)
        record = {f"d_{bone}": m for bone, m in dp.deltas.items()}
        record["seat_shift"] = np.float32(dp.seat_shift)
        record.update(belt_diagonal=diagonal.points, belt_diagonal_normals=diagonal.normals,
                      belt_lap=lap.points, belt_lap_normals=lap.normals,
                      head_centre=dp.head_centre.astype(np.float32))
        if dp.phone is not None:
            record.update(phone_centre=dp.phone[0].astype(np.float32), phone_rotation=dp.phone[1].astype(np.float32))
        if dp.can is not None:
            record.update(can_centre=dp.can[0].astype(np.float32), can_rotation=dp.can[1].astype(np.float32))
        self.store.put("driver-pose", key, record)
        return record


# ---------------------------------------------------------------------- helpers
def _topology(kind: str, style: str) -> dict:
    """Triangles, per-corner UVs, material slot and head flag per triangle, garment fields per vertex,
    and the hair style."""
    model = load_model()
    faces = model.faces.cpu().numpy().astype(np.int32)
    if kind == "child":
        body = Body(model, child_phenotype())
        fields = regions.child_fields(body)
    else:
        body = Body(model, driver_phenotype("FEMALE" if kind == "female" else "MALE", "H3", "W2"))
        fields = regions.adult_fields(body, female=kind == "female")
    rest = body.evaluate({})
    candidates = regions.bone_weights(model, ("head", "neck")) > 0.5
    style = hair.hair_style(rest, faces, candidates, style, 0.6 if kind == "child" else 1.0)
    shell = hair.hair_vertices(style, rest.vertices.astype(np.float64), hair.vertex_normals(rest.vertices, faces))
    locks = hair.lock_roots(style, shell.astype(np.float64), rest)
    uv = model.texture_coordinates[model.face_texture_coordinate_indices].cpu().numpy()
    return {"faces": faces, "uv": uv.reshape(-1, 2).astype(np.float32),
            "eye_uv": regions.eye_uv(model, uv).reshape(-1, 2),
            "slots": regions.slots(model),
            "head": regions.head_mask(model, faces), "slot_names": np.array(regions.SLOTS),
            **{f"field_{k}": v.astype(np.float32) for k, v in fields.items()}, "field_scalp": style.field,
            "lips_mask": np.array(str(regions.lips_mask_path())),
            "hands": regions.bone_weights(model, ("wrist", "finger", "metacarpal")) > 0.5,
            "carriers": belt.carrier_mask(model),
            "hair_i": style.i, "hair_j": style.j, "hair_t": style.t, "hair_faces": style.faces,
            "hair_thickness": style.thickness, "lock_face": locks.face, "lock_bary": locks.bary,
            "lock_length": locks.length, "lock_width": locks.width, "lock_lift": locks.lift,
            "lock_crown": np.int32(locks.crown), "lock_faces": hair.lock_faces(len(locks))}


def _outfit(kind: str, style: str, top: str, topo: dict) -> dict:
    model = load_model()
    faces = topo["faces"]
    body = Body(model, driver_phenotype("FEMALE" if kind == "female" else "MALE", "H3", "W2"))
    worn = garments.outfit(body, top, faces)
    rest = body.evaluate({})
    hair_lift = np.zeros(len(rest.vertices))
    scalp = topo["hair_i"] == topo["hair_j"]
    hair_lift[topo["hair_i"][scalp]] = topo["hair_thickness"][scalp]
    out = {"slots": np.array(sorted(worn)), **accessories.rest_accessories(model, rest, faces, hair_lift)}
    for slot, g in worn.items():
        out.update(g.to_arrays(slot))
    return out


def _dressed(outfit: dict, topo: dict, state: dict) -> dict:
    """Each garment's (and the cap's) vertices and crumple on the posed body, the rigid accessories placed,
    and the belt straps lifted onto the clothes."""
    v, faces = state["vertices"].astype(np.float64), topo["faces"]
    normals = hair.vertex_normals(v, faces)
    out, placed, grazed = {}, [], []
    for slot in [*map(str, outfit["slots"]), "cap", "band"]:
        g = garments.Garment.from_arrays(outfit, slot)
        out[f"{slot}_co"], out[f"{slot}_crumple"] = garments.dress(g, v, faces, normals)
        if slot not in ("cap", "band"):
            # the belt lies on the cloth over the torso, pelvis and thighs (as on the skin: belt.py) and
            # only touches the rest (a sleeve beside the chest)
            carried = topo["carriers"][g.i][g.faces].all(axis=1) & ~g.band
            placed.append((out[f"{slot}_co"], g.faces[carried]))
            grazed.append((out[f"{slot}_co"], g.faces[~carried & ~g.band]))
    out.update({f"{name}_co": co for name, co in accessories.place(outfit, v).items()})
    if "belt_diagonal" in state:
        out.update(garments.lift_straps(state, placed, grazed))
    return out


def _surface_state(posed, topo: dict) -> dict:
    """What the worker swaps in: the body's vertices, its hair shell and the locks on it (a bob's cards); and
    a few joints (JOINTS)."""
    vertices = posed.vertices
    normals = hair.vertex_normals(vertices.astype(np.float64), topo["faces"])
    style = hair.HairStyle("", topo["hair_i"], topo["hair_j"], topo["hair_t"], topo["hair_faces"],
                           topo["hair_thickness"], topo["field_scalp"])
    shell = hair.hair_vertices(style, vertices, normals)
    locks = hair.Locks(topo["lock_face"], topo["lock_bary"], topo["lock_length"], topo["lock_width"],
                       topo["lock_lift"], int(topo["lock_crown"]))
    return {"vertices": vertices.astype(np.float32), "hair": shell,
            "locks": hair.lock_vertices(locks, topo["hair_faces"], shell),
            "joints": np.array([posed.head(b) for b in JOINTS], np.float32)}


def phone_tilt_of(f: dict) -> tuple[float, float, float]:
    """A scene's (phone_tip, phone_roll, phone_turn) in degrees: zero where the space lacks them or no phone is in
    the hand (a scene may carry an inactive feature's drawn value)."""
    if f.get("phone_position", "NONE") == "NONE":
        return NO_TILT
    return tuple(float(f.get(name) or 0.0) for name in TILT_FEATURES)


def _tilt_input(tilt) -> dict:
    """A store key's phone tilt: none when the phone is held at the rig's angle (entries posed before keep theirs)."""
    return {"phone_tilt": list(tilt)} if any(tilt) else {}


def _gaze_input(gaze: str) -> dict:
    """A store key's gaze: none for the road, so that entries posed before gazes existed keep their keys' shape."""
    return {} if gaze == "ROAD" else {"gaze": gaze}


def _deltas_from(record: dict) -> dict:
    return {k[2:]: record[k] for k in record if k.startswith("d_")}


def _dig(d: dict, dotted: str):
    for part in dotted.split("."):
        d = d.get(part, {}) if isinstance(d, dict) else {}
    return d


@contextlib.contextmanager
def _posing(people: People):
    """Count a miss; pose single-threaded (torch's two threads only fight on a shared machine)."""
    import torch
    people.misses += 1
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)
