"""Objects: the child seat (front- or rear-facing; the child in it is an anny body, see people.py), the
suitcase, the phone in the driver's hand, what the driver drinks from (the can, cups, a bottle, a mug), and
the phone, cola can and cola bottle lying on the co-driver seat (each its own render instance). Each is built
the first time a scene needs it (never for scenes that do not), then only shown, hidden, moved or recoloured."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ..cabin_geometry import CAN_HEIGHT, CHILD_SEAT_PADS, DRINK_PROFILES, PHONE_SIZE, child_seat_boxes, pitch
from ..labels import INSTANCE_ID
from .. import product_art as art
from . import materials
from . import mesh as M
from .cabin import euler_deg

LUGGAGE = {"YELLOW": (0.78, 0.50, 0.01), "ANTHRACITE": (0.028, 0.030, 0.033)}
# isu-diverse's phone_case (linear RGB): most phones are dark, but not every one, and a phone is its shape in a hand
PHONE_CASES = {"GRAPHITE": (0.012, 0.013, 0.016), "WHITE": (0.70, 0.70, 0.68), "SILVER": (0.35, 0.36, 0.38),
               "NAVY": (0.010, 0.020, 0.080), "RED": (0.40, 0.015, 0.015), "PINK": (0.75, 0.28, 0.36)}


class Group:
    """Objects that move together: built at the origin in local coordinates, placed by a parent empty."""

    def __init__(self, name: str, coll):
        self.root = bpy.data.objects.new(name, None)
        coll.objects.link(self.root)
        self.coll, self.parts = coll, []
        self.asset = False   # imported from a rig asset rather than built here

    def add(self, obj):
        obj.parent = self.root
        self.parts.append(obj)
        return obj

    def show(self, visible: bool) -> None:
        for obj in self.parts:
            obj.hide_render = not visible

    def place(self, location, rotation) -> None:
        self.root.location, self.root.rotation_euler = location, rotation


# ---------------------------------------------------------------------- builders (local coordinates)
def build_child_seat(coll, front_facing: bool) -> Group:
    """The shell and pads of ``cabin_geometry.child_seat_boxes`` (which the child's posing sits on), and
    the rear-facing carrier's carry handle."""
    g = Group("child_seat_" + ("front" if front_facing else "rear"), coll)
    pid = INSTANCE_ID["child_seat"]
    shell = M.material("child_seat_shell", (0.03, 0.03, 0.035), roughness=0.6)
    pad = materials.woven("child_seat_pad", (0.30, 0.02, 0.02))
    boxes = child_seat_boxes(front_facing)
    for box in boxes:
        g.add(M.box(box.name, box.centre, box.size, pad if box.name in CHILD_SEAT_PADS else shell, coll, pid,
                    rounded=box.rounded, rotation=(0, pitch(box), 0)))
    _harness(g, {b.name: b for b in boxes}, front_facing, pid)
    if not front_facing:
        handle = g.add(M.new_object("cs_handle", M.unit_torus(1.0, 0.09), shell, coll, pid))
        handle.location, handle.rotation_euler, handle.scale = (0.0, 0, 0.30), (math.pi / 2, 0, 0), (0.2, 0.2, 0.2)
    return g


# the five-point harness on the pads: (pad, offset from the pad's centre along its own axes, size)
_STRAPS = {True: [("cs_backpad", (0.017, y, 0.03), (0.004, 0.035, 0.40)) for y in (0.06, -0.06)]
                 + [("cs_cushion", (0.0, 0.0, 0.032), (0.14, 0.035, 0.004))],
           False: [("cs_platepad", (-0.04, y, 0.017), (0.34, 0.035, 0.004)) for y in (0.06, -0.06)]
                  + [("cs_platepad", (0.20, 0.0, 0.017), (0.10, 0.035, 0.004))]}
_BUCKLE = {True: ("cs_cushion", (0.05, 0.0, 0.038)), False: ("cs_platepad", (0.14, 0.0, 0.024))}


def _harness(g: Group, boxes: dict, front_facing: bool, pid: int) -> None:
    """Shoulder and crotch straps lying on the pads and the buckle with its red release button."""
    strap = materials.woven("child_seat_strap", (0.018, 0.018, 0.02), roughness=0.7)
    buckle = M.material("child_seat_buckle", (0.02, 0.02, 0.022), roughness=0.35)
    button = M.material("child_seat_button", (0.55, 0.02, 0.02), roughness=0.4)

    def on(pad: str, offset, size, mat, name):
        box = boxes[pad]
        centre = np.asarray(box.centre) + box.R @ np.asarray(offset)
        g.add(M.box(name, tuple(centre), size, mat, g.coll, pid, rounded=0.2, rotation=(0, pitch(box), 0)))

    for k, (pad, offset, size) in enumerate(_STRAPS[front_facing]):
        on(pad, offset, size, strap, f"cs_strap{k}")
    pad, offset = _BUCKLE[front_facing]
    on(pad, offset, (0.035, 0.045, 0.014), buckle, "cs_buckle")
    on(pad, (offset[0] + 0.004, 0.0, offset[2] + 0.008), (0.016, 0.022, 0.004), button, "cs_buckle_button")


def build_luggage(coll) -> tuple[Group, bpy.types.Material]:
    """A hard-shell cabin trolley, 0.40 x 0.23 x 0.55 m, standing on the seat."""
    g = Group("luggage", coll)
    pid = INSTANCE_ID["luggage"]
    body_mat = M.material("luggage_shell", LUGGAGE["YELLOW"], roughness=0.35, specular=0.6)
    dark = M.material("luggage_trim", (0.015, 0.015, 0.015), roughness=0.5)
    g.add(M.box("lug_body", (0, 0, 0.295), (0.23, 0.40, 0.55), body_mat, coll, pid, rounded=0.12))
    for k, y in enumerate((-0.12, -0.04, 0.04, 0.12)):  # moulded ribs
        g.add(M.box(f"lug_rib{k}", (0.117, y, 0.295), (0.006, 0.018, 0.48), body_mat, coll, pid, rounded=0.3))
    # the zip runs round the sides and top between the front and back shells, its pull hanging at one side
    g.add(M.box("lug_seam", (0, 0, 0.295), (0.012, 0.406, 0.556), dark, coll, pid, rounded=0.12))
    zip_metal = M.material("luggage_zip", (0.55, 0.55, 0.57), roughness=0.3, metallic=1.0)
    g.add(M.box("lug_zip", (0, 0, 0.295), (0.003, 0.4075, 0.5575), zip_metal, coll, pid, rounded=0.12))
    g.add(M.box("lug_zip_pull", (0.0, 0.205, 0.42), (0.010, 0.004, 0.03), zip_metal, coll, pid, rounded=0.3))
    g.add(M.box("lug_handle", (0.03, 0, 0.585), (0.04, 0.14, 0.025), dark, coll, pid, rounded=0.3))
    # the telescopic trolley handle, pushed down: two aluminium tubes and the grip, at the back
    alu = M.material("luggage_alu", (0.45, 0.46, 0.48), roughness=0.35, metallic=1.0)
    for k, y in enumerate((0.10, -0.10)):
        tube = g.add(M.new_object(f"lug_tube{k}", M.unit_cylinder(12), alu, coll, pid))
        M.place_segment(tube, Vector((-0.085, y, 0.56)), Vector((-0.085, y, 0.60)), 0.008)
    g.add(M.box("lug_grip", (-0.085, 0, 0.605), (0.03, 0.23, 0.022), dark, coll, pid, rounded=0.4))
    # four spinner wheels, each in its housing under a corner
    for k, (x, y) in enumerate(((0.08, 0.16), (0.08, -0.16), (-0.08, 0.16), (-0.08, -0.16))):
        g.add(M.box(f"lug_wheel_housing{k}", (x, y, 0.035), (0.05, 0.045, 0.03), dark, coll, pid, rounded=0.3))
        wheel = g.add(M.new_object(f"lug_wheel{k}", M.unit_cylinder(16), dark, coll, pid))
        M.place_segment(wheel, Vector((x, y - 0.011, 0.022)), Vector((x, y + 0.011, 0.022)), 0.022)
    return g, body_mat


def build_phone(coll, instance: str) -> Group:
    """A 152 x 74 x 8.5 mm smartphone centred on its origin, long axis along local y, screen on local +z:
    a graphite case round it, black glass in front with a thin bezel round the lit home screen (the same
    model in the hand and on the co-driver seat), and a camera bump with three lenses and a flash on its
    back."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    # each phone its own case material: the held phone's takes isu-diverse's phone_case, the co-driver seat's stays
    case = M.material(case_material(instance), PHONE_CASES["GRAPHITE"], roughness=0.3, specular=0.7)
    glass = M.material("phone_glass", (0.004, 0.004, 0.005), roughness=0.03, specular=1.0)
    lens = M.material("phone_lens", (0.002, 0.002, 0.003), roughness=0.02, specular=1.0)
    ring = M.material("phone_lens_ring", (0.5, 0.5, 0.52), roughness=0.25, metallic=1.0)
    flash = M.material("phone_flash", (0.8, 0.75, 0.6), roughness=0.3)
    g.add(M.box("phone_body", (0, 0, 0), PHONE_SIZE, case, coll, pid, rounded=0.15))
    g.add(M.box("phone_front", (0, 0, 0.0043), (0.071, 0.149, 0.0008), glass, coll, pid, rounded=0.06))
    screen = M.image_material("phone_home_screen", art.home_screen, "plane", roughness=0.05,
                              emission_strength=1.6, specular=0.6)
    g.add(M.box("phone_screen", (0, 0, 0.0048), (0.066, 0.143, 0.0002), screen, coll, pid))
    g.add(M.box("phone_camera_bump", (-0.017, 0.051, -0.0050), (0.030, 0.036, 0.0018), glass, coll, pid,
                rounded=0.25))
    lenses = ((-0.024, 0.061), (-0.024, 0.043), (-0.010, 0.052))          # three cameras in a triangle
    back = -0.0059                                # the bump's back face, where the lenses stand
    for k, (x, y) in enumerate(lenses):
        g.add(M.cylinder(f"phone_lens_ring{k}", (x, y, back), 0.0052, 0.0008, ring, coll, pid, 16))
        g.add(M.cylinder(f"phone_lens{k}", (x, y, back), 0.0040, 0.0011, lens, coll, pid, 16))
    g.add(M.cylinder("phone_flash", (-0.008, 0.063, back), 0.0016, 0.0004, flash, coll, pid, 10))
    for obj in g.parts[-(2 * len(lenses) + 1):]:
        obj.rotation_euler = (math.pi, 0, 0)      # turned to face out of the back (-z)
    return g


def case_material(instance: str) -> str:
    """The name of a phone's case material (``build_phone``'s ``instance``)."""
    return f"{instance}_case"


# a 1 l PET bottle, radius against height from the base (m): petaloid foot, body, waist, shoulder, neck
_BOTTLE = [(0.0, 0.0), (0.030, 0.001), (0.040, 0.006), (0.044, 0.018), (0.044, 0.095), (0.041, 0.100),
           (0.041, 0.104), (0.044, 0.110), (0.044, 0.185), (0.040, 0.205), (0.030, 0.228), (0.020, 0.243),
           (0.0135, 0.252), (0.0135, 0.258), (0.0175, 0.259), (0.0175, 0.262), (0.0135, 0.263),
           (0.0135, 0.268), (0.0, 0.268)]
_FILL = 0.246    # the cola's level in a full bottle (m above the base): just into the neck, as bottled


def _radius_at(profile, z: float) -> float:
    """The outline's radius at height z, on its outer wall: the first edge from the base that rises through z
    (at a step exactly at z, the radius just above it: a cap's, not the neck's under it)."""
    for (r0, z0), (r1, z1) in zip(profile, profile[1:]):
        if z0 <= z < z1:
            return r0 + (r1 - r0) * (z - z0) / (z1 - z0)
    raise ValueError(f"height {z} is outside the profile")


def _split_profile(profile, z: float):
    """(the profile below height z, the profile above it), both closed on the axis at z."""
    edge = (_radius_at(profile, z), z)
    return ([p for p in profile if p[1] < z] + [edge, (0.0, z)],
            [(0.0, z), edge] + [p for p in profile if p[1] > z])


def build_cola_bottle(coll, instance: str) -> Group:
    """A 1 l PET cola bottle lying or standing from its base (origin) along local +z, 0.29 m long with
    its cap: dark cola behind glossy plastic, a printed label round the body, a ridged red cap."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    # cola behind PET: glossy, nearly opaque, a dark red-brown where light comes through its edges
    cola = materials.see_through("cola_in_pet", (0.030, 0.008, 0.003), (0.55, 0.16, 0.05), 0.88, 0.04, 1.0)
    # the empty neck: clear, only its reflections seen (a black base colour)
    pet = materials.see_through("pet_clear", (0.01, 0.01, 0.01), (0.93, 0.95, 0.94), 0.2, 0.03, 1.0)
    label = M.image_material("cola_label", art.cola_label, "cylinder", roughness=0.35, specular=0.6)
    cap = M.material("cola_cap", (0.60, 0.015, 0.015), roughness=0.45)
    # filled into the neck: below, cola seen through the plastic; above, the clear, empty neck
    full, empty = _split_profile(_BOTTLE, _FILL)
    g.add(M.new_object("bottle_cola", M.lathe("cola_bottle_full", full, 40), cola, coll, pid))
    g.add(M.new_object("bottle_neck", M.lathe("cola_bottle_empty", empty, 40), pet, coll, pid))
    sleeve = g.add(M.new_object("bottle_label", M.unit_cylinder(40, cap=False), label, coll, pid))
    sleeve.location, sleeve.scale = (0, 0, 0.118), (0.0446, 0.0446, 0.062)
    g.add(M.cylinder("bottle_cap", (0, 0, 0.266), 0.0158, 0.022, cap, coll, pid, 24))
    for k in range(12):                    # the cap's grip ridges
        a = 2 * math.pi * k / 12
        g.add(M.box(f"bottle_cap_ridge{k}", (0.0158 * math.cos(a), 0.0158 * math.sin(a), 0.277),
                    (0.0012, 0.0012, 0.018), cap, coll, pid, rotation=(0, 0, a)))
    return g


def build_can(coll, instance: str) -> Group:
    """A 330 ml cola can from its base (origin) along local +z, 0.116 m tall and 0.066 m across: the
    printed label on the aluminium body, silver base and top with a rim and a ring-pull tab."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    silver = M.material("can_metal", (0.62, 0.62, 0.64), roughness=0.18, metallic=1.0)
    label = M.image_material("can_label", art.cola_label, "cylinder", roughness=0.28, metallic=0.45,
                             image="cola_label")
    g.add(M.new_object("can_body", M.lathe("cola_can", DRINK_PROFILES["CAN"], 40), silver, coll, pid))
    sleeve = g.add(M.new_object("can_label", M.unit_cylinder(40, cap=False), label, coll, pid))
    sleeve.location, sleeve.scale = (0, 0, 0.010), (0.0332, 0.0332, 0.094)
    rim = g.add(M.new_object("can_rim", M.unit_torus(1.0, 0.06), silver, coll, pid))
    rim.location, rim.scale = (0, 0, 0.116), (0.0275, 0.0275, 0.0275)
    g.add(M.box("can_tab", (0.008, 0, 0.1166), (0.019, 0.011, 0.0008), silver, coll, pid, rounded=0.4))
    return g


def _band(profile, z0: float, z1: float, out: float):
    """A closed ring standing ``out`` off the outline between heights z0 and z1 (a sleeve, a label)."""
    return [(0.0, z0), (_radius_at(profile, z0) + out, z0), (_radius_at(profile, z1) + out, z1), (0.0, z1)]


@dataclass(frozen=True)
class Drink:
    """How a drink other than the can looks: its outline in ``cabin_geometry.DRINK_PROFILES`` and materials
    (each a function: materials are made inside the worker, on first use)."""
    shape: str
    body: Callable
    lid: Callable | None = None          # a lid or cap of its own material ...
    lid_from: float | None = None        # ... above this height (m from the can's base)
    band: tuple | None = None            # ((from, to) heights, material): a sleeve or a label round the body


def _paper(colour) -> Callable:
    return lambda: M.material(f"cup_{'_'.join(f'{c:.2f}' for c in colour)}", colour, roughness=0.55)


DRINKS = {
    "WHITE_CUP": Drink("CUP", _paper((0.80, 0.80, 0.77))),
    "RED_CUP": Drink("CUP", _paper((0.55, 0.025, 0.02))),
    "COFFEE": Drink("COFFEE", _paper((0.82, 0.81, 0.78)), lambda: M.material("coffee_lid", (0.02, 0.02, 0.02), 0.35),
                    0.100, ((0.035, 0.075), _paper((0.40, 0.25, 0.13)))),
    "WATER": Drink("WATER", lambda: materials.see_through("water_in_pet", (0.015, 0.02, 0.025), (0.90, 0.95, 0.97),
                                                          0.25, 0.03, 1.0),
                   lambda: M.material("water_cap", (0.05, 0.18, 0.60), roughness=0.4), 0.102,
                   ((0.0, 0.050), lambda: M.material("water_label", (0.06, 0.28, 0.62), roughness=0.35))),
    "MUG": Drink("MUG", lambda: M.material("mug_steel", (0.60, 0.60, 0.62), roughness=0.25, metallic=1.0),
                 lambda: M.material("mug_lid", (0.015, 0.015, 0.015), roughness=0.4), 0.092),
}


def build_drink(coll, kind: str, instance: str) -> Group:
    """A drink other than the can (isu-diverse's ``drink``), built in the can's frame (its base at the origin,
    its top along +z) from ``cabin_geometry.DRINK_PROFILES``, which the hand's grip and the tests share."""
    drink = DRINKS[kind]
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    profile = DRINK_PROFILES[drink.shape]
    if drink.lid is None:
        g.add(M.new_object(f"{kind}_body", M.lathe(f"drink_{drink.shape}", profile, 40), drink.body(), coll, pid))
    else:
        below, above = _split_profile(list(profile), drink.lid_from)
        g.add(M.new_object(f"{kind}_body", M.lathe(f"drink_{drink.shape}_body", below, 40), drink.body(), coll, pid))
        g.add(M.new_object(f"{kind}_lid", M.lathe(f"drink_{drink.shape}_lid", above, 40), drink.lid(), coll, pid))
    if drink.band is not None:
        (z0, z1), mat = drink.band
        ring = _band(profile, z0, z1, 0.0008)
        g.add(M.new_object(f"{kind}_band", M.lathe(f"drink_{drink.shape}_band", ring, 40), mat(), coll, pid))
    if drink.shape == "CUP":     # the coffee seen over the rim
        g.add(M.cylinder(f"{kind}_coffee", (0, 0, 0.0875), 0.0345, 0.001,
                         M.material("coffee", (0.06, 0.03, 0.012), roughness=0.15), coll, pid, 40))
    return g


# ---------------------------------------------------------------------- what a scene asks for
# the things on the co-driver seat: feature -> (asset part, builder); the feature names the instance too
ON_CODRIVER_SEAT = {"phone_codriver_seat": ("phone", build_phone),
                    "colacan_codriver_seat": ("colacan", build_can),
                    "colabottle_codriver_seat": ("colabottle", build_cola_bottle)}


class Objects:
    def __init__(self, rig: dict, coll, importer=None):
        self.rig, self.coll = rig, coll
        self.anchors = {k: Vector(v) for k, v in rig["anchors"].items()}
        self.importer = importer   # builds a Group from a rig asset, or None
        self.groups: dict[str, Group] = {}
        self.luggage_mat = None

    def _group(self, key: str, build, part: str | None = None) -> Group:
        """The group for ``key`` (built on first use); ``part`` names the rig asset that may replace the
        procedural build (default: the key up to its colon, which also names the render instance)."""
        if key not in self.groups:
            asset = self.importer(part or key.split(":")[0]) if self.importer else None
            if asset is not None:
                _label(asset, key.split(":")[0])
            self.groups[key] = asset or build()
        return self.groups[key]

    def _show_only(self, prefix: str, keep: str | None) -> None:
        for key, group in self.groups.items():
            if key.startswith(prefix):
                group.show(key == keep)

    def apply(self, f: dict, hand_pose, can_pose=None) -> None:
        self._child_seat(f)
        self._luggage(f)
        self._phone_in_hand(hand_pose, f.get("phone_screen", "BY_USE"), f.get("phone_case", "GRAPHITE"))
        self._drink_in_hand(can_pose, f.get("drink", "CAN"))
        for feature, (part, build) in ON_CODRIVER_SEAT.items():
            self._on_codriver_seat(feature, f.get(feature) == "YES", part, build)

    def _child_seat(self, f: dict) -> None:
        if f.get("child_seat") != "YES":
            self._show_only("child_seat:", None)
            return
        front = f["child_seat_orientation"] == "FRONT_FACING"
        seat_key = f"child_seat:{'front' if front else 'rear'}"
        seat = self._group(seat_key, lambda: build_child_seat(self.coll, front))
        # an imported seat is one model facing +x: turn it round for rear-facing
        seat.place(self.anchors["child_seat"], (0, 0, math.pi if seat.asset and not front else 0))
        self._show_only("child_seat:", seat_key)   # the child in it is an anny body (blender/people.py)

    def _luggage(self, f: dict) -> None:
        if f.get("luggage") != "YES":
            self._show_only("luggage", None)
            return
        def build():
            group, self.luggage_mat = build_luggage(self.coll)
            return group
        group = self._group("luggage", build)
        if self.luggage_mat is not None:
            M.set_colour(self.luggage_mat, LUGGAGE[f["luggage_colour"]])
        else:  # an imported asset: tint every material it brought
            for obj in group.parts:
                for slot in obj.material_slots:
                    if slot.material and slot.material.node_tree and "Principled BSDF" in slot.material.node_tree.nodes:
                        M.set_colour(slot.material, LUGGAGE[f["luggage_colour"]])
        anchor = self.anchors[f"luggage_{f['luggage_position']}"]
        group.place(anchor, (0, 0, math.radians(f["luggage_orientation"])))
        group.show(True)

    def _phone_in_hand(self, hand_pose, screen: str, case: str) -> None:
        if hand_pose is None:
            self._show_only("phone:", None)
            return
        group = self._group("phone:hand", lambda: build_phone(self.coll, "phone"))
        centre, R, position = hand_pose
        spec = self.rig["phone_positions"][position]
        # the pose's rotation, not the rig's angle: the hand closed round the phone tilted and turned with the head
        group.place(Vector(centre.tolist()), Matrix([list(row) for row in R]).to_euler("XYZ"))
        if not group.asset:
            M.set_colour(bpy.data.materials[case_material("phone")], PHONE_CASES[case])
        group.show(True)
        lit = art.screen_lit(screen, spec.get("at_ear", False))    # dark: only the black glass shows
        for obj in group.parts:
            if obj.name.startswith("phone_screen"):
                obj.hide_render = not lit

    def _drink_in_hand(self, can_pose, kind: str) -> None:
        """The drink in a driver's hand (isu-diverse's driver_hands DRINK and DRINK_LOW): the seat's can model,
        or the cup, bottle or mug ``drink`` names, held where the can would be; its own render instance (not the
        co-driver seat's can, which is a predicted feature)."""
        self._show_only("colacan_in_hand", None)     # then only the one held shows
        if can_pose is None:
            return
        if kind == "CAN":
            group = self._group("colacan_in_hand:CAN", lambda: build_can(self.coll, "colacan_in_hand"), "colacan")
        else:
            group = self._group(f"colacan_in_hand:{kind}", lambda: build_drink(self.coll, kind, "colacan_in_hand"),
                                f"drink_{kind.lower()}")
        centre, R = can_pose
        group.place(Vector((centre - R[:, 2] * CAN_HEIGHT / 2).tolist()),
                    Matrix([list(row) for row in R]).to_euler("XYZ"))
        group.show(True)

    def _on_codriver_seat(self, feature: str, present: bool, part: str, build) -> None:
        if not present:
            self._show_only(feature, None)
            return
        group = self._group(feature, lambda: build(self.coll, feature), part)
        spot = self.rig["codriver_seat"][feature]
        group.place(Vector(spot["position"]), euler_deg(spot["rotation_deg"]))
        group.show(True)


def _label(group: Group, instance: str) -> None:
    """An imported asset shows in the segmentation as the instance it stands for (the phone model
    serves both the hand and the seat)."""
    for obj in group.parts:
        obj.pass_index = INSTANCE_ID[instance]
