"""Objects: the child seat (front- or rear-facing; the child in it is an anny body, see people.py), the
suitcase, the phone in the driver's hand, and the phone, cola can and cola bottle lying on the co-driver
seat (each its own render instance). Each is built the first time a scene needs it (never for scenes that
do not), then only shown, hidden, moved or recoloured."""
from __future__ import annotations

import math

import bpy
from mathutils import Vector

from ..cabin_geometry import CHILD_SEAT_PADS, child_seat_boxes, pitch
from ..labels import INSTANCE_ID
from . import mesh as M
from .cabin import euler_deg

LUGGAGE = {"YELLOW": (0.78, 0.50, 0.01), "ANTHRACITE": (0.028, 0.030, 0.033)}


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
    pad = M.material("child_seat_pad", (0.30, 0.02, 0.02), roughness=0.9)
    for box in child_seat_boxes(front_facing):
        g.add(M.box(box.name, box.centre, box.size, pad if box.name in CHILD_SEAT_PADS else shell, coll, pid,
                    rounded=box.rounded, rotation=(0, pitch(box), 0)))
    if not front_facing:
        handle = g.add(M.new_object("cs_handle", M.unit_torus(1.0, 0.09), shell, coll, pid))
        handle.location, handle.rotation_euler, handle.scale = (0.0, 0, 0.30), (math.pi / 2, 0, 0), (0.2, 0.2, 0.2)
    return g


def build_luggage(coll) -> tuple[Group, bpy.types.Material]:
    """A hard-shell cabin trolley, 0.40 x 0.23 x 0.55 m, standing on the seat."""
    g = Group("luggage", coll)
    pid = INSTANCE_ID["luggage"]
    body_mat = M.material("luggage_shell", LUGGAGE["YELLOW"], roughness=0.35, specular=0.6)
    dark = M.material("luggage_trim", (0.015, 0.015, 0.015), roughness=0.5)
    g.add(M.box("lug_body", (0, 0, 0.295), (0.23, 0.40, 0.55), body_mat, coll, pid, rounded=0.12))
    for k, y in enumerate((-0.12, -0.04, 0.04, 0.12)):  # moulded ribs
        g.add(M.box(f"lug_rib{k}", (0.117, y, 0.295), (0.006, 0.018, 0.48), body_mat, coll, pid, rounded=0.3))
    g.add(M.box("lug_seam", (0, 0, 0.295), (0.236, 0.406, 0.012), dark, coll, pid))
    g.add(M.box("lug_handle", (0, 0, 0.585), (0.04, 0.14, 0.025), dark, coll, pid, rounded=0.3))
    for k, (x, y) in enumerate(((0.08, 0.16), (0.08, -0.16), (-0.08, 0.16), (-0.08, -0.16))):
        g.add(M.cylinder(f"lug_wheel{k}", (x, y, 0.0), 0.022, 0.025, dark, coll, pid, 10))
    return g, body_mat


def build_phone(coll, instance: str, screen_on: bool = True) -> Group:
    """A 150 x 72 x 8 mm phone centred on its origin, long axis along local y, screen on local +z: lit
    while in use (in the hand), dark glass when it lies unused (on the co-driver seat)."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    case = M.material("phone_case", (0.01, 0.01, 0.012), roughness=0.3)
    if screen_on:
        screen = M.material("phone_screen", (0.02, 0.03, 0.05), roughness=0.1,
                            emission=(0.35, 0.55, 1.0), emission_strength=1.6)
    else:
        screen = M.material("phone_screen_off", (0.008, 0.009, 0.011), roughness=0.05, specular=0.9)
    g.add(M.box("phone_body", (0, 0, 0), (0.074, 0.152, 0.009), case, coll, pid, rounded=0.15))
    g.add(M.box("phone_screen", (0, 0, 0.0047), (0.066, 0.140, 0.001), screen, coll, pid))
    return g


def build_cola_bottle(coll, instance: str) -> Group:
    """A 1 l cola bottle (dark liquid, red label), 0.29 m long from the base (origin) along local +z,
    0.089 m across the label."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    liquid = M.material("cola", (0.04, 0.012, 0.005), roughness=0.08, specular=0.9)
    label = M.material("cola_label", (0.6, 0.01, 0.01), roughness=0.5)
    cap = M.material("cola_cap", (0.6, 0.01, 0.01), roughness=0.4)
    g.add(M.cylinder("bottle_body", (0, 0, 0), 0.043, 0.19, liquid, coll, pid))
    g.add(M.cylinder("bottle_label", (0, 0, 0.09), 0.0445, 0.07, label, coll, pid))
    g.add(M.ellipsoid("bottle_shoulder", (0, 0, 0.19), (0.043, 0.043, 0.07), liquid, coll, pid))
    g.add(M.cylinder("bottle_neck", (0, 0, 0.22), 0.016, 0.06, liquid, coll, pid))
    g.add(M.cylinder("bottle_cap", (0, 0, 0.275), 0.018, 0.022, cap, coll, pid))
    return g


def build_can(coll, instance: str) -> Group:
    """A 330 ml cola can, red with silver ends, 0.118 m tall from the base (origin), 0.066 m across."""
    g = Group(instance, coll)
    pid = INSTANCE_ID[instance]
    red = M.material("can_red", (0.55, 0.01, 0.01), roughness=0.25, metallic=0.6)
    silver = M.material("can_top", (0.6, 0.6, 0.62), roughness=0.2, metallic=1.0)
    g.add(M.cylinder("can_body", (0, 0, 0.01), 0.033, 0.10, red, coll, pid))
    g.add(M.cylinder("can_bottom", (0, 0, 0.0), 0.029, 0.01, silver, coll, pid))
    g.add(M.cylinder("can_top", (0, 0, 0.11), 0.029, 0.008, silver, coll, pid))
    return g


def build_phone_lying(coll, instance: str) -> Group:
    return build_phone(coll, instance, screen_on=False)


# ---------------------------------------------------------------------- what a scene asks for
# the things on the co-driver seat: feature -> (asset part, builder); the feature names the instance too
ON_CODRIVER_SEAT = {"phone_codriver_seat": ("phone", build_phone_lying),
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

    def apply(self, f: dict, hand_pose) -> None:
        self._child_seat(f)
        self._luggage(f)
        self._phone_in_hand(hand_pose)
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

    def _phone_in_hand(self, hand_pose) -> None:
        if hand_pose is None:
            self._show_only("phone:", None)
            return
        group = self._group("phone:hand", lambda: build_phone(self.coll, "phone"))
        point, position = hand_pose
        group.place(point, euler_deg(self.rig["phone_positions"][position]["rotation_deg"]))
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
