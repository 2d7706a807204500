"""The driver's clothes and accessories in the worker: garment meshes cut and posed on the host
(``render/people/garments.py``, ``accessories.py``) shown as persistent objects whose vertices are swapped
per scene, and their materials: a fabric with a sheen, folds shaded where the body bends (the host's
per-vertex crumple), and a print (stripes, check, a logo on the chest, a shirt's buttons) that follows the
body (it is drawn in rest-body coordinates).

Colours are linear RGB albedos, written as the sRGB a technician would match. The top's colour is the
scene's ``tshirt_colour`` (the predicted feature: under an open jacket it is the T-shirt's)."""
from __future__ import annotations

import math

import bpy
import numpy as np

from ...srgb import linear_from_srgb8 as srgb8   # colours written as the 8-bit sRGB a technician matches
from . import mesh as M
from . import nodes as N


TOP = {"BLACK": (0.012, 0.012, 0.013), "WHITE": (0.80, 0.80, 0.78)}   # as the painted T-shirt was
PRINT = {"RED": srgb8(170, 30, 36), "NAVY": srgb8(30, 40, 80), "GREY": srgb8(120, 120, 122),
         "GREEN": srgb8(40, 110, 60), "YELLOW": srgb8(220, 180, 40)}
JACKET = {"BLACK": srgb8(24, 24, 26), "NAVY": srgb8(32, 40, 66), "BROWN": srgb8(92, 62, 40),
          "OLIVE": srgb8(82, 86, 52), "GREY": srgb8(110, 110, 112), "BEIGE": srgb8(190, 170, 135)}
TROUSERS = {"NAVY": (0.02, 0.03, 0.07), "BLACK": srgb8(26, 26, 28), "GREY": srgb8(96, 96, 100),
            "DENIM": srgb8(60, 80, 120), "BEIGE": srgb8(186, 164, 126)}
CAP = srgb8(44, 62, 112)
_PRINTS = ("STRIPES", "CHECK", "LOGO")
# rest-body coordinates (m, the hips' joint at the origin, the body facing -Y) of the chest print's middle
# and the shirt's button step
_LOGO = (0.0, 0.40)
_BUTTON_STEP = 0.075
_STRINGS_END = 0.38       # how low (rest z) a hoodie's drawstrings hang


class Outfit:
    """One driver topology's garments and accessories: objects built once per outfit file."""

    def __init__(self, name: str, coll, body_id: int, head_id: int):
        self.name, self.coll, self.body_id, self.head_id = name, coll, body_id, head_id
        self.built: dict[str, dict[str, bpy.types.Object]] = {}    # outfit file -> objects by part
        self.dressed_path = None
        self.data: dict = {}            # the dressed arrays of dressed_path
        self.current = None
        self.fabric = {slot: _fabric(f"{name}_{slot}") for slot in ("top", "outer", "trousers", "cap")}
        self.frame = M.material(f"{name}_frame", (0.012, 0.010, 0.010), roughness=0.25)
        self.lens = M.material(f"{name}_lens", (0.004, 0.004, 0.005), roughness=0.03, specular=1.0)
        self.strap = M.material(f"{name}_strap", (0.015, 0.013, 0.012), roughness=0.45)
        self.steel = M.material(f"{name}_steel", (0.55, 0.55, 0.56), roughness=0.3, metallic=1.0)

    def hide(self) -> None:
        for objects in self.built.values():
            for obj in objects.values():
                obj.hide_render = True

    def apply(self, outfit: str, dressed: str, f: dict) -> dict:
        """Show the outfit on the posed body; returns the dressed arrays (the belt lies on the clothes)."""
        if outfit not in self.built:
            self.built[outfit] = self._build(M.load_arrays(outfit))
        self.hide()
        objects = self.built[outfit]
        if dressed != self.dressed_path:     # the same posed body again (another light, colour...): no reload
            self.data = M.load_arrays(dressed)
        data = self.data
        if dressed != self.dressed_path or outfit != self.current:
            for part, obj in objects.items():
                mesh = obj.data
                mesh.vertices.foreach_set("co", np.ascontiguousarray(data[f"{part}_co"], np.float32).ravel())
                if f"{part}_crumple" in data:
                    mesh.attributes["crumple"].data.foreach_set("value", np.ascontiguousarray(data[f"{part}_crumple"]))
                mesh.update()
            self.dressed_path, self.current = dressed, outfit
        shown = {"top", "outer", "trousers"} & set(objects)
        eyewear = f.get("driver_eyewear", "NONE")
        if eyewear == "GLASSES":
            shown.add("glasses")
        elif eyewear == "SUNGLASSES":
            shown |= {"sunglasses", "lenses"}
        if f.get("driver_cap") == "YES":
            shown |= {"cap", "brim"}
        if f.get("driver_watch") == "YES":
            shown |= {"watch", "band"}
        for part, obj in objects.items():
            obj.hide_render = part not in shown
        self._colour(f)
        return data

    def _colour(self, f: dict) -> None:
        top = self.fabric["top"]
        N.set_rgb(top, "colour_base", TOP[f["tshirt_colour"]])
        N.set_rgb(top, "colour_print", PRINT[f.get("driver_print_colour", "NAVY")])
        for kind in _PRINTS:
            top.node_tree.nodes[f"print_{kind.lower()}"].outputs[0].default_value = float(
                f.get("driver_top_print", "PLAIN") == kind)
        top.node_tree.nodes["buttons"].outputs[0].default_value = float(f.get("driver_top") == "SHIRT")
        top.node_tree.nodes["hoodie"].outputs[0].default_value = float(f.get("driver_top") == "HOODIE")
        N.set_rgb(self.fabric["outer"], "colour_base", JACKET[f.get("driver_jacket_colour", "BLACK")])
        N.set_rgb(self.fabric["trousers"], "colour_base", TROUSERS[f.get("driver_trousers_colour", "NAVY")])
        N.set_rgb(self.fabric["cap"], "colour_base", CAP)

    def _build(self, outfit: dict) -> dict[str, bpy.types.Object]:
        objects = {}
        for slot in [*map(str, outfit["slots"]), "cap", "band"]:
            tri = outfit[f"{slot}_faces"]
            mesh = M.arrays_mesh(f"{self.name}_{slot}", len(outfit[f"{slot}_i"]), tri,
                                 smooth=~outfit[f"{slot}_band"].astype(bool))
            mesh.materials.append(self.strap if slot == "band" else self.fabric[slot])
            rest = mesh.attributes.new("rest", "FLOAT_VECTOR", "POINT")
            rest.data.foreach_set("vector", np.ascontiguousarray(outfit[f"{slot}_rest"], np.float32).ravel())
            mesh.attributes.new("fold_u", "FLOAT", "POINT").data.foreach_set(
                "value", np.ascontiguousarray(outfit[f"{slot}_fold_u"], np.float32))
            mesh.attributes.new("crumple", "FLOAT", "POINT")
            objects[slot] = self._object(mesh, self.head_id if slot == "cap" else self.body_id)
        for part, mats in (("glasses", self.frame), ("sunglasses", self.frame), ("lenses", self.lens),
                           ("brim", self.fabric["cap"]), ("watch", self.steel)):
            tri = outfit[f"{part}_f"]
            mesh = M.arrays_mesh(f"{self.name}_{part}", len(outfit[f"{part}_v"]), tri,
                                 smooth=np.full(len(tri), part != "brim"))
            mesh.materials.append(mats)
            objects[part] = self._object(mesh, self.body_id if part == "watch" else self.head_id)
        return objects

    def _object(self, mesh, pid):
        obj = bpy.data.objects.new(mesh.name, mesh)
        obj.pass_index = pid
        obj.hide_render = True
        self.coll.objects.link(obj)
        return obj


def _switch(nodes, name: str):
    node = nodes.new("ShaderNodeValue")
    node.name = name
    node.outputs[0].default_value = 0.0
    return node.outputs[0]


# ---------------------------------------------------------------------- the fabric
def _fabric(name: str) -> bpy.types.Material:
    """Cloth: a rough, dielectric base with a sheen at grazing angles (fibres catch light), fold ridges
    shaded where the host's crumple says the body bends the garment, and the print switched on by name
    (``print_stripes``, ``print_check``, ``print_logo``, ``buttons``)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.distribution = "GGX"
    bsdf.inputs["Roughness"].default_value = 0.85
    bsdf.inputs["Specular IOR Level"].default_value = 0.3
    bsdf.inputs["Sheen Weight"].default_value = 0.6
    bsdf.inputs["Sheen Roughness"].default_value = 0.4
    sep = nodes.new("ShaderNodeSeparateXYZ")
    rest = nodes.new("ShaderNodeAttribute")
    rest.attribute_type, rest.attribute_name = "GEOMETRY", "rest"
    links.new(rest.outputs["Vector"], sep.inputs[0])
    x, y, z = sep.outputs["X"], sep.outputs["Y"], sep.outputs["Z"]
    base = N.rgb(nodes, "colour_base", TOP["WHITE"])
    ink = N.rgb(nodes, "colour_print", PRINT["NAVY"])
    stripes = _bands(nodes, links, z, 0.030, 0.25)
    # gingham: two crossing sets of bands, half-tone where one runs, full ink where they cross
    check = N.math(nodes, links, "MULTIPLY", N.math(nodes, links, "ADD", _bands(nodes, links, x, 0.045, 0.5),
                                                   _bands(nodes, links, z, 0.045, 0.5)), 0.5)
    front = N.math(nodes, links, "LESS_THAN", y, 0.0)
    logo = N.math(nodes, links, "MULTIPLY", _logo(nodes, links, x, z), front)
    ink_share = N.value(nodes, 0.0)
    for mask, kind in ((stripes, "stripes"), (check, "check"), (logo, "logo")):
        ink_share = N.math(nodes, links, "MULTIPLY_ADD", mask, _switch(nodes, f"print_{kind}"), ink_share)
    colour = N.mix(nodes, links, ink_share, base, ink)
    buttons = N.math(nodes, links, "MULTIPLY", _buttons(nodes, links, x, z, front), _switch(nodes, "buttons"))
    colour = N.mix(nodes, links, buttons, colour, (0.55, 0.55, 0.52))
    strings = N.math(nodes, links, "MULTIPLY", _hoodie(nodes, links, x, z, front), _switch(nodes, "hoodie"))
    colour = N.mix(nodes, links, strings, colour, (0.42, 0.42, 0.40))
    # folds: ridges a few centimetres apart across the bend, only where the body compresses the cloth
    crumple = N.attribute(nodes, "crumple")
    wobble = N.noise(nodes, links, 9.0, 1.0, rest.outputs["Vector"])       # folds are never parallel lines
    phase = N.math(nodes, links, "MULTIPLY_ADD", wobble, 9.0, N.math(nodes, links, "MULTIPLY", x, 20.0))
    wave = N.math(nodes, links, "SINE", N.math(nodes, links, "MULTIPLY_ADD", N.attribute(nodes, "fold_u"),
                                               2 * math.pi / 0.028, phase))
    # ... in patches: a fold runs out after a few centimetres
    patches = N.map_range(nodes, links, N.noise(nodes, links, 7.0, 1.0, rest.outputs["Vector"]), 0.0, 1.0, 0.4, 0.6)
    depth = N.math(nodes, links, "MULTIPLY", crumple, patches)
    colour = N.multiply(nodes, links, N.math(nodes, links, "MULTIPLY", depth, 0.3), colour,
                        N.mix(nodes, links, N.math(nodes, links, "MULTIPLY_ADD", wave, 0.5, 0.5), (0.6, 0.6, 0.6),
                              (1.0, 1.0, 1.0)))
    links.new(colour, bsdf.inputs["Base Color"])
    # the ridges are shade in the colour, not relief: a bump on flat white cloth is what 3 samples and the
    # denoiser render least like a converged frame (bench render, 2 scenes against 16-spp references:
    # SSIM 0.9707 with the relief, 0.9722 without; isu-blender-8 0.9724); the mesh's billow is the relief
    return mat


def _bands(nodes, links, coordinate, period: float, share: float):
    """1 on bands across ``coordinate`` ``period`` apart, each ``share`` of it wide."""
    wave = N.math(nodes, links, "SINE", N.math(nodes, links, "MULTIPLY", coordinate, 2 * math.pi / period))
    return N.math(nodes, links, "GREATER_THAN", wave, math.cos(math.pi * share))


def _logo(nodes, links, x, z):
    """A round print in the middle of the chest: a ring round a disc."""
    dx = N.math(nodes, links, "SUBTRACT", x, _LOGO[0])
    dz = N.math(nodes, links, "SUBTRACT", z, _LOGO[1])
    r = _length(nodes, links, dx, dz)
    ring = N.math(nodes, links, "MULTIPLY", N.math(nodes, links, "LESS_THAN", r, 0.065),
                  N.math(nodes, links, "GREATER_THAN", r, 0.050))
    return N.math(nodes, links, "MAXIMUM", ring, N.math(nodes, links, "LESS_THAN", r, 0.032))


def _hoodie(nodes, links, x, z, front):
    """A hoodie's two drawstrings hanging from its neckline, 4 cm either side of the middle."""
    across = N.math(nodes, links, "LESS_THAN", N.math(nodes, links, "ABSOLUTE", N.math(
        nodes, links, "SUBTRACT", N.math(nodes, links, "ABSOLUTE", x), 0.04)), 0.003)
    down = N.math(nodes, links, "GREATER_THAN", z, _STRINGS_END)
    return N.math(nodes, links, "MULTIPLY", N.math(nodes, links, "MULTIPLY", across, down), front)


def _buttons(nodes, links, x, z, front):
    """A shirt's buttons down the middle of its front."""
    dz = N.math(nodes, links, "PINGPONG", z, _BUTTON_STEP / 2)     # 0 at each button's height
    r = _length(nodes, links, x, dz)
    return N.math(nodes, links, "MULTIPLY", N.math(nodes, links, "LESS_THAN", r, 0.0055), front)


def _length(nodes, links, a, b):
    """sqrt(a² + b²)."""
    squares = N.math(nodes, links, "MULTIPLY_ADD", a, a, N.math(nodes, links, "MULTIPLY", b, b))
    return N.math(nodes, links, "SQRT", squares)
