"""Simple hair: a shell over the scalp, lifted off the posed head along its normals.

anny ships no hair. A style is a set of scalp vertices (chosen on the standing rest body by a hairline
that runs round the head) and a thickness per vertex; the shell's triangles are anny's own between
those vertices, so the hair follows every pose and face without a separate rig. Short hair (men, the
child) stays close to the head, fuller on top, with sideburns, and ends above the ears and at the nape;
the women's bob covers the ears and the nape and flares out towards its lower edge, so hair length
differs by gender while the bodies and faces differ too (hair is not the only cue)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .skeleton import Posed

# hairline height above the eyes (share of a 1.75 m adult's size) against the cosine of the angle
# from the face's direction round the head: 1 = the forehead, 0 = above the ears, -1 = the nape
_HAIRLINES = {
    # short: sideburns in front of the ears (the hairline dips by the temples)
    "short": ((-1.0, -0.060), (0.0, 0.012), (0.08, -0.030), (0.2, -0.030), (0.3, 0.022), (1.0, 0.052)),
    "bob": ((-1.0, -0.170), (-0.3, -0.125), (0.2, -0.095), (0.45, 0.020), (1.0, 0.045)),
    "buzz": ((-1.0, -0.050), (0.0, 0.015), (0.35, 0.026), (1.0, 0.058)),
}
STYLES = tuple(_HAIRLINES)


PAINTED = 0.004   # the hair colour is painted on the scalp this far (m) beyond the shell's edge


@dataclass(frozen=True)
class HairStyle:
    """A hair shell: each of its vertices lies on the body between anny vertices ``i`` and ``j`` (at
    ``t`` from i; i == j inside the scalp), lifted ``thickness`` off the skin."""
    name: str
    i: np.ndarray
    j: np.ndarray
    t: np.ndarray
    faces: np.ndarray        # triangles, indexing the shell's vertices
    thickness: np.ndarray    # per shell vertex (m)
    field: np.ndarray        # per anny vertex: height above the hairline (m), > 0 on the scalp


@dataclass(frozen=True)
class HeadFrame:
    """Where a rest body's head is: the eyes' midpoint, the body's size against a 1.75 m adult, and per
    vertex its offset from the head's middle and the cosine of its bearing round the head from the
    face's direction (1 the forehead, 0 above the ears, -1 the nape)."""
    eyes: np.ndarray
    size: float
    offset: np.ndarray
    cos_front: np.ndarray


def head_frame(rest: Posed) -> HeadFrame:
    v = rest.vertices.astype(np.float64)
    eyes = (rest.head("eye.L") + rest.head("eye.R")) / 2
    s = (eyes[2] - rest.head("root")[2]) / 0.69
    d = v - (eyes + np.array([0.0, 0.075 * s, 0.0]))      # the head's middle; the body faces -Y at rest
    return HeadFrame(eyes, s, d, -d[:, 1] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9))


def hair_style(rest: Posed, faces: np.ndarray, candidates: np.ndarray, name: str, scale_thickness: float = 1.0
               ) -> HairStyle:
    """The style ``name`` (one of STYLES) on a rest body; ``candidates`` marks vertices that may carry
    hair (head and neck). The shell is cut exactly along its edge line (not along anny's triangles), a
    little inside the painted hairline, so its rim is as smooth as the hairline."""
    v = rest.vertices.astype(np.float64)
    head = head_frame(rest)
    eyes, s, d, cos_front = head.eyes, head.size, head.offset, head.cos_front
    knots = np.array(_HAIRLINES[name])
    hairline = eyes[2] + s * np.interp(cos_front, knots[:, 0], knots[:, 1])
    above = (v[:, 2] - hairline) / s
    # taper to nothing at the hairline where it meets the face; the lower edge of a bob stays thick
    taper = np.clip((above - PAINTED) / 0.015, 0.0, 1.0)
    if name == "bob":
        base = 0.012 + 0.035 * np.clip((eyes[2] - v[:, 2]) / (0.12 * s), 0.0, 1.0)
        taper = np.where(cos_front > 0.3, taper, 1.0)
    elif name == "buzz":       # clipped a few millimetres long: the scalp's shape shows through
        base = np.full(len(v), 0.0025)
    else:                      # short: fuller on top than at the sides
        base = 0.006 + 0.008 * np.clip((v[:, 2] - eyes[2]) / (0.12 * s), 0.0, 1.0)
    thickness = base * s * taper * scale_thickness * _clumps(d / s)
    edge = np.where(candidates, above - PAINTED, -1.0)            # > 0 under the shell
    i, j, t, shell = _clip(faces, edge)
    thickness = ((1 - t) * thickness[i] + t * thickness[j]).astype(np.float32)
    style = HairStyle(name, i, j, t, shell, thickness, np.where(candidates, above * s, -1.0).astype(np.float32))
    return _without_slivers(style, v, faces)


def _without_slivers(style: HairStyle, v: np.ndarray, faces: np.ndarray) -> HairStyle:
    """The style without triangles under 0.1 mm² at rest: a cut through (almost) a vertex leaves slivers
    that no pixel shows but that give degenerate normals."""
    tri = hair_vertices(style, v, vertex_normals(v, faces))[style.faces].astype(np.float64)
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) / 2
    return replace(style, faces=style.faces[area > 1e-7])


def _clumps(d: np.ndarray) -> np.ndarray:
    """A smooth, fixed waviness of the hair's depth (0.6-1.4): locks of a few centimetres, so the outline
    is not a helmet's. A sum of plane waves over the position round the head's centre (deterministic:
    the same hair on every frame)."""
    waves = 3.0 * np.array([[31.0, 7.0, 23.0], [-11.0, 37.0, 13.0], [19.0, -29.0, 41.0], [43.0, 17.0, -9.0]])
    phases = np.array([0.3, 1.7, 2.9, 4.1])
    return 1.0 + 0.4 * np.sin(d @ waves.T + phases).mean(axis=1) * 2.0 / np.sqrt(len(phases))


def _clip(faces: np.ndarray, f: np.ndarray):
    """The part of a triangle mesh where the vertex field f > 0, cut along f = 0 (winding kept).
    Returns the new vertices as (i, j, t) points on anny's edges, and the triangles."""
    points: dict[tuple[int, int], int] = {}
    spec: list[tuple[int, int, float]] = []

    def vertex(a: int) -> int:
        return _point(points, spec, (a, a), (a, a, 0.0))

    def crossing(a: int, b: int) -> int:      # where f changes sign on edge a-b (a inside)
        lo, hi = min(a, b), max(a, b)
        t = f[lo] / (f[lo] - f[hi])
        return _point(points, spec, (lo, hi), (lo, hi, float(t)))

    inside = f[faces] > 0
    out = []
    for tri, pos in zip(faces[inside.any(axis=1)], inside[inside.any(axis=1)]):
        if pos.all():
            out.append([vertex(a) for a in tri])
            continue
        k = int(np.flatnonzero(pos)[0]) if pos.sum() == 1 else int(np.flatnonzero(~pos)[0])
        a, b, c = np.roll(tri, -k)             # the odd one out first, winding kept
        if pos.sum() == 1:                      # a inside: a triangle
            out.append([vertex(a), crossing(a, b), crossing(a, c)])
        else:                                   # a outside: a quad b, c and the two crossings
            ab, ac = crossing(b, a), crossing(c, a)
            out += [[ab, vertex(b), vertex(c)], [ab, vertex(c), ac]]
    i, j, t = (np.array(col) for col in zip(*spec))
    return i.astype(np.int32), j.astype(np.int32), t.astype(np.float32), np.array(out, np.int32)


def _point(points: dict, spec: list, key, value) -> int:
    if key not in points:
        points[key] = len(spec)
        spec.append(value)
    return points[key]


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
    t = style.t[:, None]
    skin = (1 - t) * vertices[style.i] + t * vertices[style.j]
    normal = (1 - t) * normals[style.i] + t * normals[style.j]
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return (skin + normal * style.thickness[:, None]).astype(np.float32)
