"""The driver: a seated human built from code. Height and weight classes scale the skeleton and the
body's girth; gender changes build and hair; the face shows happy or serious through a mouth shape
key, teeth and brows; the arms are posed by two-bone inverse kinematics (hands on the wheel, or one
hand holding the phone at P1-P10); the seat belt is laid over the torso's analytic surface (a
shrink-wrap computed exactly, so the strap never cuts into the body)."""
from __future__ import annotations

import math

import bmesh
import bpy
from mathutils import Vector

from ..labels import INSTANCE_ID
from . import mesh as M
from .cabin import wheel_frame

HEIGHT = {"H1": 0.88, "H2": 0.95, "H3": 1.02, "H4": 1.09}    # skeleton scale
WEIGHT = {"W1": 0.78, "W2": 0.95, "W3": 1.18, "W4": 1.42}    # girth scale
SKIN = (0.50, 0.30, 0.21)
SHIRT = {"BLACK": (0.012, 0.012, 0.013), "WHITE": (0.80, 0.80, 0.78)}
HAIR = (0.035, 0.018, 0.010)
BELT = (0.10, 0.10, 0.11)
_LEAN = math.radians(13)     # torso leans back against the backrest
_RING_T = (0.0, 0.08, 0.2, 0.35, 0.5, 0.65, 0.78, 0.88, 0.95, 1.0)
_SEGMENTS = 28
_EXP = 2.6                    # superellipse exponent: a boxier torso section than an ellipse


class Body:
    """The skeleton's key points and the torso's shape for one (height, weight, gender)."""

    def __init__(self, seat: dict, height: str, weight: str, female: bool):
        sx, sy, sz = seat["cushion"]
        self.h, self.w, self.female = HEIGHT[height], WEIGHT[weight], female
        self.sy = sy
        self.hip = Vector((sx - 0.14, sy, sz + 0.09))
        self.axis = Vector((-math.sin(_LEAN), 0, math.cos(_LEAN)))
        self.length = 0.50 * self.h
        self.neck_base = self.hip + self.axis * self.length
        self.head = self.neck_base + Vector((0.035, 0, 0.15 * self.h ** 0.5))
        sh = self.half_width(0.9) * 0.92
        self.shoulders = {side: self.neck_base + Vector((0.0, side * sh, -0.045)) for side in (1, -1)}

    def half_depth(self, t: float) -> float:
        base = [0.100, 0.098, 0.092, 0.090, 0.095, 0.102, 0.105, 0.095, 0.075, 0.045]
        a = _interp(t, base) * (0.75 + 0.25 * self.w)
        belly = max(0.0, self.w - 0.95) * 0.085 * math.exp(-((t - 0.3) / 0.2) ** 2)
        bust = (0.012 * math.exp(-((t - 0.68) / 0.08) ** 2)) if self.female else 0.0
        return a + belly + bust

    def half_width(self, t: float) -> float:
        base = [0.165, 0.160, 0.150, 0.145, 0.150, 0.165, 0.178, 0.185, 0.170, 0.085]
        scale = (0.85 + 0.15 * self.w) * (0.93 if self.female else 1.0)
        if self.female and t < 0.25:
            scale *= 1.06  # wider hips relative to the shoulders
        return _interp(t, base) * scale

    def centre(self, t: float) -> Vector:
        return self.hip + self.axis * (self.length * t)

    def surface(self, t: float, dy: float, offset: float = 0.0) -> tuple[Vector, Vector]:
        """Front surface point of the torso at height fraction t and lateral offset dy, pushed out by
        ``offset`` along the surface normal; and that normal."""
        a, b = self.half_depth(t), self.half_width(t)
        u = min(abs(dy) / b, 0.999)
        front = a * (1 - u ** _EXP) ** (1 / _EXP)
        # normal of the superellipse |x/a|^p + |y/b|^p = 1
        nx = (front / a) ** (_EXP - 1) / a
        ny = math.copysign(u ** (_EXP - 1) / b, dy)
        normal = Vector((nx * math.cos(_LEAN), ny, nx * math.sin(_LEAN))).normalized()
        forward = Vector((math.cos(_LEAN), 0, math.sin(_LEAN)))
        point = self.centre(t) + forward * front + Vector((0, dy, 0))
        return point + normal * offset, normal


def _interp(t: float, values) -> float:
    for (t0, v0), (t1, v1) in zip(zip(_RING_T, values), zip(_RING_T[1:], values[1:])):
        if t <= t1:
            return v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    return values[-1]


def two_bone_ik(root: Vector, target: Vector, l1: float, l2: float, pole: Vector) -> tuple[Vector, Vector]:
    """(elbow, end) of a two-segment limb from ``root`` reaching for ``target``, bending towards ``pole``."""
    span = target - root
    d = min(max(span.length, abs(l1 - l2) + 1e-3), l1 + l2 - 1e-4)
    u = span.normalized()
    p = (pole - u * pole.dot(u)).normalized()
    cos_a = (l1 * l1 + d * d - l2 * l2) / (2 * l1 * d)
    elbow = root + (u * cos_a + p * math.sqrt(max(0.0, 1 - cos_a * cos_a))) * l1
    return elbow, root + u * d


class Driver:
    def __init__(self, rig: dict, coll):
        self.rig, self.coll = rig, coll
        pid, face = INSTANCE_ID["driver"], INSTANCE_ID["driver_face"]   # the head is its own part
        self.skin = M.material("skin", SKIN, roughness=0.55, specular=0.35)
        self.shirt = M.material("shirt", SHIRT["WHITE"], roughness=0.85, specular=0.2)
        self.hair_mat = M.material("hair", HAIR, roughness=0.6)
        trousers = M.material("trousers", (0.02, 0.03, 0.07), roughness=0.9)
        white = M.material("eye_white", (0.8, 0.8, 0.8), roughness=0.3)
        dark = M.material("pupil", (0.01, 0.008, 0.006), roughness=0.2)
        self.lips = M.material("mouth", (0.12, 0.015, 0.015), roughness=0.4)
        o = {}
        o["torso"] = bpy.data.objects.new("torso", bpy.data.meshes.new("torso"))
        o["torso"].data.materials.append(self.shirt)
        o["torso"].pass_index = pid
        coll.objects.link(o["torso"])
        o["neck"] = M.new_object("neck", M.unit_cylinder(), self.skin, coll, pid)
        o["head"] = M.ellipsoid("head", (0, 0, 0), (1, 1, 1), self.skin, coll, face)
        o["nose"] = M.ellipsoid("nose", (0, 0, 0), (0.018, 0.014, 0.022), self.skin, coll, face)
        for side in (1, -1):
            o[f"eye{side}"] = M.ellipsoid(f"eye{side}", (0, 0, 0), (0.008, 0.013, 0.008), white, coll, face)
            o[f"pupil{side}"] = M.ellipsoid(f"pupil{side}", (0, 0, 0), (0.005, 0.0065, 0.0065), dark, coll, face)
            o[f"brow{side}"] = M.box(f"brow{side}", (0, 0, 0), (0.008, 0.03, 0.007), self.hair_mat, coll, face)
            o[f"ear{side}"] = M.ellipsoid(f"ear{side}", (0, 0, 0), (0.012, 0.008, 0.028), self.skin, coll, face)
            o[f"cheek{side}"] = M.ellipsoid(f"cheek{side}", (0, 0, 0), (0.014, 0.02, 0.014), self.skin, coll, face)
            o[f"sleeve{side}"] = M.new_object(f"sleeve{side}", M.unit_cylinder(), self.shirt, coll, pid)
            o[f"shoulder{side}"] = M.ellipsoid(f"shoulder{side}", (0, 0, 0), (1, 1, 1), self.shirt, coll, pid)
            o[f"upper{side}"] = M.new_object(f"upper{side}", M.unit_cylinder(), self.skin, coll, pid)
            o[f"elbow{side}"] = M.ellipsoid(f"elbow{side}", (0, 0, 0), (1, 1, 1), self.skin, coll, pid)
            o[f"fore{side}"] = M.new_object(f"fore{side}", M.unit_cylinder(), self.skin, coll, pid)
            o[f"hand{side}"] = M.new_object(f"hand{side}", M.unit_sphere(), self.skin, coll, pid)
            o[f"thigh{side}"] = M.new_object(f"thigh{side}", M.unit_sphere(), trousers, coll, pid)
            o[f"shin{side}"] = M.new_object(f"shin{side}", M.unit_cylinder(), trousers, coll, pid)
            o[f"strand{side}"] = M.ellipsoid(f"strand{side}", (0, 0, 0), (1, 1, 1), self.hair_mat, coll, face)
        o["mouth"] = M.new_object("mouth", _mouth_mesh(), self.lips, coll, face)
        o["teeth"] = M.box("teeth", (0, 0, 0), (0.006, 0.044, 0.007), white, coll, face)
        o["hair_cap"] = M.ellipsoid("hair_cap", (0, 0, 0), (1, 1, 1), self.hair_mat, coll, face)
        o["hair_long"] = M.ellipsoid("hair_long", (0, 0, 0), (1, 1, 1), self.hair_mat, coll, face)
        self.objects = o
        self.belt = _Belt(rig["seat_belt"], coll)
        self.state: dict = {}
        self.body: Body | None = None
        self.phone_hand: tuple[Vector, str] | None = None

    # ------------------------------------------------------------------ apply a scene
    def apply(self, f: dict) -> None:
        key = (f["driver_gender"], f["driver_height"], f["driver_weight"], f["phone_position"], f["seat_belt"],
               f["driver_emotion"], f["tshirt_colour"])
        if key == self.state.get("key"):
            return
        for obj in self.objects.values():
            obj.hide_render = False   # per-feature parts (teeth, long hair) are hidden again below
        M.set_colour(self.shirt, SHIRT[f["tshirt_colour"]])
        female = f["driver_gender"] == "FEMALE"
        body = Body(self.rig["seats"]["driver"], f["driver_height"], f["driver_weight"], female)
        self.body = body
        self._torso(body)
        self._head(body, f["driver_emotion"], female)
        self._arms(body, f["phone_position"])
        self._legs(body)
        self.belt.apply(body, f["seat_belt"] == "YES")
        self.state["key"] = key

    def _torso(self, body: Body) -> None:
        bm = bmesh.new()
        rings = []
        for t in _RING_T:
            c, a, b = body.centre(t), body.half_depth(t), body.half_width(t)
            ring = []
            for k in range(_SEGMENTS):
                ang = 2 * math.pi * k / _SEGMENTS
                ca, sa = math.cos(ang), math.sin(ang)
                x = a * math.copysign(abs(ca) ** (2 / _EXP), ca)
                y = b * math.copysign(abs(sa) ** (2 / _EXP), sa)
                ring.append(bm.verts.new(c + Vector((x * math.cos(_LEAN), y, x * math.sin(_LEAN)))))
            rings.append(ring)
        for r0, r1 in zip(rings, rings[1:]):
            for k in range(_SEGMENTS):
                bm.faces.new((r0[k], r0[(k + 1) % _SEGMENTS], r1[(k + 1) % _SEGMENTS], r1[k]))
        bm.faces.new(rings[0][::-1])
        bm.faces.new(rings[-1])
        for face in bm.faces:
            face.smooth = len(face.verts) == 4
        bm.to_mesh(self.objects["torso"].data)
        bm.free()

    def _head(self, body: Body, emotion: str, female: bool) -> None:
        o, h = self.objects, body.head
        rx, ry, rz = 0.098, 0.080, 0.115
        o["head"].location, o["head"].scale = h, (rx, ry, rz)
        M.place_segment(o["neck"], body.neck_base - body.axis * 0.04, h - Vector((0, 0, 0.06)), 0.048, 0.052)

        def face(dy, dz, out=0.0):  # a point on the head's front surface
            u = 1 - (dy / ry) ** 2 - (dz / rz) ** 2
            return h + Vector((rx * math.sqrt(max(u, 0.0)) + out, dy, dz))

        happy = emotion == "HAPPY"
        o["nose"].location = face(0.0, -0.01, 0.004)
        for side in (1, -1):
            o[f"eye{side}"].location = face(side * 0.031, 0.018, -0.002)
            o[f"pupil{side}"].location = face(side * 0.031, 0.018, 0.004)
            # happy: raised, relaxed brows; serious: lowered and pulled down towards the nose
            o[f"brow{side}"].location = face(side * 0.033, 0.048 if happy else 0.036, 0.003)
            o[f"brow{side}"].rotation_euler = (side * math.radians(-8 if happy else 22), 0, 0)
            o[f"ear{side}"].location = h + Vector((-0.005, side * ry, 0.0))
            # a real smile lifts the cheeks and narrows the eyes
            o[f"cheek{side}"].location = face(side * 0.04, -0.028, -0.006)
            o[f"cheek{side}"].hide_render = not happy
            o[f"eye{side}"].scale = (0.008, 0.013, 0.0055 if happy else 0.008)
            o[f"pupil{side}"].scale = (0.005, 0.0065, 0.0045 if happy else 0.0065)
        o["mouth"].location = face(0.0, -0.052, 0.002)
        o["mouth"].data.shape_keys.key_blocks["smile"].value = 1.0 if happy else 0.0
        o["teeth"].location = face(0.0, -0.0545, -0.003)
        o["teeth"].hide_render = not happy
        if female:   # fuller hair down the sides; men get a short crop that shows the ears and temples
            o["hair_cap"].location, o["hair_cap"].scale = h + Vector((-0.028, 0, 0.024)), (rx * 1.02, ry * 1.12, rz * 0.98)
        else:
            o["hair_cap"].location, o["hair_cap"].scale = h + Vector((-0.034, 0, 0.034)), (rx * 0.97, ry * 1.05, rz * 0.92)
        o["hair_long"].hide_render = not female
        o["hair_long"].location, o["hair_long"].scale = h + Vector((-0.05, 0, -0.07)), (0.075, ry * 1.35, 0.17)
        for side in (1, -1):
            strand = o[f"strand{side}"]
            strand.hide_render = not female
            strand.location, strand.scale = h + Vector((-0.005, side * (ry + 0.006), -0.06)), (0.05, 0.022, 0.14)

    def _arms(self, body: Body, phone_position: str) -> None:
        o, h = self.objects, body.h
        grip = self._wheel_grips()
        self.phone_hand = None
        targets = dict(grip)
        if phone_position != "NONE":
            spec = self.rig["phone_positions"][phone_position]
            side = 1 if spec["hand"] == "left" else -1   # driver's left is +y
            ref = {"head": body.head, "shoulder": body.neck_base - Vector((0, 0, 0.045)),
                   "wheel": Vector(self.rig["steering_wheel"]["centre"])}[spec["relative_to"]]
            targets[side] = ref + Vector(spec["offset"])
            self.phone_hand = (targets[side], phone_position)
        l1, l2 = 0.29 * h, 0.25 * h
        r_arm = 0.040 * (0.8 + 0.2 * body.w)
        for side in (1, -1):
            shoulder = body.shoulders[side]
            pole = Vector((-0.3, side * 0.6, -1.0))
            target = targets[side]
            elbow, wrist = two_bone_ik(shoulder, target - (target - shoulder).normalized() * 0.04, l1, l2, pole)
            M.place_segment(o[f"upper{side}"], shoulder, elbow, r_arm)
            M.place_segment(o[f"sleeve{side}"], shoulder - (elbow - shoulder) * 0.05, shoulder + (elbow - shoulder) * 0.5,
                            r_arm * 1.3)
            o[f"shoulder{side}"].location = shoulder
            o[f"shoulder{side}"].scale = (r_arm * 1.45,) * 3
            o[f"elbow{side}"].location, o[f"elbow{side}"].scale = elbow, (r_arm * 0.95,) * 3
            M.place_segment(o[f"fore{side}"], elbow, wrist, r_arm * 0.8, r_arm * 0.85)
            direction = (wrist - elbow).normalized()
            M.place_capsule(o[f"hand{side}"], wrist, wrist + direction * 0.06, 0.032)

    def _wheel_grips(self) -> dict:
        centre, e_y, e_up, normal = wheel_frame(self.rig["steering_wheel"])
        r = self.rig["steering_wheel"]["radius"]
        c, s = math.cos(math.radians(30)), math.sin(math.radians(30))  # 10 and 2 o'clock
        return {side: centre + (e_y * side * c + e_up * s) * r + normal * 0.01 for side in (1, -1)}

    def _legs(self, body: Body) -> None:
        o, h = self.objects, body.h
        sx, sy, sz = self.rig["seats"]["driver"]["cushion"]
        r = 0.068 * (0.8 + 0.2 * body.w)
        for side in (1, -1):
            hip = body.hip + Vector((0.02, side * 0.09, 0.0))
            knee = Vector((sx + 0.22 + 0.16 * h, sy + side * 0.11, sz + 0.13))
            ankle = Vector((knee.x + 0.14, knee.y, 0.09))
            M.place_capsule(o[f"thigh{side}"], hip, knee, r)
            M.place_segment(o[f"shin{side}"], knee, ankle, r * 0.7)

    def hide(self) -> None:
        for obj in [*self.objects.values(), *self.belt.worn, self.belt.retracted]:
            obj.hide_render = True
        self.state.clear()
        self.phone_hand = None

    def hand_pose(self):
        """(hand point, phone position) when a hand holds the phone, else None."""
        return self.phone_hand


def _mouth_mesh() -> bpy.types.Mesh:
    """A curved strip: basis = closed, straight (serious); shape key ``smile`` = wide, open, corners up."""
    n = 9
    verts, smile = [], []
    for row in (0, 1):
        for i in range(n):
            s = (i / (n - 1)) * 2 - 1          # -1 .. 1 across the mouth
            x = -0.012 * s * s                 # follows the face's curvature
            verts.append((x, s * 0.024, 0.0025 if row == 0 else -0.0025))
            # smile: a crescent whose lips meet at raised corners, open in the middle
            z = (-0.001 + 0.014 * s * s) if row == 0 else (-0.021 + 0.035 * s * s)
            smile.append((-0.02 * s * s, s * 0.038, z))
    faces = [(i, i + 1, n + i + 1, n + i) for i in range(n - 1)]
    mesh = bpy.data.meshes.new("mouth")
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new("_mouth_tmp", mesh)
    obj.shape_key_add(name="Basis")
    key = obj.shape_key_add(name="smile")
    for v, co in zip(key.data, smile):
        v.co = co
    bpy.data.objects.remove(obj)   # the shape keys live on the mesh
    return mesh


class _Belt:
    """Shoulder and lap strap laid on the torso; a retracted strap hangs on the B-pillar when unused."""

    def __init__(self, hw: dict, coll):
        self.hw = {k: Vector(v) for k, v in hw.items()}
        pid = INSTANCE_ID["seat_belt"]
        self.mat = M.material("belt", BELT, roughness=0.6)
        self.worn = [self._obj(n, coll, pid) for n in ("belt_shoulder", "belt_lap")]
        # an unused belt is part of the car: its mask class is cabin, so "seat_belt" means worn
        self.retracted = self._obj("belt_retracted", coll, INSTANCE_ID["cabin"])
        up = self.hw["upper_anchor"]
        pts = [up, up - Vector((0.0, 0.0, 0.38))]
        self.retracted.data = M.ribbon_mesh("belt_retracted", pts, [0.048] * 2, [Vector((0, -1, 0))] * 2)

    def _obj(self, name, coll, pid):
        obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
        obj.data.materials.append(self.mat)
        obj.pass_index = pid
        coll.objects.link(obj)
        return obj

    def apply(self, body: Body, worn: bool) -> None:
        for obj in self.worn:
            obj.hide_render = not worn
        self.retracted.hide_render = worn
        if not worn:
            return
        b = body.half_width
        diag = []
        for i in range(15):  # over the left (+y) shoulder, across the chest to the right hip
            s = i / 14
            t = 0.93 + (0.12 - 0.93) * s
            dy = (0.55 * b(0.93)) + (-0.8 * b(0.12) - 0.55 * b(0.93)) * s
            diag.append(body.surface(t, dy, 0.012))
        points = [self.hw["upper_anchor"]] + [p for p, _ in diag] + [self.hw["buckle"]]
        normals = [diag[0][1]] + [n for _, n in diag] + [diag[-1][1]]
        mesh = self.worn[0].data
        M.ribbon_mesh(mesh.name, points, [0.048] * len(points), normals)
        lap = [body.surface(0.05, -0.8 * b(0.05) + 1.6 * b(0.05) * i / 8, 0.03) for i in range(9)]
        lap_pts = [self.hw["buckle"]] + [p + Vector((0.04, 0, 0.04)) for p, _ in lap] + [self.hw["lap_anchor"]]
        lap_n = [lap[0][1]] + [n for _, n in lap] + [lap[-1][1]]
        M.ribbon_mesh(self.worn[1].data.name, lap_pts, [0.048] * len(lap_pts), lap_n)
