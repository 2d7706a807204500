"""Clothes as garment meshes that stand off the posed body: a top (T-shirt, long sleeve, shirt with a
collar, hoodie with its hood lying on the back, or a T-shirt under an open jacket) and trousers.

anny ships no clothes. A garment is cut from anny's own triangles where a per-vertex field is positive
(the field is decided on the standing rest body from skinning weights and bone positions, like the
painted regions of ``regions.py``, and cut exactly along its zero line), so it follows every pose and
body without a cloth simulation. On a posed body each of its vertices is lifted off the skin along
the normal by its ease: more at a hem (a T-shirt's flares, a short sleeve opens), a rolled edge where
it ends, a slow billow and more where the body bends (the skin under it is compressed: the waist of a
seated driver, the inside of an elbow). Cloth bridges the body's hollows (between the breasts, the
small of the back, the armpit: an outward-only smoothing), keeps clear of skin it does not cover (the
torso under a sleeve), and every edge (hem, cuffs, neckline, collar) turns back into the body as a
band, so it shows its thickness. A shirt adds a collar, a hoodie its hood, a jacket a collar and an
open front showing the T-shirt under it."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .hair import clip_mesh, vertex_normals
from .regions import ARM_BONES, along_upper_arm, body_scale, bone_weights
from .skeleton import Body, Posed

TOPS = ("TSHIRT", "LONG_SLEEVE", "SHIRT", "HOODIE", "JACKET")
GAP = 0.0015          # the least a garment keeps off skin (m)
RIM_DEPTH = 0.002     # an edge band turns this far into the body: no gap shows along it
HEM_ROLL = 0.0025     # a hem, cuff or neckline is rolled: this much thicker over its last centimetre
_ARM_M = 0.28         # metres of arm per unit of "along the arm" (0 shoulder, 1 elbow, 2 wrist)

# per top: sleeve end (along the arm), ease (m) of body and sleeves, hem below the hip joints and how far
# the hem flares out, and the pieces it adds
_TOP = {"TSHIRT": dict(sleeve=0.45, ease=0.004, hem=0.10, flare=0.010, sleeve_flare=0.008),
        "LONG_SLEEVE": dict(sleeve=1.85, ease=0.0035, hem=0.10, flare=0.008, sleeve_flare=0.0),
        "SHIRT": dict(sleeve=1.85, ease=0.005, hem=0.11, flare=0.010, sleeve_flare=0.0, collar=(0.030, 0.010, 0.015)),
        "HOODIE": dict(sleeve=1.85, ease=0.010, hem=0.11, flare=0.006, sleeve_flare=0.0, hood=True),
        "JACKET": dict(sleeve=1.85, ease=0.016, hem=0.08, flare=0.008, sleeve_flare=0.0, collar=(0.045, 0.018, 0.05),
                       open_front=(0.040, 0.085))}
TROUSERS = dict(ease=0.005, flare=0.010)


@dataclass(frozen=True)
class Garment:
    """A garment mesh: vertex k lies on the skin between anny vertices ``i[k]`` and ``j[k]`` (at ``t`` from
    i) and is lifted ``lift[k]`` off it; ``copy_of`` >= 0 marks an edge band's outer vertex (it goes where
    that shell vertex goes), ``inner`` its inner one (in the skin). ``rest`` is the skin point on the rest
    body (prints and folds follow it), ``fold_u`` the coordinate folds run across (m)."""
    i: np.ndarray
    j: np.ndarray
    t: np.ndarray
    lift: np.ndarray
    copy_of: np.ndarray
    inner: np.ndarray
    faces: np.ndarray
    band: np.ndarray       # per triangle: part of an edge band (flat shaded)
    rest: np.ndarray
    fold_u: np.ndarray

    def to_arrays(self, prefix: str) -> dict:
        return {f"{prefix}_{k}": getattr(self, k) for k in self.__dataclass_fields__}

    @classmethod
    def from_arrays(cls, arrays: dict, prefix: str) -> Garment:
        return cls(**{k: arrays[f"{prefix}_{k}"] for k in cls.__dataclass_fields__})


@dataclass(frozen=True)
class Piece:
    field: np.ndarray     # per anny vertex, > 0 inside (about metres from its edge)
    lift: np.ndarray      # per anny vertex (m)
    fold_u: np.ndarray    # per anny vertex (m)


# ---------------------------------------------------------------------- the garments on the rest body
def outfit(body: Body, top: str, faces: np.ndarray) -> dict[str, Garment]:
    """The garments of an adult in ``top`` (one of TOPS) and trousers, by slot."""
    if top not in _TOP:
        raise ValueError(f"unknown top {top!r}; known: {', '.join(TOPS)}")
    rest = body.evaluate({})
    frame = _RestFrame(body.model, rest)
    out = {"trousers": _cut([frame.trousers()], faces, rest)}
    if top == "JACKET":
        out["top"] = _cut(frame.top("TSHIRT"), faces, rest)
        out["outer"] = _cut(frame.top("JACKET"), faces, rest)
    else:
        out["top"] = _cut(frame.top(top), faces, rest)
    return out


class _RestFrame:
    """Where things are on a standing rest body (faces -Y, Z up): what the garments' fields measure."""

    def __init__(self, model, rest: Posed):
        self.v = rest.vertices.astype(np.float64)
        self.s = body_scale(rest)
        self.rest = rest
        self.arm = bone_weights(model, ARM_BONES) > 0.5
        self.neck_skin = bone_weights(model, ("neck",)) > 0.5
        self.along = along_arm(self.v, rest)
        self.root = rest.head("root")
        self.neck = rest.head("neck01")
        z, y = self.v[:, 2], self.v[:, 1]
        # crew neck: lower in front (the body faces -Y at rest), up at the back
        back = np.clip((y - self.neck[1]) / (0.06 * self.s), -1, 1)
        self.neckline = self.neck[2] - 0.015 * self.s + 0.02 * self.s * back
        self.front = y < self.neck[1]
        self.z = z

    def top(self, kind: str) -> list[Piece]:
        spec, s, z = _TOP[kind], self.s, self.z
        hem = self.root[2] - spec["hem"] * s
        torso = np.minimum(z - hem, self.neckline - z)
        if "open_front" in spec:       # an open jacket: the gap widens from the collar down to the hem
            lo, hi = spec["open_front"]
            width = (lo + (hi - lo) * np.clip((self.neckline - z) / (self.neckline - hem).clip(1e-6), 0, 1)) * s
            torso = np.where(self.front, np.minimum(torso, np.abs(self.v[:, 0]) - width), torso)
        sleeve = (spec["sleeve"] - self.along) * _ARM_M * s
        field = np.where(self.arm, sleeve, torso)
        hem_near = np.clip(1.0 - (z - hem) / (0.12 * s), 0.0, 1.0) ** 1.5
        sleeve_near = np.clip(1.0 - sleeve / (0.10 * s), 0.0, 1.0)
        lift = spec["ease"] + np.where(self.arm, spec["sleeve_flare"] * sleeve_near, spec["flare"] * hem_near)
        fold_u = np.where(self.arm, self.along * _ARM_M * s, z)
        pieces = [Piece(field, lift, fold_u)]
        if "collar" in spec:
            pieces.append(self._collar(*spec["collar"], open_front=kind == "JACKET"))
        if spec.get("hood"):
            pieces.append(self._hood(spec["ease"]))
        return pieces

    def trousers(self) -> Piece:
        s, z = self.s, self.z
        waist = self.root[2] + 0.03 * s
        ankle = min(self.rest.head("foot.L")[2], self.rest.head("foot.R")[2]) + 0.05 * s
        field = np.where(self.arm, -1.0, np.minimum(waist - z, z - ankle))
        lift = TROUSERS["ease"] + TROUSERS["flare"] * np.clip(1.0 - (z - ankle) / (0.15 * s), 0.0, 1.0)
        return Piece(field, lift, z)

    def _collar(self, height: float, ease: float, top_ease: float, open_front: bool) -> Piece:
        """A band round the neck from just under the neckline up ``height``, open at the front."""
        s, z = self.s, self.z
        up = (z - self.neckline) / (height * s)
        gap = (0.035 if open_front else 0.012) * s
        field = np.minimum(np.minimum(z - self.neckline + 0.008 * s, self.neckline + height * s - z),
                           np.where(self.front, np.abs(self.v[:, 0]) - gap, 1.0))
        field = np.where(self.neck_skin | ~self.arm, field, -1.0)
        lift = ease + (top_ease - ease) * np.clip(up, 0.0, 1.0)
        return Piece(field, lift, z)

    def _hood(self, ease: float) -> Piece:
        """A hood lying down: a roll of cloth round the back and sides of the neck, heaped on the upper back."""
        s, v = self.s, self.v
        centre = self.neck + np.array([0.0, 0.05, -0.07]) * s
        r = np.linalg.norm((v - centre) / (np.array([0.14, 0.12, 0.11]) * s), axis=1)
        heap = np.where(v[:, 1] > self.neck[1] - 0.01 * s, (1.0 - r) * 0.1 * s, -1.0)
        # the roll: a band just under the neckline, from the back round to the sides (it thins out there)
        middle = self.neckline - 0.03 * s
        side = np.clip((v[:, 1] - (self.neck[1] - 0.04 * s)) / (0.05 * s), 0.0, 1.0)
        roll = np.where(v[:, 1] > self.neck[1] - 0.04 * s, 0.035 * s - np.abs(v[:, 2] - middle), -1.0)
        field = np.where(self.arm, -1.0, np.maximum(heap, roll))
        round_neck = np.clip(1.0 - ((v[:, 2] - middle) / (0.035 * s)) ** 2, 0.0, 1.0)
        lift = ease + 0.004 + np.maximum(0.030 * np.clip(1.0 - r ** 2, 0.0, 1.0), 0.026 * side * round_neck)
        return Piece(field, lift, self.z)


def along_arm(v: np.ndarray, rest: Posed) -> np.ndarray:
    """Per vertex, where it lies along its arm: 0 at the shoulder joint, 1 at the elbow, 2 at the wrist."""
    upper = along_upper_arm(v, rest)
    out = upper.copy()
    for side, sign in (("L", 1), ("R", -1)):
        b, c = rest.head(f"lowerarm01.{side}"), rest.head(f"wrist.{side}")
        t = ((v - b) @ (c - b)) / ((c - b) @ (c - b))
        mine = (np.sign(v[:, 0]) == sign) & (upper >= 1.0)
        out[mine] = 1.0 + t[mine]
    return out


def _cut(pieces: list[Piece], faces: np.ndarray, rest: Posed) -> Garment:
    """The pieces cut from the body along their fields' zero lines, each with its edge band, as one mesh."""
    parts = [cut_piece(p, faces, rest.vertices.astype(np.float64)) for p in pieces]
    offset, out = 0, {k: [] for k in Garment.__dataclass_fields__}
    for g in parts:
        for k in out:
            value = getattr(g, k)
            if k == "faces":
                value = value + offset
            elif k == "copy_of":
                value = np.where(value >= 0, value + offset, -1)
            out[k].append(value)
        offset += len(g.i)
    return Garment(**{k: np.concatenate(v) for k, v in out.items()})


def cut_piece(piece: Piece, faces: np.ndarray, v: np.ndarray) -> Garment:
    i, j, t, shell = clip_mesh(faces, piece.field)

    def at(values):           # a per-anny-vertex value at the cut's vertices
        return (1 - t) * values[i] + t * values[j]

    depth = at(np.maximum(piece.field, 0.0))
    lift = at(piece.lift) + HEM_ROLL * np.clip(1.0 - depth / 0.01, 0.0, 1.0)
    # edge bands: every boundary edge (a -> b as its triangle winds) gets a quad back into the body,
    # on copies of its vertices so the band's normals do not bend the shell's shading
    directed = np.concatenate([shell[:, [0, 1]], shell[:, [1, 2]], shell[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = directed[counts[inverse.ravel()] == 1]
    ends = np.unique(boundary)
    n = len(i)
    outer = {int(k): n + m for m, k in enumerate(ends)}
    inner = {int(k): n + len(ends) + m for m, k in enumerate(ends)}
    band = [[outer[b], outer[a], inner[a]] for a, b in boundary.tolist()]
    band += [[outer[b], inner[a], inner[b]] for a, b in boundary.tolist()]
    index = np.concatenate([np.arange(n), ends, ends])
    copy_of = np.concatenate([np.full(n, -1), ends, np.full(len(ends), -1)])
    is_inner = np.concatenate([np.zeros(n + len(ends), bool), np.ones(len(ends), bool)])
    tri = np.concatenate([shell, np.array(band, np.int64).reshape(-1, 3)]).astype(np.int32)
    rest = (1 - t)[:, None] * v[i] + t[:, None] * v[j]
    lift = np.where(is_inner, -RIM_DEPTH, lift[index])
    return Garment(i[index].astype(np.int32), j[index].astype(np.int32), t[index].astype(np.float32),
                   lift.astype(np.float32), copy_of.astype(np.int32), is_inner, tri,
                   np.arange(len(tri)) >= len(shell), rest[index].astype(np.float32),
                   at(piece.fold_u)[index].astype(np.float32))


# ---------------------------------------------------------------------- on a posed body
def dress(garment: Garment, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None
          ) -> tuple[np.ndarray, np.ndarray]:
    """(vertices of the garment on a posed body, its crumple per vertex 0..1: how much the skin under it
    is compressed against the rest body)."""
    v = np.asarray(vertices, np.float64)
    normals = vertex_normals(v, faces) if normals is None else normals
    t = garment.t[:, None].astype(np.float64)
    skin = (1 - t) * v[garment.i] + t * v[garment.j]
    n = (1 - t) * normals[garment.i] + t * normals[garment.j]
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    shell = (garment.copy_of < 0) & ~garment.inner
    crumple = _crumple(garment, skin, shell)
    phase = 40.0 * garment.rest[:, 0] + 25.0 * garment.rest[:, 1]
    billow = 0.5 + 0.5 * np.sin(2 * np.pi * garment.fold_u / 0.07 + phase)
    lift = garment.lift + np.where(shell, (0.0015 + 0.006 * crumple) * billow, 0.0)
    out = skin + n * lift[:, None]
    out = _bridge(garment, out, n, shell)
    out[shell] = _keep_off(v, faces, out[shell])
    copies = garment.copy_of >= 0
    out[copies] = out[garment.copy_of[copies]]
    return out.astype(np.float32), crumple.astype(np.float32)


_REACH = 0.06     # the thickest cloth a strap is lifted onto (m): nothing farther above it is under it
_GRAZE = 0.01     # a strap point this far into other cloth (a sleeve beside the chest) rests on it instead


def lift_straps(state: dict, cloth: list[tuple[np.ndarray, np.ndarray]],
                grazed: list[tuple[np.ndarray, np.ndarray]] = ()) -> dict:
    """The belt's straps (laid on the skin by ``belt.py``) lifted onto the clothes: each point of a strap
    rises along its normal until its underside clears the topmost cloth under it (a ray cast down onto
    every garment), and the strap stays taut over what lifts it (it spans an open jacket's front instead of
    dipping into it); the anchored ends stay. Then a point the rays missed (cloth under a slanting strap, a
    sleeve beside the chest), nearer any cloth than half the strap's thickness or up to ``_GRAZE`` into it,
    rests on it; one deeper lies under it (an arm in front of the strap), as it does. ``cloth``: each
    garment's (vertices, triangles) as placed over the belt's carriers; ``grazed``: the rest of it, which the
    strap only touches."""
    import trimesh
    from .belt import THICKNESS, WIDTH
    from .surface import Surface
    touched = [Surface(vertices, triangles) for vertices, triangles in [*cloth, *grazed]]   # built once, both straps
    offsets = np.cumsum([0] + [len(v) for v, _ in cloth])
    mesh = trimesh.Trimesh(np.concatenate([v for v, _ in cloth]).astype(np.float64),
                           np.concatenate([f + o for (_, f), o in zip(cloth, offsets)]), process=False)
    out = {}
    for strap in ("belt_diagonal", "belt_lap"):
        points, normals = state[strap].astype(np.float64), state[f"{strap}_normals"].astype(np.float64)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        across = np.cross(np.gradient(points, axis=0), normals)
        across /= np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)
        lift = np.zeros(len(points))
        for side in (-0.5, 0.0, 0.5):          # under the strap's middle and its two edges
            under = points + across * side * WIDTH
            hits, rays, _ = mesh.ray.intersects_location(under + normals * _REACH, -normals, multiple_hits=False)
            height = ((hits - under[rays]) * normals[rays]).sum(axis=1) + THICKNESS / 2 + 0.001
            np.maximum.at(lift, rays, height)
        lift[[0, -1]] = 0.0
        for _ in range(30):     # taut: no point lower than the mean of its neighbours (a string over its supports)
            lift[1:-1] = np.maximum(lift[1:-1], (lift[:-2] + lift[2:]) / 2)
        lifted = points + normals * lift[:, None]
        for _ in range(3):        # resting on one cloth may bring a point nearer another one
            for surface in touched:
                lifted[1:-1] = _rest_on(lifted[1:-1], surface, THICKNESS / 2 + 0.001)
        out[strap] = lifted.astype(np.float32)
        out[f"{strap}_normals"] = normals.astype(np.float32)
    return out


def _rest_on(points: np.ndarray, cloth, height: float) -> np.ndarray:
    """Points nearer a cloth (a ``Surface``) than ``height`` (or up to ``_GRAZE`` into it), straight over one of
    its triangles, moved out to ``height`` above it along its normal."""
    q, n, d = cloth.closest(points)
    square = np.abs(((points - q) * n).sum(axis=1)) >= 0.95 * np.linalg.norm(points - q, axis=1)
    touching = (d < height) & (d > -_GRAZE) & square
    out = points.copy()
    out[touching] = q[touching] + n[touching] * height
    return out


def _crumple(g: Garment, skin: np.ndarray, shell: np.ndarray) -> np.ndarray:
    """Per vertex 0..1: the mean shortening of its edges from the rest body to the posed one, against the
    garment's median (a bigger or smaller body is not a crumpled one); a quarter shorter is 1."""
    tri = g.faces[~g.band]
    edges = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    before = np.linalg.norm(g.rest[edges[:, 0]] - g.rest[edges[:, 1]], axis=1)
    after = np.linalg.norm(skin[edges[:, 0]] - skin[edges[:, 1]], axis=1)
    ok = before > 1e-5
    ratio = after[ok] / before[ok]
    shortening = np.clip(1.0 - ratio / np.median(ratio), 0.0, None)
    total, count = np.zeros(len(skin)), np.zeros(len(skin))
    for end in (0, 1):
        np.add.at(total, edges[ok, end], shortening)
        np.add.at(count, edges[ok, end], 1.0)
    per_vertex = np.clip(total / np.maximum(count, 1.0) / 0.25, 0.0, 1.0)
    copies = g.copy_of >= 0
    per_vertex[copies] = per_vertex[g.copy_of[copies]]
    return np.where(g.inner, 0.0, per_vertex)


def _bridge(g: Garment, out: np.ndarray, n: np.ndarray, shell: np.ndarray, rounds: int = 4) -> np.ndarray:
    """Cloth spans hollows: each shell vertex moves out (never in) towards its neighbours' mean plane."""
    import scipy.sparse as sp
    tri = g.faces[~g.band]
    rows = np.concatenate([tri[:, 0], tri[:, 1], tri[:, 2], tri[:, 1], tri[:, 2], tri[:, 0]])
    cols = np.concatenate([tri[:, 1], tri[:, 2], tri[:, 0], tri[:, 0], tri[:, 1], tri[:, 2]])
    adjacency = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(out), len(out)))
    adjacency.data[:] = 1.0
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    for _ in range(rounds):
        mean = (adjacency @ out) / np.maximum(degree, 1)[:, None]
        outward = np.clip(((mean - out) * n).sum(axis=1), 0.0, 0.02)
        out[shell] += (n * outward[:, None])[shell]
    return out


def _keep_off(v: np.ndarray, faces: np.ndarray, points: np.ndarray, rounds: int = 6) -> np.ndarray:
    """Points moved out of the body to GAP above its surface (the closest point on its triangles, the side
    from that triangle's normal): a sleeve's cloth against the torso, the belly's fold of a seated body."""
    from .surface import Surface
    surface = Surface(v, faces)
    moved = np.arange(len(points))        # a point left where it was stays clear: only moved ones are re-measured
    for _ in range(rounds):
        q, n, d = surface.closest(points[moved])
        low = d < GAP
        if not low.any():
            break
        moved = moved[low]
        points[moved] = q[low] + n[low] * GAP
    return points
