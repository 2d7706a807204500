"""The yardsticks on real photographs that ship with scikit-image (no download): the calibration of the
yardstick itself, beside which the rates on renders are read.

``astronaut`` (one frontal, smiling face: found, and read happy as it shrinks to the face sizes of a cabin
camera), the LFW subset (100 real faces and 100 non-faces, 25x25 grey, enlarged 4x as the issue measured
them), ``coffee`` (a real cup of espresso, shrunk to the sizes the cabin's objects have)."""
from __future__ import annotations

import numpy as np

FACE_WIDTHS = (110, 48, 24)        # px: the astronaut's face as large as in the photo, and as small as ours
LFW_SCALE = 4                      # 25 px -> 100 px, about the rendered driver's face
CUP_BOX = (180, 20, 520, 330)      # x0, y0, x1, y1 of the cup and saucer in ``coffee()``
CUP_SIDES = (160, 96, 48)
CUP_CLASSES = ("espresso", "cup", "coffee mug")   # what the cup is in ImageNet's words


def astronaut_face(models) -> list[dict]:
    """Per face width: was the face found, FER's read and P(happy) on the face shrunk to that width."""
    import cv2
    from skimage import data

    from .expression import HAPPY, LABELS

    rgb = data.astronaut()
    face = models.faces.detect(rgb)[0]
    out = []
    for width in FACE_WIDTHS:
        s = width / face.width
        small = cv2.resize(rgb, None, fx=s, fy=s, interpolation=cv2.INTER_AREA)
        found = models.faces.detect(small)
        p = models.expression.read(cv2.cvtColor(small, cv2.COLOR_RGB2GRAY), [tuple(v * s for v in face.xywh())])[0]
        out.append({"face_px": width, "found": bool(found), "p_face": round(found[0].p, 4) if found else None,
                    "read": LABELS[int(p.argmax())], "p_happy": round(float(p[HAPPY]), 4)})
    return out


def lfw(models, n: int = 100) -> dict:
    """Faces found among the first ``n`` LFW faces and the first ``n`` non-faces."""
    import cv2
    from skimage import data

    images = data.lfw_subset()   # 100 faces, then 100 non-faces

    def found(grey) -> bool:
        rgb = cv2.cvtColor((grey * 255).astype(np.uint8), cv2.COLOR_GRAY2RGB)
        return bool(models.faces.detect(cv2.resize(rgb, None, fx=LFW_SCALE, fy=LFW_SCALE,
                                                   interpolation=cv2.INTER_CUBIC)))

    return {"face_px": 25 * LFW_SCALE, "faces": sum(found(g) for g in images[:n]), "n_faces": n,
            "non_faces": sum(found(g) for g in images[100:100 + n]), "n_non_faces": n}


def cup(models) -> list[dict]:
    """The real cup at each crop side: ImageNet's top-1, and whether a cup class is in the top-5."""
    import cv2
    from skimage import data

    x0, y0, x1, y1 = CUP_BOX
    crop = data.coffee()[y0:y1, x0:x1]
    crops = [cv2.resize(crop, (s, s), interpolation=cv2.INTER_AREA) for s in CUP_SIDES]
    return [{"side_px": s, "top1": top[0][0], "p": round(top[0][1], 4),
             "cup_in_top5": any(c in CUP_CLASSES for c, _ in top)}
            for s, top in zip(CUP_SIDES, models.objects.top(crops), strict=True)]


def calibration(models) -> dict:
    return {"astronaut": astronaut_face(models), "lfw": lfw(models), "cup": cup(models)}


def format_calibration(c: dict) -> str:
    lines = ["yardsticks on real photographs (scikit-image's bundled astronaut, LFW subset, coffee):"]
    for a in c["astronaut"]:
        lines.append(f"  astronaut, face {a['face_px']:>3} px: {'found' if a['found'] else 'MISSED'}"
                     f" (p {a['p_face']}); FER reads {a['read']} (P(happy) {a['p_happy']:.2f})")
    f = c["lfw"]
    lines.append(f"  LFW at {f['face_px']} px: {f['faces']}/{f['n_faces']} faces found, "
                 f"{f['non_faces']}/{f['n_non_faces']} non-faces taken for faces")
    for k in c["cup"]:
        lines.append(f"  a real cup at {k['side_px']:>3} px: top-1 {k['top1']} ({k['p']:.2f}); "
                     f"a cup class in the top-5: {'yes' if k['cup_in_top5'] else 'no'}")
    return "\n".join(lines)
