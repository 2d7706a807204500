"""Faces: MTCNN (facenet-pytorch 2.6.0), trained on photographs of real faces (WIDER FACE, CelebA).

Its weights ship in the wheel (``facenet_pytorch/data/{pnet,rnet,onet}.pt``); the settings are
facenet-pytorch's defaults (smallest face 20 px, stage thresholds 0.6/0.7/0.7), not tuned to the renders."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

MIN_SIDE = 12   # MTCNN's first stage looks at 12 px windows: a smaller frame holds no face it can find


@dataclass(frozen=True)
class Face:
    box: tuple[float, float, float, float]   # x0, y0, x1, y1 in frame pixels
    p: float

    @property
    def width(self) -> float:
        return self.box[2] - self.box[0]

    @property
    def centre(self) -> tuple[float, float]:
        return (self.box[0] + self.box[2]) / 2, (self.box[1] + self.box[3]) / 2

    def xywh(self) -> tuple[float, float, float, float]:
        return self.box[0], self.box[1], self.box[2] - self.box[0], self.box[3] - self.box[1]


class FaceDetector:
    name = "MTCNN (facenet-pytorch 2.6.0; WIDER FACE / CelebA photographs), default thresholds"

    def __init__(self, device: str = "cpu"):
        try:
            from facenet_pytorch import MTCNN
        except ImportError as exc:
            raise InputError(f"the MTCNN face detector is not installed ({exc}): run `make setup` (it installs "
                             "facenet-pytorch==2.6.0 with --no-deps)") from None
        self.model = MTCNN(keep_all=True, device=device)

    def detect(self, rgb: np.ndarray) -> list[Face]:
        """Faces in an RGB uint8 frame, most confident first."""
        if min(rgb.shape[:2]) < MIN_SIDE:
            return []
        boxes, probs = self.model.detect(rgb)
        if boxes is None:
            return []
        faces = [Face(tuple(float(v) for v in b), float(p)) for b, p in zip(boxes, probs, strict=True)]
        return sorted(faces, key=lambda f: -f.p)


def match(faces: list[Face], truth_box: tuple | None) -> Face | None:
    """The detected face that is the driver's: its centre inside the rendered head's box (the head mask
    holds face, hair and ears, so a true detection's centre lies inside it); without a box, the most
    confident face."""
    if truth_box is None:
        return faces[0] if faces else None
    x0, y0, x1, y1 = truth_box
    inside = [f for f in faces if x0 <= f.centre[0] <= x1 and y0 <= f.centre[1] <= y1]
    return inside[0] if inside else None
