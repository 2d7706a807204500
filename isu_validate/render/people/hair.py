"""Simple hair: a shell over the scalp, lifted off the posed head along its normals, and over the bob
locks as opaque tapered cards (``lock_roots``, ``lock_vertices``), none over the forehead.

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

    @property
    def middle(self) -> np.ndarray:
        return _head_middle(self.eyes, self.size)

    def bearing(self, points: np.ndarray) -> np.ndarray:
        """The cosine of each point's bearing round the head from the face's direction (as ``cos_front``)."""
        return _cos_front(np.atleast_2d(points) - self.middle)


def head_frame(rest: Posed) -> HeadFrame:
    v = rest.vertices.astype(np.float64)
    eyes = (rest.head("eye.L") + rest.head("eye.R")) / 2
    s = (eyes[2] - rest.head("root")[2]) / 0.69
    d = v - _head_middle(eyes, s)
    return HeadFrame(eyes, s, d, _cos_front(d))


def _head_middle(eyes: np.ndarray, size: float) -> np.ndarray:
    return eyes + np.array([0.0, 0.075 * size, 0.0])      # behind the eyes; the body faces -Y at rest


def _cos_front(d: np.ndarray) -> np.ndarray:
    return -d[:, 1] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)


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
    i, j, t, shell = clip_mesh(faces, edge)
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


def clip_mesh(faces: np.ndarray, f: np.ndarray):
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


# ---------------------------------------------------------------------- locks over the bob
# The bob carries locks: opaque tapered cards rooted on its shell, lying along the head as they flow from
# the crown and droop, standing a little off it, so its outline and its highlights break into locks. None
# grows on the face's side of the head (no fringe over the forehead: the planners' decision on issue 32), and
# each ends above the hairline (the bob's lower edge behind the face), so none hangs free of the bob. Short
# hair and the buzz cut stay the shell (cards on short hair hardly show at the cabin camera's scale). As Cycles
# curves (about 25 000 locks) they cost standard's SSIM more than its floor allows.
LOCKS = {"bob": 87}
LOCK_POINTS = 4               # along a card's middle line; a card is a strip of LOCK_POINTS - 1 quads
LOCK_LENGTH = (0.030, 0.060)  # m, a 1.75 m adult's
LOCK_WIDTH = (0.010, 0.016)   # m at the root; the tip is TIP_SHARE of it
TIP_SHARE = 0.25
LOCK_LIFT = (0.001, 0.0035)   # m: how far a lock stands off the shell at most
HEAD_RADIUS = 0.20            # a lock falls away from its tangent as on a head this round (m)
FACE_SIDE = 0.3               # no lock is rooted where the bearing's cosine from the face is above this
LOCK_SEED = 32                # the same locks on every frame and every desk


@dataclass(frozen=True)
class Locks:
    """Cards rooted on a style's shell: each at barycentric ``bary`` in shell triangle ``face``, ``length`` and
    root ``width`` (m) and ``lift`` (m off the shell at most); they flow from shell vertex ``crown``."""
    face: np.ndarray
    bary: np.ndarray
    length: np.ndarray
    width: np.ndarray
    lift: np.ndarray
    crown: int

    def __len__(self) -> int:
        return len(self.face)


def lock_roots(style: HairStyle, shell: np.ndarray, rest: Posed, seed: int = LOCK_SEED) -> Locks:
    """The style's locks on its shell ``shell`` (vertices on the rest body): roots spread by area over the
    shell behind ``FACE_SIDE``, each no longer than its root's height above the hairline; none for a style
    without locks."""
    n = LOCKS.get(style.name, 0)
    if not n:
        none = np.zeros(0, np.float32)
        return Locks(np.zeros(0, np.int32), np.zeros((0, 3), np.float32), none, none, none, 0)
    head = head_frame(rest)
    tri = shell[style.faces]
    behind = head.bearing(tri.mean(axis=1)) <= FACE_SIDE
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) * behind
    rng = np.random.default_rng(seed)
    face = rng.choice(len(area), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1.0
    u, v = np.where(flip, 1.0 - u, u), np.where(flip, 1.0 - v, v)
    bary = np.column_stack([1.0 - u - v, u, v])
    corners = style.faces[face]
    t = style.t[corners]
    root = np.einsum("sk,skd->sd", bary, shell[corners])
    above = (bary * ((1 - t) * style.field[style.i[corners]] + t * style.field[style.j[corners]])).sum(axis=1)
    length = rng.uniform(*LOCK_LENGTH, n) * head.size
    # a lock ends above the hairline and above the shell's own lower edge near it (the shell ends where the
    # head's and neck's skin does, above the nape's hairline): none hangs free of the bob, none falls over the face
    length = np.minimum(length, np.maximum(np.minimum(above, root[:, 2] - _edge_below(root, shell)), 0.004))
    crown = int(np.argmax(shell[:, 2] + 0.4 * shell[:, 1]))          # top and back of the head (faces -Y)
    return Locks(face.astype(np.int32), bary.astype(np.float32), length.astype(np.float32),
                 (rng.uniform(*LOCK_WIDTH, n) * head.size).astype(np.float32),
                 (rng.uniform(*LOCK_LIFT, n) * head.size).astype(np.float32), crown)


def _edge_below(points: np.ndarray, shell: np.ndarray, reach: float = 0.03) -> np.ndarray:
    """The height of the shell's lowest vertex within ``reach`` (m, across) of each point."""
    across = np.linalg.norm(points[:, None, :2] - shell[None, :, :2], axis=2)
    return np.where(across < reach, shell[None, :, 2], np.inf).min(axis=1)


def lock_faces(n: int) -> np.ndarray:
    """The cards' triangles: card k's vertices are 2 * LOCK_POINTS from k * 2 * LOCK_POINTS, in pairs across it."""
    quads = np.arange(LOCK_POINTS - 1) * 2
    one = np.concatenate([np.column_stack([quads, quads + 1, quads + 3]),
                          np.column_stack([quads, quads + 3, quads + 2])])
    return (one[None] + (np.arange(n) * 2 * LOCK_POINTS)[:, None, None]).reshape(-1, 3).astype(np.int32)


def lock_vertices(locks: Locks, shell_faces: np.ndarray, shell: np.ndarray) -> np.ndarray:
    """(n * 2 * LOCK_POINTS, 3) vertices of the cards on a posed shell: each middle line starts just under the
    shell at its root and runs along the flow from the crown (drooping), lying on the head while it stands
    off by up to its lift; across it, the card's width tapers from root to tip."""
    if not len(locks):
        return np.zeros((0, 3), np.float32)
    normals = vertex_normals(shell.astype(np.float64), shell_faces)
    corners = shell_faces[locks.face]
    bary = locks.bary.astype(np.float64)[..., None]
    root = (bary * shell[corners]).sum(axis=1)
    normal = _unit((bary * normals[corners]).sum(axis=1))
    flow = _tangent(root - shell[locks.crown], normal)
    droop = _tangent(np.tile([0.0, 0.0, -1.0], (len(root), 1)), normal)
    direction = _unit(flow + 0.8 * droop + 1e-6 * normal)
    across = _unit(np.cross(normal, direction))
    step = (locks.length / (LOCK_POINTS - 1))[:, None]
    lift = locks.lift[:, None]
    middle = [root - 0.0005 * normal]
    for k, rise in enumerate((0.7, 1.2, 0.8)[:LOCK_POINTS - 1], start=1):
        along = k * step
        middle.append(root + along * direction - normal * (along ** 2 / (2 * HEAD_RADIUS)) + rise * lift * normal)
    half = locks.width[:, None] / 2 * np.linspace(1.0, TIP_SHARE, LOCK_POINTS)[None]      # (n, points)
    line = np.stack(middle, axis=1)                                                           # (n, points, 3)
    sides = np.stack([line - half[..., None] * across[:, None], line + half[..., None] * across[:, None]], axis=2)
    return sides.reshape(-1, 3).astype(np.float32)


def _tangent(v: np.ndarray, normal: np.ndarray) -> np.ndarray:
    return _unit(v - normal * (v * normal).sum(axis=1, keepdims=True))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-12)
