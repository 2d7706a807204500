"""Simple hair: a shell over the scalp, lifted off the posed head along its normals.

anny ships no hair. A style is a set of scalp vertices (chosen on the standing rest body by a hairline
that runs round the head) and a thickness per vertex; the shell's triangles are anny's own between
those vertices, so the hair follows every pose and face without a separate rig. Short hair (men, the
child) stays close to the head and ends at the ears and the nape; the women's bob covers the ears and
the nape and flares out towards its lower edge, so hair length differs by gender while the bodies and
faces differ too (hair is not the only cue)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skeleton import Posed

# hairline height above the eyes (share of a 1.75 m adult's size) against the cosine of the angle
# from the face's direction round the head: 1 = the forehead, 0 = above the ears, -1 = the nape
_HAIRLINES = {
    "short": ((-1.0, -0.060), (0.0, 0.012), (0.35, 0.022), (1.0, 0.052)),
    "bob": ((-1.0, -0.170), (-0.3, -0.125), (0.2, -0.095), (0.45, 0.020), (1.0, 0.045)),
}


PAINTED = 0.004   # the hair colour is painted on the scalp this far (m) beyond the shell's edge


@dataclass(frozen=True)
class HairStyle:
    name: str
    scalp: np.ndarray        # anny vertex indices under the hair
    faces: np.ndarray        # triangles, indexing into ``scalp``
    thickness: np.ndarray    # per scalp vertex (m)
    field: np.ndarray        # per anny vertex: height above the hairline (m), > 0 on the scalp


def hair_style(rest: Posed, faces: np.ndarray, candidates: np.ndarray, name: str, scale_thickness: float = 1.0
               ) -> HairStyle:
    """The style ``name`` ("short" or "bob") on a rest body; ``candidates`` marks vertices that may
    carry hair (head and neck)."""
    v = rest.vertices.astype(np.float64)
    eyes = (rest.head("eye.L") + rest.head("eye.R")) / 2
    s = (eyes[2] - rest.head("root")[2]) / 0.69
    centre = eyes + np.array([0.0, 0.075 * s, 0.0])     # the body faces -Y at rest
    d = v - centre
    cos_front = -d[:, 1] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    knots = np.array(_HAIRLINES[name])
    hairline = eyes[2] + s * np.interp(cos_front, knots[:, 0], knots[:, 1])
    above = (v[:, 2] - hairline) / s
    # the shell starts a little inside the painted hairline, whose smooth edge is what one sees
    scalp = np.flatnonzero(candidates & (above > PAINTED))
    # taper to nothing at the hairline where it meets the face; the lower edge of a bob stays thick
    taper = np.clip((above[scalp] - PAINTED) / 0.015, 0.0, 1.0)
    if name == "bob":
        base = 0.012 + 0.035 * np.clip((eyes[2] - v[scalp, 2]) / (0.12 * s), 0.0, 1.0)
        taper = np.where(cos_front[scalp] > 0.3, taper, 1.0)
    else:
        base = np.full(len(scalp), 0.007)
    thickness = base * s * taper * scale_thickness
    index = np.full(len(v), -1)
    index[scalp] = np.arange(len(scalp))
    inside = (index[faces] >= 0).all(axis=1)
    field = np.where(candidates, above * s, -1.0)
    return HairStyle(name, scalp, index[faces[inside]].astype(np.int32), thickness.astype(np.float32),
                     field.astype(np.float32))


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals of a triangle mesh."""
    tri = vertices[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    out = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(out, faces[:, k], n)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


def hair_vertices(style: HairStyle, vertices: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The hair shell's vertices on a posed body."""
    return (vertices[style.scalp] + normals[style.scalp] * style.thickness[:, None]).astype(np.float32)
