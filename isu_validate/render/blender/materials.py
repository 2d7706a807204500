"""Procedural materials of the things in the cabin beyond a plain Principled BSDF (``mesh.material``):
see-through plastic and liquid, woven fabric, seat covers of fabric or leather with stitched seams, and
window glass. All node trees, no image files; each built once per name (seat covers are then recoloured and
turned to leather by node values). Cheap by design: the presets trace no transmission bounces (refraction
would render black), so see-through is a Transparent BSDF mixed in, more opaque towards grazing angles as
real plastic reflects more there."""
from __future__ import annotations

import bpy

from . import mesh as M
from . import nodes as N


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
    fac = N.math(nodes, links, "MULTIPLY_ADD", facing.outputs["Facing"], 1.0 - opacity, opacity)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(fac, mix.inputs["Fac"])
    links.new(clear.outputs["BSDF"], mix.inputs[1])
    links.new(bsdf.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    mat["_isu_see_through"] = True
    return mat


def seat_cover(name: str, colour, quilted: bool = True) -> bpy.types.Material:
    """A car seat's cover, woven fabric or leather (``set_cover``), in each box's own coordinates (-0.5..0.5
    across, so it fits every seat part): a mottled tone; unless not ``quilted`` (a headrest), a darker middle
    insert between two lengthwise stitched seams, quilted by seams across it. Each seam is a soft groove about
    a centimetre wide (in the bump and a little darker), not a hairline: a line thinner than a pixel flickers
    at 2 samples and the denoiser smears it. Leather is smoother in tone, glossier and pleated the same way."""
    mat = M.material(name, colour, roughness=0.95, specular=0.2)
    if mat.get("_isu_cover"):
        return mat
    mat["_isu_cover"] = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    base = N.rgb(nodes, "cover_colour", colour)
    leather = N.value(nodes, 0.0)
    leather.node.name = "cover_leather"
    fabric_tone = N.multiply(nodes, links, N.noise(nodes, links, 30.0, 2.0), base, (1.25, 1.2, 1.15))
    leather_tone = N.multiply(nodes, links, N.noise(nodes, links, 6.0, 1.0), base, (1.12, 1.1, 1.08))
    colour_out = N.mix(nodes, links, leather, fabric_tone, leather_tone)
    links.new(N.map_range(nodes, links, leather, 0.95, 0.42), bsdf.inputs["Roughness"])
    links.new(N.map_range(nodes, links, leather, 0.2, 0.55), bsdf.inputs["Specular IOR Level"])
    if not quilted:
        links.new(colour_out, bsdf.inputs["Base Color"])
        return mat
    xyz = nodes.new("ShaderNodeSeparateXYZ")
    links.new(N.object_coordinates(nodes), xyz.inputs["Vector"])
    across = N.math(nodes, links, "ABSOLUTE", xyz.outputs["Y"])
    insert = N.math(nodes, links, "LESS_THAN", across, 0.27)
    lengthwise = _groove(nodes, links, N.math(nodes, links, "ABSOLUTE",
                                                 N.math(nodes, links, "SUBTRACT", across, 0.27)), 0.015)
    # along the part: x on a cushion's top, z up a backrest (the other is constant on that face)
    along = N.math(nodes, links, "ADD", xyz.outputs["X"], xyz.outputs["Z"])
    phase = N.math(nodes, links, "FRACT", N.math(nodes, links, "MULTIPLY", along, 6.0))
    to_seam = N.math(nodes, links, "SUBTRACT", 0.5,                # 0.5 - |phase - 0.5|, then / 6
                        N.math(nodes, links, "ABSOLUTE", N.math(nodes, links, "SUBTRACT", phase, 0.5)))
    quilt = _groove(nodes, links, N.math(nodes, links, "DIVIDE", to_seam, 6.0), 0.012)
    seam = N.math(nodes, links, "MAXIMUM", lengthwise, N.math(nodes, links, "MULTIPLY", quilt, insert))
    colour_out = N.multiply(nodes, links, insert, colour_out, (0.72, 0.72, 0.72))
    colour_out = N.multiply(nodes, links, seam, colour_out, (0.6, 0.6, 0.6))
    links.new(colour_out, bsdf.inputs["Base Color"])
    links.new(N.bump(nodes, links, seam, 0.5, invert=True), bsdf.inputs["Normal"])     # a seam is a groove
    return mat


def set_cover(mat: bpy.types.Material, colour, leather: float) -> None:
    """A seat cover's colour and how much leather it is (0: fabric, 1: leather)."""
    nodes = mat.node_tree.nodes
    nodes["cover_colour"].outputs[0].default_value = (*colour, 1.0)
    nodes["cover_leather"].outputs[0].default_value = leather


def _groove(nodes, links, distance, half_width: float):
    """1 on a seam, falling linearly to 0 at ``half_width`` from it (in the box's own units)."""
    return N.math(nodes, links, "MULTIPLY_ADD", distance, -1.0 / half_width, 1.0, clamp=True)   # 1 - d / w


def woven(name: str, colour, roughness: float = 0.9) -> bpy.types.Material:
    """Woven fabric (child-seat pads, straps): a mottled tone and lumpy cloth in the bump, both from
    noise in the object's own coordinates, so they scale with the part."""
    mat = M.material(name, colour, roughness=roughness, specular=0.2)
    if mat.get("_isu_woven"):
        return mat
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    tone = N.multiply(nodes, links, N.noise(nodes, links, 12.0), colour, (1.35, 1.3, 1.3))
    links.new(tone, bsdf.inputs["Base Color"])
    # the cloth's lumpiness, coarse enough to resolve at 2 samples (a true weave is below a pixel)
    links.new(N.bump(nodes, links, N.noise(nodes, links, 40.0, 1.0), 0.15), bsdf.inputs["Normal"])
    mat["_isu_woven"] = True
    return mat


def glass(name: str = "window_glass") -> bpy.types.Material:
    """Window glass: clear and a little green, without reflections. A Fresnel-weighted glossy reflection of
    the cabin was tried: at 3 samples its noise made the denoiser blur the world behind the glass, and the
    exterior's SSIM to the 64-sample reference fell from 0.99 to 0.96 (standard's mean by 0.006)."""
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    if mat.get("_isu_glass"):
        return mat
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    clear, out = nodes.new("ShaderNodeBsdfTransparent"), nodes.new("ShaderNodeOutputMaterial")
    clear.inputs["Color"].default_value = (0.86, 0.92, 0.89, 1.0)
    links.new(clear.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = (0.86, 0.92, 0.89, 0.2)
    mat["_isu_glass"] = True
    return mat
