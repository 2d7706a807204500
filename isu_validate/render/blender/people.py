"""People in the Blender worker: anny bodies posed on the host (``render/people``), shown here as
persistent meshes whose vertices are swapped per scene (a few milliseconds), never rebuilt.

A person is two objects that share one anny topology split at the neck - the head (with the hair:
its own segmentation instance, ``driver_face`` for the driver) and the rest of the body - plus the
hair shell and, over a bob, its locks (tapered cards). The driver also has the seat belt, laid on the
body by the host, and holds the phone where the host placed it."""
from __future__ import annotations

import bpy
import numpy as np
from mathutils import Vector

from ..labels import INSTANCE_ID
from . import mesh as M
from .clothes import Outfit
from .people_look import Look

# isu-diverse's seat_belt_colour (linear RGB): CHARCOAL is isu-paper's belt. Webbing is mostly black or dark grey
# in real cars, lighter grey or beige beside light trims; the belt is its diagonal across the body, not its colour
BELTS = {"CHARCOAL": (0.10, 0.10, 0.11), "BLACK": (0.018, 0.018, 0.020), "GREY": (0.26, 0.26, 0.27),
         "BEIGE": (0.40, 0.32, 0.22)}


class Person:
    """One anny body: built from a topology file once, re-posed from state files."""

    def __init__(self, name: str, coll, body_id: int, head_id: int):
        self.name, self.coll, self.body_id, self.head_id = name, coll, body_id, head_id
        self.topology_path = None
        self.state_path = None
        self.state: dict = {}        # the arrays of state_path: a scene seen again loads nothing
        self.parts: dict[str, bpy.types.Object] = {}
        self.maps: dict[str, np.ndarray] = {}
        self.look: Look | None = None

    def show(self, visible: bool) -> None:
        for obj in self.parts.values():
            obj.hide_render = not visible

    def set(self, topology: str, state: str) -> dict:
        """Show this person in a state; returns the state's arrays (belt, phone...)."""
        if topology != self.topology_path:
            self._build(M.load_arrays(topology))
            self.topology_path = topology
            self.state_path = None
        if state != self.state_path:
            data = self.state = M.load_arrays(state)
            for part, index in self.maps.items():
                source = data[part] if part in ("hair", "locks") else data["vertices"][index]
                mesh = self.parts[part].data
                mesh.vertices.foreach_set("co", np.ascontiguousarray(source, np.float32).ravel())
                if part not in ("hair", "locks"):    # the expression's skin folds (none for a face at rest)
                    crease = data["crease"][index] if "crease" in data else np.zeros(len(index), np.float32)
                    mesh.attributes["crease"].data.foreach_set("value", np.ascontiguousarray(crease, np.float32))
                mesh.update()
            self.state_path = state
        self.show(True)
        return self.state

    # ------------------------------------------------------------------ building
    def _build(self, topo: dict) -> None:
        for obj in self.parts.values():   # the object and its mesh: nothing left behind in bpy.data
            mesh = obj.data
            bpy.data.objects.remove(obj)
            bpy.data.meshes.remove(mesh)
        faces, slots, head = topo["faces"], topo["slots"], topo["head"]
        self.look = self.look or Look(self.name, str(topo["lips_mask"]))
        mats = [self.look.slot(str(n)) for n in topo["slot_names"]]
        fields = {str(k)[6:]: topo[k] for k in topo if str(k).startswith("field_")}
        self.parts, self.maps = {}, {}
        for part, chosen, pid in (("body", ~head, self.body_id), ("head", head, self.head_id)):
            used, local = np.unique(faces[chosen], return_inverse=True)
            mesh = _mesh(f"{self.name}_{part}", len(used), local.reshape(-1, 3), slots[chosen], mats,
                         {"UVMap": topo["uv"].reshape(-1, 3, 2)[chosen],
                          "EyeUV": topo["eye_uv"].reshape(-1, 3, 2)[chosen]})
            for field, values in fields.items():
                mesh.attributes.new(field, "FLOAT", "POINT").data.foreach_set(
                    "value", np.ascontiguousarray(values[used], np.float32))
            mesh.attributes.new("crease", "FLOAT", "POINT")          # per state: set by ``set``
            self.parts[part] = self._object(f"{self.name}_{part}", mesh, pid)
            self.maps[part] = used
        hair_mat = self.look.slot("hair")
        mesh = _mesh(f"{self.name}_hair", len(topo["hair_i"]), topo["hair_faces"],
                     np.zeros(len(topo["hair_faces"]), np.uint8), [hair_mat], None)
        self.parts["hair"] = self._object(f"{self.name}_hair", mesh, self.head_id)
        self.maps["hair"] = topo["hair_i"]    # only its length counts: the hair's vertices come whole
        if len(topo.get("lock_faces", ())):   # a bob's locks: opaque cards in the hair's material
            cards = topo["lock_faces"]
            mesh = _mesh(f"{self.name}_locks", int(cards.max()) + 1, cards, np.zeros(len(cards), np.uint8),
                         [hair_mat], None)
            self.parts["locks"] = self._object(f"{self.name}_locks", mesh, self.head_id)
            self.maps["locks"] = np.arange(int(cards.max()) + 1)   # its vertices come whole, as the hair's

    def _object(self, name, mesh, pid):
        obj = bpy.data.objects.new(name, mesh)
        obj.pass_index = pid
        self.coll.objects.link(obj)
        return obj

    def set_look(self, skin: str, hair: str, shirt: str | None = None) -> None:
        self.look.set(skin, hair, shirt)


_mesh = M.arrays_mesh    # a mesh from arrays (one home: mesh.py)


class Driver:
    """The driver: an anny body in clothes (``clothes.py``), the seat belt over them when worn, the phone in hand, and
    the driver's seat slid on its track to fit (with the belt buckle mounted on it); a can in a hand off the wheel."""

    def __init__(self, rig: dict, coll, seat_parts: list):
        # one persistent person per topology (the genders differ in topology), so a change of
        # driver between frames swaps vertices instead of rebuilding meshes
        self.coll, self.persons, self.person = coll, {}, None
        self.outfits: dict[str, Outfit] = {}     # per topology, like the persons
        self.belt = _Belt(rig["seat_belt"], coll)
        self.phone_hand = self.can_hand = None
        self.seat = [(obj, obj.location.x) for obj in seat_parts]

    def slide_seat(self, shift: float) -> None:
        for obj, x in self.seat:
            obj.location.x = x + shift

    def apply(self, f: dict, spec: dict) -> None:
        if spec["topology"] not in self.persons:
            self.persons[spec["topology"]] = Person(f"driver{len(self.persons)}", self.coll,
                                                    INSTANCE_ID["driver"], INSTANCE_ID["driver_face"])
        for topology, person in self.persons.items():
            if topology != spec["topology"]:
                person.show(False)
        self.person = self.persons[spec["topology"]]
        data = self.person.set(spec["topology"], spec["state"])
        self.slide_seat(float(data["seat_shift"]))
        self.person.set_look(f["driver_skin_tone"], f["driver_hair_colour"], f["tshirt_colour"])
        if spec["topology"] not in self.outfits:
            self.outfits[spec["topology"]] = Outfit(f"{self.person.name}_outfit", self.coll,
                                                    INSTANCE_ID["driver"], INSTANCE_ID["driver_face"])
        for topology, outfit in self.outfits.items():
            if topology != spec["topology"]:
                outfit.hide()
        dressed = self.outfits[spec["topology"]].apply(spec["outfit"], spec["dressed"], f)
        self.belt.apply(dressed, f["seat_belt"] == "YES", f["seat_belt_colour"])   # the straps lie on the clothes
        self.phone_hand = self.can_hand = None
        if "phone_centre" in data:   # the phone lies in the posed palm, turned as the pose turned it
            self.phone_hand = (np.asarray(data["phone_centre"], float), np.asarray(data["phone_rotation"], float),
                               f["phone_position"])
        if "can_centre" in data:     # a can held to drink from (a rig hand position that holds one)
            self.can_hand = (np.asarray(data["can_centre"], float), np.asarray(data["can_rotation"], float))

    def hide(self) -> None:
        for person in self.persons.values():
            person.show(False)
        for outfit in self.outfits.values():
            outfit.hide()
        self.belt.hide()
        self.slide_seat(0.0)
        self.phone_hand = self.can_hand = None

    def hand_pose(self):
        """(centre, 3x3 rotation: the rig's angle tilted in the hand and turned with the head, phone position)
        when a hand holds the phone, else None."""
        return self.phone_hand

    def can_pose(self):
        """(centre, 3x3 rotation: local z from base to top) when a hand holds a can, else None."""
        return self.can_hand


class Child:
    def __init__(self, coll):
        self.person = Person("child", coll, INSTANCE_ID["child"], INSTANCE_ID["child"])

    def apply(self, spec: dict | None, f: dict) -> None:
        """The child, in its one-piece suit, has the driver's skin tone and hair colour (a family)."""
        if spec is None:
            self.person.show(False)
            return
        self.person.set(spec["topology"], spec["state"])
        self.person.set_look(f["driver_skin_tone"], f["driver_hair_colour"])


class _Belt:
    """Shoulder and lap strap laid on the body by the host; a retracted strap hangs on the B-pillar."""

    def __init__(self, hw: dict, coll):
        self.hw = {k: Vector(v) for k, v in hw.items()}
        self.mat = M.material("belt", BELTS["CHARCOAL"], roughness=0.6)
        self.worn = [self._obj(n, coll, INSTANCE_ID["seat_belt"]) for n in ("belt_shoulder", "belt_lap")]
        # an unused belt is part of the car: its mask class is cabin, so "seat_belt" means worn
        self.retracted = self._obj("belt_retracted", coll, INSTANCE_ID["cabin"])
        up = self.hw["upper_anchor"]
        pts = [up, up - Vector((0.0, 0.0, 0.38))]
        self.retracted.data = M.ribbon_mesh("belt_retracted", pts, [0.048] * 2, [Vector((0, -1, 0))] * 2)
        self.key = None

    def _obj(self, name, coll, pid):
        obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
        obj.data.materials.append(self.mat)
        obj.pass_index = pid
        coll.objects.link(obj)
        return obj

    def hide(self) -> None:
        for obj in [*self.worn, self.retracted]:
            obj.hide_render = True

    def apply(self, data: dict, worn: bool, colour: str) -> None:
        M.set_colour(self.mat, BELTS[colour])    # the car's belt: worn or hanging on the pillar
        for obj in self.worn:
            obj.hide_render = not worn
        self.retracted.hide_render = worn
        if not worn:
            return
        for obj, strap in zip(self.worn, ("belt_diagonal", "belt_lap")):
            points, normals = data[strap], data[f"{strap}_normals"]
            M.ribbon_mesh(obj.data.name, [Vector(p) for p in points.tolist()], [0.048] * len(points),
                          [Vector(n) for n in normals.tolist()])
