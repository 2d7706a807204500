"""The procedural cabin: shell, windows (open: the environment shows through), dashboard, console,
seats, steering wheel, seat-belt hardware. Built once per worker from the cabin rig."""
from __future__ import annotations

import math

from mathutils import Euler, Vector

from ..cabin_geometry import RIM_TUBE, pitch, seat_boxes
from ..cabin_geometry import wheel_frame as geometry_wheel_frame
from .. import product_art as art
from ..labels import INSTANCE_ID
from . import materials
from . import mesh as M

# linear-RGB colours of a plausible dark-grey interior with lighter seats (so dark objects stand out)
PLASTIC = (0.025, 0.025, 0.028)
TRIM = (0.06, 0.058, 0.055)
HEADLINER = (0.32, 0.31, 0.29)
FABRIC = (0.12, 0.115, 0.11)
CARPET = (0.02, 0.02, 0.02)


def build_cabin(rig: dict, coll) -> dict:
    s = rig["shell"]
    cab = INSTANCE_ID["cabin"]
    plastic = M.material("plastic", PLASTIC, roughness=0.55)
    trim = M.material("trim", TRIM, roughness=0.7)
    liner = M.material("headliner", HEADLINER, roughness=0.9, specular=0.2)
    carpet = M.material("carpet", CARPET, roughness=1.0, specular=0.1)
    xr, xf, hw, roof, belt = s["x_rear"], s["x_front"], s["half_width"], s["roof"], s["belt_line"]
    length, xmid = xf - xr, (xf + xr) / 2
    roof_front = xf - 0.62
    parts = [
        M.box("floor", (xmid, 0, -0.03), (length, 2 * hw, 0.06), carpet, coll, cab),
        M.box("roof", ((roof_front + xr) / 2, 0, roof + 0.02), (roof_front - xr, 2 * hw, 0.04), liner, coll, cab),
        M.box("rear_wall", (xr - 0.02, 0, 0.45), (0.04, 2 * hw, 0.9), trim, coll, cab),
        M.box("parcel_shelf", (xr + 0.12, 0, 0.88), (0.26, 2 * hw, 0.03), trim, coll, cab),
        M.box("centre_console", (0.26, 0, 0.2), (0.78, 0.2, 0.4), plastic, coll, cab, rounded=0.08),
        M.box("armrest", (0.02, 0, 0.43), (0.3, 0.18, 0.06), trim, coll, cab, rounded=0.2),
        M.box("mirror", (0.68, 0, 1.15), (0.03, 0.24, 0.07), plastic, coll, cab, rounded=0.2),
    ]
    for side in (1, -1):
        y = side * (hw + 0.02)
        parts += [
            M.box(f"door_{side}", (xmid, y, belt / 2), (length, 0.04, belt), trim, coll, cab),
            M.box(f"sill_{side}", (xmid, side * (hw - 0.05), belt - 0.02), (length - 0.3, 0.1, 0.04),
                  plastic, coll, cab),
            M.box(f"b_pillar_{side}", (-0.32, side * hw, (belt + roof) / 2), (0.12, 0.06, roof - belt),
                  trim, coll, cab),
            M.box(f"c_pillar_{side}", (xr + 0.12, side * hw, (belt + roof) / 2), (0.24, 0.06, roof - belt),
                  trim, coll, cab),
            _pillar(f"a_pillar_{side}", Vector((xf, side * hw, s["dashboard_top"])),
                    Vector((roof_front, side * (hw - 0.03), roof)), trim, coll, cab),
        ]
    parts += _dashboard(s, plastic, trim, coll, cab)
    parts += _door_panels(s, plastic, trim, coll, cab)
    objects = {"cabin": parts}
    for key, seat in rig["seats"].items():
        name = {"driver": "driver_seat", "passenger": "passenger_seat", "rear": "rear_bench"}[key]
        objects[name] = _seat(name, seat, coll, INSTANCE_ID[name])
    objects["steering_wheel"] = _steering_wheel(rig["steering_wheel"], plastic, coll, INSTANCE_ID["steering_wheel"])
    belt_hw = rig["seat_belt"]
    metal = M.material("belt_metal", (0.5, 0.5, 0.52), roughness=0.3, metallic=1.0)
    objects["cabin"] += [M.box("belt_anchor", belt_hw["upper_anchor"], (0.04, 0.02, 0.06), metal, coll, cab),
                         M.box("belt_buckle", belt_hw["buckle"], (0.05, 0.035, 0.08), plastic, coll, cab)]
    return objects


def _pillar(name, p0, p1, mat, coll, pid):
    obj = M.new_object(name, M.unit_cube(), mat, coll, pid)
    mid, axis = (p0 + p1) / 2, p1 - p0
    obj.matrix_world = (M.Matrix.Translation(mid) @ axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
                        @ M.Matrix.Diagonal((0.09, 0.06, axis.length, 1.0)))
    return obj


def _dashboard(s, plastic, trim, coll, pid):
    xf, hw, top = s["x_front"], s["half_width"], s["dashboard_top"]
    display = M.image_material("centre_display", art.navigation_screen, "facing_back", roughness=0.08,
                               emission_strength=0.3, specular=0.8)   # night-dimmed: it must not light the cabin
    dial = M.image_material("instrument_dial", art.instrument_dial, "facing_back", roughness=0.1,
                            emission_strength=0.25, specular=0.8)
    tilt = math.radians(-15)
    gauges = [M.box(f"gauge_{k}", (xf - 0.441, 0.37 + dy, top + 0.01), (0.002, 0.07, 0.07), dial, coll, pid)
              for k, dy in enumerate((0.045, -0.045))]
    return gauges + [
        M.box("centre_display", (xf - 0.3125, 0.0, top + 0.04), (0.001, 0.24, 0.135), display, coll, pid,
              rotation=(0, tilt, 0)),
        M.box("dash_lower", (xf - 0.12, 0, top / 2 + 0.1), (0.34, 2 * hw, top - 0.2), plastic, coll, pid),
        M.box("dash_top", (xf - 0.18, 0, top - 0.03), (0.5, 2 * hw, 0.08), plastic, coll, pid,
              rotation=(0, math.radians(-8), 0)),
        M.box("cluster_hood", (xf - 0.36, 0.37, top + 0.01), (0.16, 0.36, 0.08), plastic, coll, pid, rounded=0.2),
        M.box("centre_screen", (xf - 0.30, 0.0, top + 0.04), (0.02, 0.26, 0.15), trim, coll, pid,
              rotation=(0, math.radians(-15), 0)),
        M.box("glovebox", (xf - 0.28, -0.37, top - 0.17), (0.04, 0.42, 0.16), trim, coll, pid),
    ]


def _door_panels(s, plastic, trim, coll, pid):
    """On each door's inner face, front and rear: an armrest with a pull handle, an inset fabric panel
    and a speaker grille low down."""
    hw, belt = s["half_width"], s["belt_line"]
    grille = M.material("speaker_grille", (0.008, 0.008, 0.009), roughness=0.9, specular=0.1)
    insert = M.material("door_insert", (0.09, 0.087, 0.083), roughness=0.95, specular=0.15)
    out = []
    for side in (1, -1):
        face = side * hw
        for k, x in enumerate((0.25, -0.62)):
            out += [
                M.box(f"door_insert_{side}_{k}", (x, face - side * 0.004, belt - 0.20), (0.55, 0.01, 0.16),
                      insert, coll, pid, rounded=0.1),
                M.box(f"door_armrest_{side}_{k}", (x - 0.03, face - side * 0.035, belt - 0.30), (0.42, 0.07, 0.05),
                      trim, coll, pid, rounded=0.3),
                M.box(f"door_handle_{side}_{k}", (x + 0.16, face - side * 0.012, belt - 0.12), (0.12, 0.02, 0.03),
                      plastic, coll, pid, rounded=0.4),
            ]
            speaker = M.new_object(f"door_speaker_{side}_{k}", M.unit_cylinder(24), grille, coll, pid)
            M.place_segment(speaker, Vector((x, face, 0.18)), Vector((x, face - side * 0.006, 0.18)), 0.075)
            out.append(speaker)
    return out


def _seat(name, seat, coll, pid):
    """Cushion, base, tilted backrest and headrest(s): the boxes of ``cabin_geometry.seat_boxes``."""
    fabric = materials.seat_cover("seat_fabric", FABRIC)
    plain = materials.seat_cover("headrest_fabric", FABRIC, quilted=False)
    plastic = M.material("plastic", PLASTIC)
    parts = []
    for box in seat_boxes(name, seat):
        mat = plastic if box.name.endswith("_base") else plain if "_headrest" in box.name else fabric
        parts.append(M.box(box.name, box.centre, box.size, mat, coll, pid, rotation=(0, pitch(box), 0),
                           rounded=box.rounded))
    return parts


def wheel_frame(wheel: dict):
    """(centre, lateral axis, up-in-rim-plane axis, normal towards the driver) of the steering wheel."""
    return tuple(Vector(v) for v in geometry_wheel_frame(wheel))


def _steering_wheel(wheel, mat, coll, pid):
    centre, _, _, normal = wheel_frame(wheel)
    r = wheel["radius"]
    rim = M.new_object("wheel_rim", M.unit_torus(1.0, RIM_TUBE), M.material("wheel", (0.012, 0.012, 0.012), 0.45),
                       coll, pid)
    rot = normal.to_track_quat("Z", "Y").to_euler()
    rim.location, rim.rotation_euler, rim.scale = centre, rot, (r, r, r)
    hub = M.new_object("wheel_hub", M.unit_cylinder(), mat, coll, pid)
    M.place_segment(hub, centre - normal * 0.03, centre + normal * 0.03, r * 0.35)
    spokes = []
    for k, ang in enumerate((90, 270, 180)):
        a = math.radians(ang)
        _, e_y, e_up, _ = wheel_frame(wheel)
        tip = centre + (e_y * math.cos(a) + e_up * math.sin(a)) * r
        spoke = M.new_object(f"wheel_spoke{k}", M.unit_cylinder(8), mat, coll, pid)
        M.place_segment(spoke, centre, tip, 0.014, 0.03)
        spokes.append(spoke)
    column = M.new_object("wheel_column", M.unit_cylinder(), mat, coll, pid)
    M.place_segment(column, centre - normal * 0.02, centre - normal * 0.3, 0.04)
    return [rim, hub, column, *spokes]


def euler_deg(rotation_deg) -> Euler:
    return Euler([math.radians(a) for a in rotation_deg], "XYZ")
