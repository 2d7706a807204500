"""Captured frames with their sidecars, as the fits need them; unusable frames are set aside with a reason.

A sidecar is the JSON ``capture shoot`` writes beside each frame (``frame_0000.json``), or ``capture import``
from a photo's EXIF (``capture/photo_import.py``): ``exposure_us``,
``iso`` (DepthAI; gain = ISO / 100) or ``gain`` (V4L2's raw gain, taken as a multiplier),
``auto_exposure``, and ``timestamp``/``sequence`` when the source reports them."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from isu_validate.errors import InputError, InputNotFound
from isu_validate.image_files import IMAGE_SUFFIXES

from ..sidecar import load_sidecar, sidecar_path

BLACK_CODE, WHITE_CODE = 2, 253      # a frame with 99% of its pixels beyond these is all black / saturated
EXTREME_SHARE = 0.99


@dataclass
class Frame:
    path: Path
    image: np.ndarray            # RGB, output levels 0..1 (float32)
    exposure_us: float
    gain: float
    auto: bool
    order: tuple                 # (folder, sequence or timestamp or name): sorts a session in time
    group: str = ""              # the folder named on the command line it came from (one scene, one bracket)

    @property
    def product(self) -> float:
        return self.exposure_us * self.gain


@dataclass
class FrameSet:
    frames: list[Frame] = field(default_factory=list)
    excluded: dict[str, str] = field(default_factory=dict)     # path -> why

    @property
    def auto(self) -> list[Frame]:
        return [f for f in self.frames if f.auto]

    @property
    def manual(self) -> list[Frame]:
        return [f for f in self.frames if not f.auto]

    def warnings(self) -> list[str]:
        return [f"{path}: {why}; left out" for path, why in self.excluded.items()]


def expand(inputs) -> list[tuple[Path, str]]:
    """Image files named directly or found under the folders named (sorted), each with its group: the
    folder named (a bracket shot as one session per exposure setting stays one bracket), or a file's folder."""
    paths = []
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            paths += [(q, str(p)) for q in sorted(p.rglob("*"))
                      if q.suffix.lower() in IMAGE_SUFFIXES and not q.name.startswith(".")]
        elif p.exists():
            paths.append((p, str(p.parent)))
        else:
            raise InputNotFound(f"frame {p} does not exist")
    if not paths:
        raise InputError(f"no frames found in {', '.join(map(str, inputs))} "
                         f"(looked for {', '.join(sorted(IMAGE_SUFFIXES))})")
    return paths


def load(inputs) -> FrameSet:
    out = FrameSet()
    for path, group in expand(inputs):
        frame, why = _load_one(path, group)
        if frame is None:
            out.excluded[str(path)] = why
        else:
            out.frames.append(frame)
    return out


def _load_one(path: Path, group: str) -> tuple[Frame | None, str]:
    sidecar = sidecar_path(path)
    try:
        meta = load_sidecar(path)
    except FileNotFoundError:
        return None, (f"no sidecar {sidecar.name} (exposure time and ISO/gain unknown; shoot with "
                      "`isu-validate capture shoot`, or make sidecars from photos' EXIF with "
                      "`isu-validate capture import PHOTOS --out DIR`)")
    except ValueError as exc:
        return None, f"sidecar {sidecar.name} is not valid JSON ({exc})"
    exposure_us, gain = meta.get("exposure_us"), _gain(meta)
    if not isinstance(exposure_us, (int, float)) or exposure_us <= 0:
        return None, f"sidecar {sidecar.name} has no exposure_us"
    if gain is None:
        return None, f"sidecar {sidecar.name} has neither a positive iso nor gain"
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        return None, "cannot be read as an image (corrupt or not an image)"
    if bgr.dtype != np.uint8:
        return None, f"is {bgr.dtype}, not an 8-bit frame"
    why = extreme(bgr)
    if why:
        return None, why
    image = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32) / 255.0
    when = meta.get("sequence", meta.get("frame_index", meta.get("timestamp", path.name)))
    return Frame(path, image, float(exposure_us), gain, bool(meta.get("auto_exposure", False)),
                 (str(path.parent), str(when).zfill(12) if isinstance(when, (int, float)) else str(when)), group), ""


def _gain(meta: dict) -> float | None:
    iso, gain = meta.get("iso"), meta.get("gain")
    if isinstance(iso, (int, float)) and iso > 0:
        return float(iso) / 100.0
    if isinstance(gain, (int, float)) and gain > 0:
        return float(gain)
    return None


def extreme(image8: np.ndarray) -> str:
    """Why a frame carries no exposure information (all black, all saturated), or ''."""
    grey = image8.max(axis=2) if image8.ndim == 3 else image8
    if np.mean(grey <= BLACK_CODE) >= EXTREME_SHARE:
        return "all black (nothing above code 2): no exposure information"
    low = image8.min(axis=2) if image8.ndim == 3 else image8
    if np.mean(low >= WHITE_CODE) >= EXTREME_SHARE:
        return "saturated (everything at code 253 or above): no exposure information"
    return ""
