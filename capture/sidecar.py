"""A captured frame's sidecar (``frame_0000.json`` beside ``frame_0000.png``): read here, and nowhere else.

``capture shoot`` writes it (``session.py``): device, exposure time, ISO/gain, time; ``capture import``
writes the same from a photo's EXIF (``photo_import.py``); a frame of the
stand-in source (``sources/standin.py``: a render made where no car or camera was at hand) carries
``"stand_in": true``. Every report that takes captured frames for reality counts its stand-ins with
``provenance`` and says so (``banner``): a number measured on renders must never read like a
real-world result.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

STAND_IN = "stand_in"


def sidecar_path(frame: str | Path) -> Path:
    return Path(frame).with_suffix(".json")


def load_sidecar(frame: str | Path) -> dict:
    """The sidecar of ``frame``; FileNotFoundError when it has none, ValueError when it is no JSON object."""
    meta = json.loads(sidecar_path(frame).read_text(encoding="utf-8"))
    if not isinstance(meta, dict):
        raise ValueError(f"{sidecar_path(frame).name} holds a {type(meta).__name__}, not a JSON object")
    return meta


def read_sidecar(frame: str | Path) -> dict:
    """The sidecar of ``frame``, or {} when it has none or it cannot be read."""
    try:
        return load_sidecar(frame)
    except (OSError, ValueError):
        return {}


def is_stand_in(frame: str | Path) -> bool:
    """Whether ``frame`` is a stand-in render; a frame without a readable sidecar counts as a capture."""
    return read_sidecar(frame).get(STAND_IN) is True


@dataclass(frozen=True)
class Provenance:
    """Frames taken for reality, split into stand-ins (renders) and real captures."""
    stand_in: tuple[Path, ...] = ()
    real: tuple[Path, ...] = ()

    def counts(self) -> dict[str, int]:
        """The keys every report carries: ``stand_in_frames``, ``real_frames``."""
        return {"stand_in_frames": len(self.stand_in), "real_frames": len(self.real)}

    def banner(self) -> str:
        return banner(len(self.stand_in), len(self.real))


def provenance(frames: Iterable[str | Path]) -> Provenance:
    stand_in, real = [], []
    for frame in frames:
        (stand_in if is_stand_in(frame) else real).append(Path(frame))
    return Provenance(tuple(stand_in), tuple(real))


def banner(stand_in_frames: int, real_frames: int) -> str:
    """One line saying how many of the frames taken for reality are stand-ins; '' when none is."""
    if not stand_in_frames:
        return ""
    made = "renders made by `capture shoot --source standin`, not photographs"
    if not real_frames:
        return (f"STAND-IN FRAMES: all {stand_in_frames} 'real' frame(s) are stand-ins ({made}): these figures "
                "compare renders with renders and say nothing about reality.")
    return (f"STAND-IN FRAMES: {stand_in_frames} of {stand_in_frames + real_frames} 'real' frames are stand-ins "
            f"({made}); {real_frames} are real captures. The figures on each are given apart: only those on the "
            "real captures say something about reality.")
