"""The procedural cabin: shell, window glass (the world outside shows through), dashboard with instrument
cluster, display and vents, centre console and stack, door panels, headliner fittings, the bonnet and door
mirrors seen through the windows, seats, steering wheel, seat-belt hardware. Built once per worker from the
cabin rig; its colours and seat covers follow the scene's style (cabin_style.py)."""
from __future__ import annotations

import math

import bpy
from mathutils import Euler, Vector

from ..cabin_geometry import RIM_TUBE, pitch, seat_boxes
from ..cabin_geometry import wheel_frame as geometry_wheel_frame
from .. import product_art as art
from ..labels import INSTANCE_ID
from . import materials
from . import mesh as M
from .cabin_style import CabinStyle

# the parts that keep one colour in every style (isu-diverse's `cabin_trim` recolours the rest: cabin_style.py)
WHEEL = (0.012, 0.012, 0.012)
GRILLE = (0.008, 0.008, 0.009)
ACCENT = (0.30, 0.30, 0.31)        # satin metal-look strips and knobs
PAINT = (0.05, 0.07, 0.10)         # the body seen through the windows: bonnet and mirrors, a dark blue metallic


def build_cabin(rig: dict, coll) -> tuple[dict, CabinStyle]:
    """The cabin's objects by part (``cabin``, the seats, ``steering_wheel``) and its style materials."""
    s = rig["shell"]
    cab = INSTANCE_ID["cabin"]
    style = CabinStyle()
    xr, xf, hw, roof, belt = s["x_rear"], s["x_front"], s["half_width"], s["roof"], s["belt_line"]
    length, xmid = xf - xr, (xf + xr) / 2
    roof_front = xf - 0.62
    trim, plastic = style["trim"], style["plastic"]
    parts = [
        M.box("floor", (xmid, 0, -0.03), (length, 2 * hw, 0.06), style["carpet"], coll, cab),
        M.box("roof", ((roof_front + xr) / 2, 0, roof + 0.02), (roof_front - xr, 2 * hw, 0.04), style["headliner"],
              coll, cab),
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
    parts += _dashboard(s, style, coll, cab)
    parts += _console(style, coll, cab)
    parts += _door_panels(s, style, coll, cab)
    parts += _headliner_fittings(s, style, coll, cab)
    parts += _body(s, coll, cab)
    _glass(s, coll)
    objects = {"cabin": parts}
    for key, seat in rig["seats"].items():
        name = {"driver": "driver_seat", "passenger": "passenger_seat", "rear": "rear_bench"}[key]
        objects[name] = _seat(name, seat, style, coll, INSTANCE_ID[name])
    objects["steering_wheel"] = _steering_wheel(rig["steering_wheel"], coll, INSTANCE_ID["steering_wheel"])
    belt_hw = rig["seat_belt"]
    metal = M.material("belt_metal", (0.5, 0.5, 0.52), roughness=0.3, metallic=1.0)
    buckle = M.material("belt_buckle", (0.015, 0.015, 0.016), roughness=0.5)
    objects["cabin"] += [M.box("belt_anchor", belt_hw["upper_anchor"], (0.04, 0.02, 0.06), metal, coll, cab),
                         M.box("belt_buckle", belt_hw["buckle"], (0.05, 0.035, 0.08), buckle, coll, cab)]
    return objects, style


def _pillar(name, p0, p1, mat, coll, pid):
    obj = M.new_object(name, M.unit_cube(), mat, coll, pid)
    mid, axis = (p0 + p1) / 2, p1 - p0
    obj.matrix_world = (M.Matrix.Translation(mid) @ axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
                        @ M.Matrix.Diagonal((0.09, 0.06, axis.length, 1.0)))
    return obj


def _dashboard(s, style, coll, pid):
    """Dashboard: a dark top, the instrument cluster under its hood, the centre display, four air vents, a
    metal-look strip across its face, the glovebox, and the centre stack with the climate knobs."""
    xf, hw, top = s["x_front"], s["half_width"], s["dashboard_top"]
    plastic, trim = style["plastic"], style["trim"]
    display = M.image_material("centre_display", art.navigation_screen, "facing_back", roughness=0.08,
                               emission_strength=0.3, specular=0.8)   # night-dimmed: it must not light the cabin
    dial = M.image_material("instrument_dial", art.instrument_dial, "facing_back", roughness=0.1,
                            emission_strength=0.25, specular=0.8)
    accent = M.material("accent", ACCENT, roughness=0.35, metallic=0.6)
    tilt = math.radians(-15)
    face = xf - 0.29                       # the dashboard's face towards the cabin (dash_lower's back)
    gauges = [M.box(f"gauge_{k}", (xf - 0.441, 0.37 + dy, top + 0.01), (0.002, 0.07, 0.07), dial, coll, pid)
              for k, dy in enumerate((0.045, -0.045))]
    out = gauges + [
        M.box("centre_display", (xf - 0.3125, 0.0, top + 0.04), (0.001, 0.24, 0.135), display, coll, pid,
              rotation=(0, tilt, 0)),
        M.box("dash_lower", (xf - 0.12, 0, top / 2 + 0.1), (0.34, 2 * hw, top - 0.2), plastic, coll, pid),
        M.box("dash_top", (xf - 0.18, 0, top - 0.03), (0.5, 2 * hw, 0.08), style["dash"], coll, pid,
              rotation=(0, math.radians(-8), 0)),
        M.box("cluster_hood", (xf - 0.36, 0.37, top + 0.01), (0.16, 0.36, 0.08), style["dash"], coll, pid,
              rounded=0.2),
        M.box("centre_screen", (xf - 0.30, 0.0, top + 0.04), (0.02, 0.26, 0.15), trim, coll, pid,
              rotation=(0, math.radians(-15), 0)),
        M.box("glovebox", (xf - 0.28, -0.37, top - 0.17), (0.04, 0.42, 0.16), trim, coll, pid),
        M.box("dash_strip", (face - 0.004, 0, top - 0.16), (0.01, 2 * hw - 0.1, 0.025), accent, coll, pid),
        M.box("centre_stack", (face - 0.05, 0, 0.5), (0.1, 0.22, 0.26), plastic, coll, pid, rounded=0.1),
    ]
    for k, dy in enumerate((-0.06, 0.0, 0.06)):
        knob = M.new_object(f"climate_knob_{k}", M.unit_cylinder(16), accent, coll, pid)
        M.place_segment(knob, Vector((face - 0.1, dy, 0.52)), Vector((face - 0.118, dy, 0.52)), 0.018)
        out.append(knob)
    for k, y in enumerate((0.66, 0.09, -0.09, -0.66)):
        out += _vent(f"vent_{k}", Vector((face, y, top - 0.09)), coll, pid)
    return out


def _vent(name, centre, coll, pid):
    """An air vent on the dashboard's face: a black bezel and four slats set in it, angled down."""
    black = M.material("vent", (0.006, 0.006, 0.007), roughness=0.6)
    slat = M.material("vent_slat", (0.02, 0.02, 0.022), roughness=0.45)
    w, h = 0.11, 0.06
    out = [M.box(f"{name}_bezel", centre - Vector((0.006, 0, 0)), (0.014, w, h), black, coll, pid, rounded=0.25)]
    for k in range(4):
        z = centre.z - h / 2 + h * (k + 0.5) / 4
        out.append(M.box(f"{name}_slat{k}", (centre.x - 0.015, centre.y, z), (0.018, w - 0.012, 0.005), slat, coll,
                         pid, rotation=(0, math.radians(20), 0)))
    return out


def _console(style, coll, pid):
    """On the centre console: a gear lever in its boot and two cup holders (clear of the hands at P9)."""
    black = M.material("console_black", (0.01, 0.01, 0.011), roughness=0.5)
    accent = M.material("accent", ACCENT, roughness=0.35, metallic=0.6)
    boot = M.box("gear_boot", (0.46, 0, 0.41), (0.09, 0.08, 0.03), black, coll, pid, rounded=0.4)
    lever = M.new_object("gear_lever", M.unit_cylinder(12), black, coll, pid)
    M.place_segment(lever, Vector((0.46, 0, 0.41)), Vector((0.45, 0, 0.5)), 0.011)
    knob = M.ellipsoid("gear_knob", (0.45, 0, 0.515), (0.026, 0.024, 0.024), accent, coll, pid)
    out = [boot, lever, knob]
    for k, y in enumerate((0.045, -0.045)):
        holder = M.new_object(f"cup_holder_{k}", M.unit_cylinder(20), black, coll, pid)
        M.place_segment(holder, Vector((0.24, y, 0.398)), Vector((0.24, y, 0.404)), 0.036)
        out.append(holder)
    return out


def _door_panels(s, style, coll, pid):
    """On each door's inner face, front and rear: an armrest with window switches and a pull handle, an
    inset panel, a map pocket and a speaker grille low down."""
    hw, belt = s["half_width"], s["belt_line"]
    grille = M.material("speaker_grille", GRILLE, roughness=0.9, specular=0.1)
    switches = M.material("window_switches", (0.01, 0.01, 0.011), roughness=0.4)
    trim, plastic = style["trim"], style["plastic"]
    out = []
    for side in (1, -1):
        face = side * hw
        for k, x in enumerate((0.25, -0.62)):
            out += [
                M.box(f"door_insert_{side}_{k}", (x, face - side * 0.004, belt - 0.20), (0.55, 0.01, 0.16),
                      style["insert"], coll, pid, rounded=0.1),
                M.box(f"door_armrest_{side}_{k}", (x - 0.03, face - side * 0.035, belt - 0.30), (0.42, 0.07, 0.05),
                      trim, coll, pid, rounded=0.3),
                M.box(f"door_switches_{side}_{k}", (x + 0.08, face - side * 0.04, belt - 0.272), (0.1, 0.035, 0.008),
                      switches, coll, pid, rounded=0.3),
                M.box(f"door_handle_{side}_{k}", (x + 0.16, face - side * 0.012, belt - 0.12), (0.12, 0.02, 0.03),
                      plastic, coll, pid, rounded=0.4),
                M.box(f"door_pocket_{side}_{k}", (x - 0.02, face - side * 0.03, 0.30), (0.40, 0.05, 0.07),
                      plastic, coll, pid, rounded=0.2),
            ]
            speaker = M.new_object(f"door_speaker_{side}_{k}", M.unit_cylinder(24), grille, coll, pid)
            M.place_segment(speaker, Vector((x + 0.12, face, 0.15)), Vector((x + 0.12, face - side * 0.006, 0.15)),
                            0.065)
            out.append(speaker)
    return out


def _headliner_fittings(s, style, coll, pid):
    """Under the roof: sun visors folded up in front of the front seats and grab handles over the doors."""
    hw, roof = s["half_width"], s["roof"]
    out = [M.box(f"sun_visor_{side}", (0.17, side * 0.37, roof - 0.018), (0.17, 0.34, 0.022), style["headliner"],
                 coll, pid, rounded=0.3, rotation=(0, math.radians(-6), 0)) for side in (1, -1)]
    for k, (x, side) in enumerate(((0.05, -1), (-0.75, 1), (-0.75, -1))):
        out.append(M.box(f"grab_handle_{k}", (x, side * (hw - 0.035), roof - 0.05), (0.2, 0.025, 0.03),
                         style["plastic"], coll, pid, rounded=0.4))
    return out


def _body(s, coll, pid):
    """What is seen of the car's body through the windows: the bonnet ahead and the door mirrors."""
    xf, hw, top = s["x_front"], s["half_width"], s["dashboard_top"]
    paint = M.material("paint", PAINT, roughness=0.25, metallic=0.5)
    out = [M.box("bonnet", (xf + 0.6, 0, top - 0.12), (1.2, 2 * hw + 0.04, 0.06), paint, coll, pid,
                 rotation=(0, math.radians(5), 0))]
    for side in (1, -1):
        out.append(M.box(f"door_mirror_{side}", (xf - 0.12, side * (hw + 0.16), top + 0.08), (0.1, 0.2, 0.11),
                         paint, coll, pid, rounded=0.35))
    return out


def _glass(s, coll) -> list:
    """Glass in the side and rear windows, seen by the camera only: light and shadows pass through it (the
    window lights and the sun stand outside), and it is no render instance (pass index 0: the segmentation
    and depth show what lies behind it, as Cycles' passes skip surfaces this clear). The windscreen has none:
    the rig's mirror camera hangs in front of the windscreen's line (the shell's windscreen is lower than a
    real one), and a pane there would lie across everything that camera sees."""
    xr, xf, hw, roof, belt = s["x_rear"], s["x_front"], s["half_width"], s["roof"], s["belt_line"]
    roof_front = xf - 0.62
    panes = {"rear_window": [(xr - 0.01, hw, 0.9), (xr - 0.01, -hw, 0.9), (xr - 0.01, -hw, roof),
                             (xr - 0.01, hw, roof)]}
    for side in (1, -1):
        y = side * (hw + 0.03)
        panes[f"side_window_{side}"] = [(xr + 0.24, y, belt), (xf - 0.02, y, belt), (roof_front, y, roof),
                                        (xr + 0.24, y, roof)]
    glass = materials.glass()
    out = []
    for name, corners in panes.items():
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(corners, [], [(0, 1, 2, 3)])
        obj = M.new_object(name, mesh, glass, coll, 0)
        obj.visible_shadow = obj.visible_diffuse = obj.visible_glossy = False
        obj.visible_transmission = obj.visible_volume_scatter = False
        out.append(obj)
    return out


def _seat(name, seat, style, coll, pid):
    """Cushion, base, tilted backrest and headrest(s): the boxes of ``cabin_geometry.seat_boxes``."""
    fabric, plain = style.covers
    plastic = style["plastic"]
    parts = []
    for box in seat_boxes(name, seat):
        mat = plastic if box.name.endswith("_base") else plain if "_headrest" in box.name else fabric
        parts.append(M.box(box.name, box.centre, box.size, mat, coll, pid, rotation=(0, pitch(box), 0),
                           rounded=box.rounded))
    return parts


def wheel_frame(wheel: dict):
    """(centre, lateral axis, up-in-rim-plane axis, normal towards the driver) of the steering wheel."""
    return tuple(Vector(v) for v in geometry_wheel_frame(wheel))


def _steering_wheel(wheel, coll, pid):
    centre, _, _, normal = wheel_frame(wheel)
    r = wheel["radius"]
    mat = M.material("wheel", WHEEL, 0.45)
    rim = M.new_object("wheel_rim", M.unit_torus(1.0, RIM_TUBE), mat, coll, pid)
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
