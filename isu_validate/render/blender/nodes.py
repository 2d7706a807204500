"""Shader-node building blocks shared by the worker's procedural materials (the people's in
``people_look.py``, the things' in ``materials.py`` and ``mesh.image_material``): each adds one node to a
material's tree, wires its inputs (a socket is linked, a constant is set) and returns its output socket."""
from __future__ import annotations

import bpy


def math(nodes, links, operation: str, a, b=None, c=None, clamp: bool = False):
    """A Math node (``operation`` as Blender names it) on ``a``, ``b`` and ``c``."""
    node = nodes.new("ShaderNodeMath")
    node.operation, node.use_clamp = operation, clamp
    for k, value in enumerate((a, b, c)):
        _feed(links, node.inputs[k], value)
    return node.outputs[0]


def mix(nodes, links, factor, a, b, kind: str = "RGBA"):
    """``a`` blended into ``b`` as ``factor`` goes 0 -> 1; ``kind`` RGBA (colours) or FLOAT."""
    node = nodes.new("ShaderNodeMix")
    node.data_type = kind
    suffix = "Color" if kind == "RGBA" else "Float"
    _feed(links, socket(node.inputs, "Factor_Float"), factor)
    _feed(links, socket(node.inputs, f"A_{suffix}"), a)
    _feed(links, socket(node.inputs, f"B_{suffix}"), b)
    return socket(node.outputs, f"Result_{suffix}")


def multiply(nodes, links, factor, a, b):
    """Colour ``a`` multiplied by colour ``b`` as far as ``factor`` (1: fully)."""
    node = nodes.new("ShaderNodeMix")
    node.data_type, node.blend_type = "RGBA", "MULTIPLY"
    _feed(links, socket(node.inputs, "Factor_Float"), factor)
    _feed(links, socket(node.inputs, "A_Color"), a)
    _feed(links, socket(node.inputs, "B_Color"), b)
    return socket(node.outputs, "Result_Color")


def map_range(nodes, links, value, lo: float, hi: float, lo_in: float = 0.0, hi_in: float = 1.0):
    """``value`` from [lo_in, hi_in] to [lo, hi], clamped."""
    node = nodes.new("ShaderNodeMapRange")
    node.clamp = True
    links.new(value, node.inputs["Value"])
    node.inputs["From Min"].default_value, node.inputs["From Max"].default_value = lo_in, hi_in
    node.inputs["To Min"].default_value, node.inputs["To Max"].default_value = lo, hi
    return node.outputs["Result"]


def noise(nodes, links, scale: float, detail: float = 2.0, vector=None):
    """Noise texture (0..1) over ``vector``, by default the object's own coordinates."""
    node = nodes.new("ShaderNodeTexNoise")
    node.inputs["Scale"].default_value = scale
    node.inputs["Detail"].default_value = detail
    links.new(vector if vector is not None else object_coordinates(nodes), node.inputs["Vector"])
    return node.outputs["Fac"]


def object_coordinates(nodes):
    return nodes.new("ShaderNodeTexCoord").outputs["Object"]


def rgb(nodes, name: str, colour):
    """A named RGB node (a material's colour a scene sets by name later); its output socket."""
    node = nodes.new("ShaderNodeRGB")
    node.name = name
    node.outputs[0].default_value = (*colour, 1.0)
    return node.outputs[0]


def set_rgb(material, name: str, colour) -> None:
    """Set the named RGB node (``rgb``) of a material to a linear colour."""
    material.node_tree.nodes[name].outputs[0].default_value = (*colour, 1.0)


def value(nodes, number: float):
    node = nodes.new("ShaderNodeValue")
    node.outputs[0].default_value = number
    return node.outputs[0]


def bump(nodes, links, height, strength: float, distance_m: float = 0.001, invert: bool = False):
    """A normal bent by ``height`` (0..1) as a relief ``distance_m`` deep at ``strength`` (``invert``:
    high is a groove)."""
    node = nodes.new("ShaderNodeBump")
    node.invert = invert
    node.inputs["Strength"].default_value = strength
    node.inputs["Distance"].default_value = distance_m
    _feed(links, node.inputs["Height"], height)
    return node.outputs["Normal"]


def attribute(nodes, name: str):
    """A mesh attribute (a per-vertex field) by name."""
    node = nodes.new("ShaderNodeAttribute")
    node.attribute_type, node.attribute_name = "GEOMETRY", name
    return node.outputs["Fac"]


def socket(sockets, identifier: str):
    """A socket by identifier (ShaderNodeMix has several sockets of one name, one per data type)."""
    return next(s for s in sockets if s.identifier == identifier)


def _feed(links, target, value) -> None:
    """Link a socket into ``target``, or set a constant (an RGB colour gets its alpha); None leaves it."""
    if isinstance(value, bpy.types.NodeSocket):
        links.new(value, target)
    elif value is not None:
        target.default_value = (*value, 1.0) if isinstance(value, tuple) and len(value) == 3 else value
