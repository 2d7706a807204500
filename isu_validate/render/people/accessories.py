"""What drivers wear besides clothes: glasses, sunglasses, a cap, a watch; modelled procedurally.

Glasses, sunglasses and the watch's case are rigid: modelled once on the standing rest body of a kind of person
(the eyes, the left forearm where it meets the wrist) and carried to a posed body by the similarity
(rotation, scale, shift) that best maps the rest positions of their anchor vertices onto the posed ones
(the skull above the brows for the head; the forearm's end for the watch). The cap's crown is cut from
the head's own skin like a garment (``garments.py``), lifted over the hair, so it follows the head; its
brim is rigid like the glasses; the watch's band is cut from the forearm's skin likewise. Per vertex of the
cap's crown, the lift is the hair's thickness there plus a little, so a cap sits on the hair of any style."""
from __future__ import annotations

import numpy as np

from .garments import Garment, Piece, along_arm, cut_piece, dress
from .regions import body_scale, bone_weights
from .skeleton import Posed
from .surface import Surface

RIGID = {"glasses": "head", "sunglasses": "head", "lenses": "head", "brim": "head", "watch": "wrist"}
_FRAME_R, _BAND_W = 0.0016, 0.018
_WATCH_AT = 1.96      # along the arm (1 the elbow, 2 the wrist): where the watch's middle is


def rest_accessories(model, rest: Posed, faces: np.ndarray, hair_lift: np.ndarray) -> dict:
    """Everything to place the accessories on a posed body of this topology: the rigid meshes in the rest
    frame ("<name>_v", "<name>_f"), their anchors ("anchor_<rig>": anny vertex indices, "anchor_<rig>_rest":
    their rest positions) and the cap's crown (a garment, "cap_*"). ``hair_lift``: per anny vertex, how far
    the hair stands off the scalp (0 where there is none)."""
    v = rest.vertices.astype(np.float64)
    eyes = (rest.head("eye.L"), rest.head("eye.R"))
    s = body_scale(rest)
    out = {}
    skull = np.flatnonzero((bone_weights(model, ("head",)) > 0.95) & (v[:, 2] > eyes[0][2] + 0.02 * s))
    forearm = np.flatnonzero(bone_weights(model, ("lowerarm02.L",)) > 0.6)
    out.update(anchor_head=skull.astype(np.int32), anchor_head_rest=v[skull].astype(np.float32),
               anchor_wrist=forearm.astype(np.int32), anchor_wrist_rest=v[forearm].astype(np.float32))
    face = Surface(v, faces)
    frame, lens = _clear_of_face(face, *_glasses(eyes, s, 0.024, 0.017))
    out.update(_named("glasses", frame))
    big_frame, big_lens = _clear_of_face(face, *_glasses(eyes, s, 0.026, 0.020))
    out.update(**_named("sunglasses", big_frame), **_named("lenses", big_lens))
    crown = _crown(rest, v, s, hair_lift, faces)
    out.update(crown.to_arrays("cap"))
    worn, _ = dress(crown, v, faces)
    out.update(_named("brim", _brim(worn[crown.copy_of >= 0].astype(np.float64), eyes, s)))
    out.update(_named("watch", _watch_case(rest, v, model)), **_watch_band(rest, v, model, faces).to_arrays("band"))
    return out


def place(rest_arrays: dict, vertices: np.ndarray) -> dict[str, np.ndarray]:
    """The rigid meshes' vertices on a posed body ({name: (N, 3)})."""
    v = np.asarray(vertices, np.float64)
    out = {}
    for rig in ("head", "wrist"):
        scale, R, shift = similarity(rest_arrays[f"anchor_{rig}_rest"], v[rest_arrays[f"anchor_{rig}"]])
        for name, on in RIGID.items():
            if on == rig:
                out[name] = (scale * rest_arrays[f"{name}_v"] @ R.T + shift).astype(np.float32)
    return out


def similarity(a: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(s, R, t) minimising |s R a + t - b|² (Umeyama 1991)."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    ma, mb = a.mean(axis=0), b.mean(axis=0)
    A, B = a - ma, b - mb
    U, S, Vt = np.linalg.svd(B.T @ A / len(a))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    scale = float(np.trace(np.diag(S) @ D) / (A ** 2).sum(axis=1).mean())
    return scale, R, mb - scale * R @ ma


# ---------------------------------------------------------------------- the shapes, on the rest body
def _glasses(eyes, s: float, half_w: float, half_h: float):
    """(frame, lens) meshes: two rounded rims 2 cm in front of the eyes, a bridge and the temples back to
    the ears; the lenses fill the rims (the sunglasses' dark glass; clear glasses have none)."""
    parts, lenses = [], []
    for eye in eyes:
        out_x = np.sign(eye[0])
        centre = eye + np.array([out_x * 0.003 * s, -0.026 * s, -0.003 * s])
        ring = _rounded_rect(centre, half_w * s, half_h * s, wrap=0.004 * s)
        parts.append(_tube(ring, _FRAME_R * s, closed=True))
        lenses.append(_fan(ring, centre + np.array([0.0, -0.002 * s, 0.0])))
        hinge = centre + np.array([out_x * (half_w + 0.004) * s, 0.004 * s, 0.004 * s])
        ear = eye + np.array([out_x * 0.040 * s, 0.095 * s, 0.0])
        parts.append(_tube(np.array([hinge, hinge + (ear - hinge) * 0.5, ear]), _FRAME_R * s, closed=False))
    inner = [eye + np.array([np.sign(eye[0]) * (0.003 - half_w * 0.92) * s, -0.026 * s, 0.006 * s]) for eye in eyes]
    mid = (inner[0] + inner[1]) / 2 + np.array([0.0, -0.002 * s, 0.004 * s])
    parts.append(_tube(np.array([inner[0], mid, inner[1]]), _FRAME_R * s, closed=False))
    return _join(parts), _join(lenses)


def _clear_of_face(face: Surface, frame, lens, margin: float = 0.006):
    """Glasses moved forward until their lenses' rims clear the rest face (brow ridge, nose) by ``margin``:
    a posed face of another build or expression keeps some of it."""
    shift = np.array([0.0, -max(0.0, margin - face.distance(lens[0].astype(np.float64)).min()), 0.0])
    return (frame[0] + shift, frame[1]), (lens[0] + shift, lens[1])


def _rounded_rect(centre, half_w, half_h, wrap, n: int = 28) -> np.ndarray:
    """A superellipse in the face's plane (X, Z), bent back by ``wrap`` at its sides."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    c, sn = np.cos(a), np.sin(a)
    x = half_w * np.sign(c) * np.abs(c) ** 0.6
    z = half_h * np.sign(sn) * np.abs(sn) ** 0.6
    y = wrap * (x / half_w) ** 2
    return centre + np.stack([x, y, z], axis=1)


def _crown(rest: Posed, v: np.ndarray, s: float, hair_lift: np.ndarray, faces: np.ndarray) -> Garment:
    """The cap's crown: the head above a line round it (over the brows in front, lower at the back)."""
    eyes = (rest.head("eye.L") + rest.head("eye.R")) / 2
    d = v - (eyes + np.array([0.0, 0.075 * s, 0.0]))
    cos_front = -d[:, 1] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    line = eyes[2] + s * (0.040 + 0.012 * cos_front)
    head = np.linalg.norm(d / s, axis=1) < 0.13
    field = np.where(head, v[:, 2] - line, -1.0)
    lift = hair_lift + 0.004 * s
    return cut_piece(Piece(field, lift, v[:, 2]), faces, v)


def _brim(rim: np.ndarray, eyes, s: float) -> tuple[np.ndarray, np.ndarray]:
    """A peak over the face: from the front of the crown's edge forward 6.5 cm, curved down at its sides."""
    centre = (eyes[0] + eyes[1]) / 2
    front = rim[rim[:, 1] < centre[1] + 0.02 * s]
    front = front[np.argsort(front[:, 0])]
    xs = np.linspace(front[0, 0], front[-1, 0], 17)
    inner = np.stack([xs, np.interp(xs, front[:, 0], front[:, 1]) - 0.003 * s,
                      np.interp(xs, front[:, 0], front[:, 2]) + 0.002 * s], axis=1)
    u = (xs - centre[0]) / max(np.abs(xs - centre[0]).max(), 1e-9)
    reach = 0.065 * s * np.sqrt(np.clip(1 - u ** 2, 0.0, 1.0)) + 0.004 * s
    outer = inner + np.stack([np.zeros_like(u), -reach, -0.012 * s * (0.4 + u ** 2)], axis=1)
    top = np.stack([inner, outer], axis=1)                        # (17, 2, 3)
    return _slab(top, 0.004 * s)


def _watch_band(rest: Posed, v: np.ndarray, model, faces: np.ndarray) -> Garment:
    """The watch's band: cut from the left forearm's skin just above the wrist (it follows the forearm's
    twist), lifted a few millimetres."""
    along = along_arm(v, rest)
    left = (v[:, 0] > 0) & (bone_weights(model, ("lowerarm", "wrist")) > 0.5)
    field = np.where(left, _BAND_W / 2 - np.abs(along - _WATCH_AT) * 0.26, -1.0)
    return cut_piece(Piece(field, np.full(len(v), 0.0025), v[:, 2]), faces, v)


def _watch_case(rest: Posed, v: np.ndarray, model) -> tuple[np.ndarray, np.ndarray]:
    """The watch's round case on the back of the wrist (rigid: placed like the glasses)."""
    b, c = rest.head("lowerarm01.L"), rest.head("wrist.L")
    axis = (c - b) / np.linalg.norm(c - b)
    at = b + (c - b) * (_WATCH_AT - 1.0)
    hand = bone_weights(model, ("wrist", "finger", "metacarpal")) > 0.5
    h = v[hand & (v[:, 0] > 0)] - v[hand & (v[:, 0] > 0)].mean(axis=0)
    back = np.linalg.svd(h, full_matrices=False)[2][2]            # the hand's flat side...
    back = back - axis * (back @ axis)
    back = back / np.linalg.norm(back) * np.sign(back[0])         # ...facing out of the body (its back)
    skin = v[np.linalg.norm(np.cross(v - at, axis), axis=1) < 0.05]
    reach = ((skin - at) @ back)[np.abs((skin - at) @ axis) < 0.01].max()
    return _disc(at + back * (reach + 0.004), back, axis, 0.019, 0.008)


# ---------------------------------------------------------------------- mesh helpers
def _tube(path: np.ndarray, radius: float, closed: bool, sides: int = 6) -> tuple[np.ndarray, np.ndarray]:
    n = len(path)
    tangent = np.gradient(path, axis=0) if not closed else np.roll(path, -1, axis=0) - np.roll(path, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    up = np.where(np.abs(tangent[:, 2:3]) > 0.9, [[1.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]])
    e1 = np.cross(tangent, up)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(tangent, e1)
    a = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    verts = path[:, None] + radius * (np.cos(a)[None, :, None] * e1[:, None] + np.sin(a)[None, :, None] * e2[:, None])
    faces = []
    for k in range(n if closed else n - 1):
        k2 = (k + 1) % n
        for m in range(sides):
            m2 = (m + 1) % sides
            a, b, c, d = k * sides + m, k2 * sides + m, k2 * sides + m2, k * sides + m2
            faces += [[a, b, c], [a, c, d]]
    return verts.reshape(-1, 3), np.array(faces, np.int32)


def _fan(ring: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(ring)
    faces = [[n, k, (k + 1) % n] for k in range(n)]
    return np.concatenate([ring, centre[None]]), np.array(faces, np.int32)


def _slab(top: np.ndarray, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """A strip (rows of 2 points) made solid: its other face ``thickness`` below it, and the sides closed."""
    top = np.asarray(top, np.float64)
    bottom = top - np.array([0.0, 0.0, thickness])
    m = len(top)
    verts = np.concatenate([top.reshape(-1, 3), bottom.reshape(-1, 3)])
    T, B = (lambda r, c: r * 2 + c), (lambda r, c: 2 * m + r * 2 + c)
    faces = []
    for r in range(m - 1):
        for f in (T, B):
            faces += [[f(r, 0), f(r + 1, 0), f(r + 1, 1)], [f(r, 0), f(r + 1, 1), f(r, 1)]]
        for c in (0, 1):
            faces += [[T(r, c), B(r, c), B(r + 1, c)], [T(r, c), B(r + 1, c), T(r + 1, c)]]
    for r in (0, m - 1):
        faces += [[T(r, 0), T(r, 1), B(r, 1)], [T(r, 0), B(r, 1), B(r, 0)]]
    return verts, np.array(faces, np.int32)


def _disc(centre, normal, along, radius: float, height: float, n: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A short cylinder (a watch case) standing on ``normal``."""
    e1 = along / np.linalg.norm(along)
    e2 = np.cross(normal, e1)
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.outer(np.cos(a), e1) + np.outer(np.sin(a), e2)
    low, high = centre + ring * radius, centre + ring * radius + normal * height
    verts = np.concatenate([low, high, [centre + normal * height], [centre]])
    faces = []
    for k in range(n):
        k2 = (k + 1) % n
        faces += [[k, k2, n + k2], [k, n + k2, n + k], [2 * n, n + k, n + k2], [2 * n + 1, k2, k]]
    return verts, np.array(faces, np.int32)


def _join(meshes) -> tuple[np.ndarray, np.ndarray]:
    verts, faces, offset = [], [], 0
    for v, f in meshes:
        verts.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.concatenate(verts).astype(np.float32), np.concatenate(faces).astype(np.int32)


def _named(name: str, mesh) -> dict:
    return {f"{name}_v": mesh[0], f"{name}_f": mesh[1]}
