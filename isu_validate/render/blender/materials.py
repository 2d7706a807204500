"""Procedural materials of the things in the cabin beyond a plain Principled BSDF (``mesh.material``):
see-through plastic and liquid, and woven fabric with stitched seams. All node trees, no image files;
each built once per name. Cheap by design: the presets trace no transmission bounces (refraction would
render black), so see-through is a Transparent BSDF mixed in, more opaque towards grazing angles as
real plastic reflects more there."""
from __future__ import annotations

import bpy

from . import mesh as M


def see_through(name: str, colour, tint, opacity: float, roughness: float = 0.05,
                specular: float = 0.8) -> bpy.types.Material:
    """A glossy surface of ``colour`` letting ``1 - opacity`` of the light through, tinted ``tint``
    (PET round a dark liquid, or an empty clear neck)."""
    mat = M.material(name, colour, roughness=roughness, specular=specular)
    if mat.get("_isu_see_through"):
        return mat
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf, out = nodes["Principled BSDF"], nodes["Material Output"]
    clear = nodes.new("ShaderNodeBsdfTransparent")
    clear.inputs["Color"].default_value = (*tint, 1.0)
    facing = nodes.new("ShaderNodeLayerWeight")
    facing.inputs["Blend"].default_value = 0.35
    fac = math_node(nodes, links, "MULTIPLY_ADD", facing.outputs["Facing"], 1.0 - opacity, opacity)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(fac, mix.inputs["Fac"])
    links.new(clear.outputs["BSDF"], mix.inputs[1])
    links.new(bsdf.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    mat["_isu_see_through"] = True
    return mat


def math_node(nodes, links, operation: str, a, b=None, c=None):
    """A Math node on socket ``a`` with constant ``b`` (and ``c``); its output socket."""
    node = nodes.new("ShaderNodeMath")
    node.operation = operation
    links.new(a, node.inputs[0])
    for k, value in ((1, b), (2, c)):
        if value is not None:
            node.inputs[k].default_value = value
    return node.outputs[0]
