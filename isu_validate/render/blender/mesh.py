"""Mesh and material primitives for the procedural builders (runs inside the Blender worker only).

Shapes are built once as unit meshes and placed by their object matrix, so re-posing a scene
changes transforms, never geometry."""
from __future__ import annotations

import math

import bmesh
import bpy
from mathutils import Matrix, Vector

from . import nodes as N

_MESH_CACHE: dict[str, bpy.types.Mesh] = {}


# ---------------------------------------------------------------------- materials
def material(name: str, colour, roughness: float = 0.6, metallic: float = 0.0, emission=None,
             emission_strength: float = 0.0, specular: float = 0.5) -> bpy.types.Material:
    """A Principled BSDF material (linear RGB colour); reused by name."""
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    if mat.get("_isu_built"):
        return mat
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular IOR Level"].default_value = specular
    bsdf.distribution = "GGX"   # multiscatter GGX costs ~10% per sample for no visible gain here
    if emission is not None:
        bsdf.inputs["Emission Color"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission_strength
        # small glowing parts (screen, lamp lens) are seen, not sampled as lights: real lamps light the cabin
        mat.cycles.emission_sampling = "NONE"
    mat.diffuse_color = (*colour, 1.0)
    mat["_isu_built"] = True
    return mat


def image_material(name: str, draw, mapping: str, roughness: float = 0.4, metallic: float = 0.0,
                   emission_strength: float = 0.0, specular: float = 0.5, image: str | None = None
                   ) -> bpy.types.Material:
    """A material showing an image drawn in code: ``draw()`` returns it (``render/product_art.py``: float
    RGBA rows, top first) and is called only when the image ``image`` (default: the material's name) is
    not in the scene yet, so materials showing one picture share it and a built material draws nothing.
    It is mapped from the object's own coordinates: ``"cylinder"`` wraps it once round a unit cylinder's axis
    (u round it, v up its height 0..1), ``"plane"`` lays it on the xy square -0.5..0.5 (a box's face),
    ``"facing_back"`` on the yz square of a unit box seen from -x (a display facing the cabin).
    With ``emission_strength`` the image glows (a screen); like the other small glowing parts it is
    seen, never sampled as a light."""
    mat = material(name, (1.0, 1.0, 1.0), roughness=roughness, metallic=metallic, specular=specular)
    if mat.get("_isu_image"):
        return mat
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = _image(image or name, draw)
    tex.extension = "REPEAT" if mapping == "cylinder" else "EXTEND"
    links.new(_uv(nodes, links, mapping), tex.inputs["Vector"])
    links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    if emission_strength:
        links.new(tex.outputs["Color"], bsdf.inputs["Emission Color"])
        bsdf.inputs["Emission Strength"].default_value = emission_strength
        mat.cycles.emission_sampling = "NONE"
    mat["_isu_image"] = True
    return mat


def _image(name: str, draw) -> bpy.types.Image:
    found = bpy.data.images.get(name)
    if found is not None and found.get("_isu_drawn"):
        return found
    import numpy as np
    rgba = np.asarray(draw(), np.float32)
    h, w = rgba.shape[:2]
    image = bpy.data.images.new(name, w, h, alpha=True, float_buffer=False)
    image.colorspace_settings.name = "sRGB"
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())   # Blender's rows start at the bottom
    image.pack()
    image["_isu_drawn"] = True
    return image


def _uv(nodes, links, mapping: str):
    xyz = nodes.new("ShaderNodeSeparateXYZ")
    links.new(N.object_coordinates(nodes), xyz.inputs["Vector"])
    combine = nodes.new("ShaderNodeCombineXYZ")
    if mapping == "cylinder":          # u = angle / 2 pi + 0.5 round the axis, v = z
        angle = N.math(nodes, links, "ARCTAN2", xyz.outputs["Y"], xyz.outputs["X"])
        links.new(N.math(nodes, links, "MULTIPLY_ADD", angle, 1.0 / (2 * math.pi), 0.5), combine.inputs["X"])
        links.new(xyz.outputs["Z"], combine.inputs["Y"])
    else:
        # (source axis, sign) of u and v: seen from -x, the box's +y is on the viewer's left
        axes = {"plane": (("X", 1.0), ("Y", 1.0)), "facing_back": (("Y", -1.0), ("Z", 1.0))}[mapping]
        for target, (axis, sign) in zip(("X", "Y"), axes):
            links.new(N.math(nodes, links, "MULTIPLY_ADD", xyz.outputs[axis], sign, 0.5), combine.inputs[target])
    return combine.outputs["Vector"]


def set_colour(mat: bpy.types.Material, colour) -> None:
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*colour, 1.0)


def set_emission(mat: bpy.types.Material, strength: float) -> None:
    mat.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"].default_value = strength


# ---------------------------------------------------------------------- unit meshes
def _cached(name: str, build) -> bpy.types.Mesh:
    mesh = _MESH_CACHE.get(name)
    if mesh is None:
        bm = bmesh.new()
        build(bm)
        mesh = bpy.data.meshes.new(name)
        bm.to_mesh(mesh)
        bm.free()
        _MESH_CACHE[name] = mesh
    return mesh


def _smooth(bm) -> None:
    for f in bm.faces:
        f.smooth = True


def unit_cube() -> bpy.types.Mesh:
    """A cube from -0.5 to 0.5."""
    return _cached("u_cube", lambda bm: bmesh.ops.create_cube(bm, size=1.0))


def unit_rounded_box(bevel: float = 0.12) -> bpy.types.Mesh:
    """A cube from -0.5 to 0.5 with bevelled edges (``bevel`` in unit-cube units)."""
    def build(bm):
        bmesh.ops.create_cube(bm, size=1.0)
        bmesh.ops.bevel(bm, geom=list(bm.edges), offset=bevel, segments=3, affect="EDGES", profile=0.5)
        _smooth(bm)
    return _cached(f"u_rbox_{bevel:.3f}", build)


def unit_sphere(segments: int = 24, rings: int = 12) -> bpy.types.Mesh:
    """A sphere of radius 1."""
    def build(bm):
        bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=1.0)
        _smooth(bm)
    return _cached(f"u_sphere_{segments}", build)


def unit_cylinder(segments: int = 20, cap: bool = True) -> bpy.types.Mesh:
    """A cylinder of radius 1 from z = 0 to z = 1."""
    def build(bm):
        bmesh.ops.create_cone(bm, cap_ends=cap, segments=segments, radius1=1.0, radius2=1.0, depth=1.0,
                              matrix=Matrix.Translation((0, 0, 0.5)))
        for f in bm.faces:
            f.smooth = len(f.verts) == 4
    return _cached(f"u_cyl_{segments}_{cap}", build)


def unit_torus(major: float = 1.0, minor: float = 0.1, segments: int = 40) -> bpy.types.Mesh:
    """A torus in the xy plane."""
    def build(bm):
        ring = 10
        verts = []
        for i in range(segments):
            a = 2 * math.pi * i / segments
            for j in range(ring):
                b = 2 * math.pi * j / ring
                r = major + minor * math.cos(b)
                verts.append(bm.verts.new((r * math.cos(a), r * math.sin(a), minor * math.sin(b))))
        for i in range(segments):
            for j in range(ring):
                a, b = i * ring + j, i * ring + (j + 1) % ring
                c, d = ((i + 1) % segments) * ring + (j + 1) % ring, ((i + 1) % segments) * ring + j
                bm.faces.new((verts[a], verts[b], verts[c], verts[d]))
        _smooth(bm)
    return _cached(f"u_torus_{minor:.3f}", build)


def lathe(name: str, profile, segments: int = 32) -> bpy.types.Mesh:
    """A surface of revolution round z through (radius, z) points from the base up, closed at both ends
    (a bottle, a can); smooth-shaded, built once per name. A point on the axis (radius 0) is one vertex
    that the next ring fans out from; an end off the axis is closed by a flat cap."""
    def ring(bm, r, z):
        if r == 0.0:
            return [bm.verts.new((0.0, 0.0, z))] * segments
        return [bm.verts.new((r * math.cos(2 * math.pi * k / segments), r * math.sin(2 * math.pi * k / segments), z))
                for k in range(segments)]

    def build(bm):
        rings = [ring(bm, r, z) for r, z in profile]
        for a, b in zip(rings, rings[1:]):
            for k in range(segments):
                quad = (a[k], a[(k + 1) % segments], b[(k + 1) % segments], b[k])
                corners = list(dict.fromkeys(quad))          # a pole's repeated vertex makes it a triangle
                if len(corners) >= 3:
                    bm.faces.new(corners)
        if profile[0][0] > 0.0:
            bm.faces.new(rings[0][::-1])
        if profile[-1][0] > 0.0:
            bm.faces.new(rings[-1])
        _smooth(bm)
    return _cached(f"lathe_{name}", build)


# ---------------------------------------------------------------------- objects
def arrays_mesh(name: str, n_vertices: int, triangles, slots=None, materials=(), uv_layers: dict | None = None,
                smooth=True) -> bpy.types.Mesh:
    """A triangle mesh from arrays (vertices placed later, e.g. by ``foreach_set("co", ...)``): material
    slot per triangle, per-corner UV layers {name: (triangles, 3, 2)}, smooth shading (per triangle or all)."""
    import numpy as np
    triangles = np.ascontiguousarray(triangles, np.int32)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(n_vertices)
    mesh.loops.add(len(triangles) * 3)
    mesh.polygons.add(len(triangles))
    mesh.loops.foreach_set("vertex_index", triangles.ravel())
    mesh.polygons.foreach_set("loop_start", np.arange(0, len(triangles) * 3, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(triangles), 3, np.int32))
    mesh.polygons.foreach_set("use_smooth", np.broadcast_to(np.asarray(smooth, bool), len(triangles)).copy())
    for mat in materials:
        mesh.materials.append(mat)
    if slots is not None:
        mesh.polygons.foreach_set("material_index", np.ascontiguousarray(slots, np.int32))
    for layer_name, corners in (uv_layers or {}).items():
        layer = mesh.uv_layers.new(name=layer_name)
        layer.data.foreach_set("uv", np.ascontiguousarray(corners, np.float32).ravel())
    mesh.update(calc_edges=True)
    mesh.validate(clean_customdata=False)
    return mesh


def new_object(name: str, mesh: bpy.types.Mesh, mat: bpy.types.Material | None, collection,
               pass_index: int = 0) -> bpy.types.Object:
    if mat is not None and not mesh.materials:
        mesh.materials.append(None)  # one slot; shared meshes carry their material on the object
    obj = bpy.data.objects.new(name, mesh)
    if mat is not None:
        obj.material_slots[0].link = "OBJECT"
        obj.material_slots[0].material = mat
    obj.pass_index = pass_index
    collection.objects.link(obj)
    return obj


def box(name, centre, size, mat, collection, pass_index=0, rotation=(0, 0, 0), rounded: float = 0.0):
    mesh = unit_rounded_box(rounded) if rounded else unit_cube()
    obj = new_object(name, mesh, mat, collection, pass_index)
    obj.location, obj.rotation_euler, obj.scale = centre, rotation, size
    return obj


def ellipsoid(name, centre, radii, mat, collection, pass_index=0, rotation=(0, 0, 0)):
    obj = new_object(name, unit_sphere(), mat, collection, pass_index)
    obj.location, obj.rotation_euler, obj.scale = centre, rotation, radii
    return obj


def cylinder(name, base, radius, height, mat, collection, pass_index=0, segments=20):
    obj = new_object(name, unit_cylinder(segments), mat, collection, pass_index)
    obj.location, obj.scale = base, (radius, radius, height)
    return obj


def segment_matrix(p0, p1, rx: float, ry: float | None = None, twist=None) -> Matrix:
    """Object matrix that stretches a unit z-cylinder from p0 to p1 with radii rx, ry."""
    p0, p1 = Vector(p0), Vector(p1)
    axis = p1 - p0
    length = max(axis.length, 1e-6)
    rot = axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
    scale = Matrix.Diagonal((rx, ry if ry is not None else rx, length, 1.0))
    return Matrix.Translation(p0) @ rot @ scale


def place_segment(obj, p0, p1, rx: float, ry: float | None = None) -> None:
    obj.matrix_world = segment_matrix(p0, p1, rx, ry)


def ribbon_mesh(name: str, points, widths, normals, thickness: float = 0.004) -> bpy.types.Mesh:
    """A strap (seat belt) along ``points`` with its flat side facing ``normals``; a thin closed box
    section so it shades from both sides."""
    bm = bmesh.new()
    rows = []
    n = len(points)
    for i, (p, w, nrm) in enumerate(zip(points, widths, normals)):
        p, nrm = Vector(p), Vector(nrm).normalized()
        tangent = (Vector(points[min(i + 1, n - 1)]) - Vector(points[max(i - 1, 0)])).normalized()
        side = tangent.cross(nrm).normalized() * (w / 2)
        off = nrm * (thickness / 2)
        rows.append([bm.verts.new(p + side + off), bm.verts.new(p - side + off),
                     bm.verts.new(p - side - off), bm.verts.new(p + side - off)])
    for a, b in zip(rows, rows[1:]):
        for k in range(4):
            bm.faces.new((a[k], a[(k + 1) % 4], b[(k + 1) % 4], b[k]))
    bm.faces.new(rows[0][::-1])
    bm.faces.new(rows[-1])
    mesh = bpy.data.meshes.get(name) or bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    return mesh


def load_arrays(path: str) -> dict:
    """The arrays of a host-written .npz (a person's topology or posed state, a garment) by name."""
    import numpy as np

    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}
