"""What the yardsticks read: a frame, its scene, and where its features are.

A ``Frame`` is built by the readers of runs, datasets, pairs and frame folders (``isu_validate/yardstick``);
this package never reads those layouts. Boxes are (x0, y0, x1, y1), pixel ends exclusive, per render
instance (``render/labels.py`` names)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, InputNotFound

KINDS = ("render", "real", "stand-in")
LIGHTS = ("external_light", "car_lights")   # the scene's light features: the splits of every table


@dataclass(frozen=True)
class Unit:
    """One feature the yardsticks read: its render instance, the scene feature whose visibility decides
    whether it is occluded, and when the scene holds it at all."""
    name: str          # face | phone | bottle
    instance: str
    feature: str
    present: tuple[str, tuple[str, ...]] | None   # (feature, values that put it in the frame); None: always


UNITS = (
    Unit("face", "driver_face", "driver_emotion", None),
    Unit("phone", "phone", "phone_position", ("phone_position", ("P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8",
                                                               "P9", "P10"))),
    Unit("phone", "phone_codriver_seat", "phone_codriver_seat", ("phone_codriver_seat", ("YES",))),
    Unit("bottle", "colabottle_codriver_seat", "colabottle_codriver_seat", ("colabottle_codriver_seat", ("YES",))),
)


@dataclass(frozen=True)
class Frame:
    image: Path
    name: str                       # unique in one measurement (sample/frame, slot, test id)
    kind: str                       # render | real | stand-in (a capture sidecar says which)
    preset: str | None              # the render preset (of the sim frame, for a real one)
    scene: dict
    boxes: dict = field(default_factory=dict)       # instance -> (x0, y0, x1, y1)
    occluded: frozenset = frozenset()               # scene features the frame shows too little of
    own_boxes: bool = True          # False: the boxes are the aligned sim frame's (a real photograph)
    boxes_size: tuple[int, int] | None = None       # (w, h) of the image the boxes were measured on
    up: dict = field(default_factory=dict)          # instance -> (dx, dy): where its top points (a unit vector)
    face_anywhere: bool = False     # no head box (a labelled real photograph): the most confident face counts

    def boxes_for(self, width: int, height: int) -> dict:
        """The boxes in a (width x height) image: a real frame may be shot larger than the sim frame."""
        if (scale := self._scale(width, height)) is None:
            return dict(self.boxes)
        sx, sy = scale
        return {k: (round(b[0] * sx), round(b[1] * sy), round(b[2] * sx), round(b[3] * sy))
                for k, b in self.boxes.items()}

    def up_for(self, width: int, height: int) -> dict:
        """Where each thing's top points in a (width x height) image (a frame shot at another aspect)."""
        if (scale := self._scale(width, height)) is None:
            return dict(self.up)
        stretched = {k: (u[0] * scale[0], u[1] * scale[1]) for k, u in self.up.items()}
        return {k: (x / float(np.hypot(x, y)), y / float(np.hypot(x, y))) for k, (x, y) in stretched.items()}

    def _scale(self, width: int, height: int) -> tuple[float, float] | None:
        """(sx, sy) from the image the boxes were measured on to a (width x height) one; None: the same."""
        if not self.boxes_size or tuple(self.boxes_size) == (width, height):
            return None
        return width / self.boxes_size[0], height / self.boxes_size[1]

    def light(self) -> dict[str, str]:
        return {f: str(self.scene.get(f, "?")) for f in LIGHTS}

    def units(self) -> list[tuple[Unit, str]]:
        """(unit, status) for each feature the scene holds: visible, or occluded (too little of it shows,
        or no pixel of it at all); features the scene does not hold are left out."""
        out = []
        for unit in UNITS:
            if unit.present and self.scene.get(unit.present[0]) not in unit.present[1]:
                continue
            boxless = unit.instance not in self.boxes and not (unit.name == "face" and self.face_anywhere)
            hidden = unit.feature in self.occluded or boxless
            out.append((unit, "occluded" if hidden else "visible"))
        return out


def read_image(path: Path) -> np.ndarray:
    """An RGB uint8 frame; a missing or undecodable file is a user error naming it."""
    import cv2

    if not Path(path).is_file():
        raise InputNotFound(f"frame {path} is missing: the source lists it but the file is gone")
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None or image.size == 0:
        raise InputError(f"cannot decode frame {path}: it is empty, truncated or not an image; "
                         "re-render or re-capture it, or remove it (and its label) from the source")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
