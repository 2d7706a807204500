"""The unoccluded footprint pass (runs inside the Blender worker): for each requested render instance
("part", see ``labels.INSTANCES``), every mesh object the render shows with that pass index is
evaluated (shape keys, modifiers, parenting applied), its triangles rasterised through the render
camera, and the masks written for the host (see ``isu_validate/render/footprint.py``).

A part is whatever carries its pass index: procedural builds, imported assets, or a body mesh whose
vertices the host replaces, with nothing to declare beyond the pass index."""
from __future__ import annotations

import hashlib
import time

import bpy
import numpy as np

from ..footprint import facing_camera, footprints, is_closed, orientation, pack
from ..labels import INSTANCE_ID


# closedness of a face list, by its bytes' digest: it depends on the topology only, which a person
# keeps from frame to frame while its vertices move (the edge check was ~35 ms per person mesh a frame)
_CLOSED: dict[bytes, bool] = {}


def _closed(faces: np.ndarray) -> bool:
    key = hashlib.blake2b(faces.tobytes(), digest_size=16).digest()
    if key not in _CLOSED:
        _CLOSED[key] = is_closed(faces)
    return _CLOSED[key]


def _triangles(obj, depsgraph, cache: dict, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Triangles (T,3,3) of a mesh object as the render sees it, in the camera's OpenCV frame
    (R = R_cabin_from_camera, t = camera position)."""
    evaluated = obj.evaluated_get(depsgraph)
    plain = obj.data.shape_keys is None and not obj.modifiers   # shared unit meshes: read once per frame
    key = obj.data.as_pointer() if plain else None
    if key in cache:
        local = cache[key]
    else:
        mesh = obj.data if plain else evaluated.to_mesh()
        try:
            mesh.calc_loop_triangles()
            co = np.empty(len(mesh.vertices) * 3, np.float64)
            mesh.vertices.foreach_get("co", co)
            idx = np.empty(len(mesh.loop_triangles) * 3, np.int64)
            mesh.loop_triangles.foreach_get("vertices", idx)
            vertices, faces = co.reshape(-1, 3), idx.reshape(-1, 3)
            local = (vertices, faces, orientation(vertices, faces, _closed(faces)))
        finally:
            if not plain:
                evaluated.to_mesh_clear()
        if plain:
            cache[key] = local
    m = np.array(evaluated.matrix_world)
    vertices, faces, orient = local
    # local -> cabin -> camera in one affine map, applied to vertices (fewer than triangle corners)
    tris = (vertices @ (R.T @ m[:3, :3]).T + R.T @ (m[:3, 3] - t))[faces]
    orient *= int(np.sign(np.linalg.det(m[:3, :3])))   # a mirroring transform turns the mesh inside out
    return tris[facing_camera(tris, orient)] if orient else tris


def part_objects(scene, names) -> dict[str, list]:
    """The mesh objects the camera sees for each named part."""
    ids = {INSTANCE_ID[n]: n for n in names}
    found = {n: [] for n in names}
    for obj in scene.objects:
        if obj.type == "MESH" and obj.pass_index in ids and not obj.hide_render and obj.visible_camera:
            found[ids[obj.pass_index]].append(obj)
    return found


def write_footprints(scene, names: list[str], camera: dict, path: str) -> dict:
    """Rasterise each named part's footprint in the pinhole image Blender renders; save the packed
    masks to ``path`` (.npy). Returns timings and triangle counts."""
    t0 = time.perf_counter()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    R, t = np.array(camera["rotation"], float), np.array(camera["position"], float)
    w, h = camera["width"], camera["height"]
    cache: dict = {}
    parts, triangles = [], {}
    for name, objects in part_objects(scene, names).items():
        tris = [_triangles(o, depsgraph, cache, R, t) for o in objects]
        parts.append(np.concatenate(tris) if tris else np.zeros((0, 3, 3)))
        triangles[name] = len(parts[-1])
    np.save(path, pack(footprints(parts, camera["f"], camera["cx"], camera["cy"], w, h)))
    return {"footprint_s": time.perf_counter() - t0, "footprint_triangles": triangles}
