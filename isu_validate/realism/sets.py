"""Image sets: a folder of images, or one role (sim, real, nst) of a sim/real pairs directory.

Pairs layout (ARCHITECTURE.md): ``pairs/<sample>/sim.png``, ``real/*.png``, optional ``nst.png``.
A set is written ``DIR`` (a folder of images) or ``PAIRS_DIR:ROLE``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .images import IMAGE_SUFFIXES, ImageError, list_frames

ROLES = ("sim", "real", "nst")


@dataclass
class ImageSet:
    label: str
    paths: list[Path]
    left_out: list[Path] = field(default_factory=list)  # render by-products in the folder (contact sheet...)


def is_pairs_dir(folder: Path) -> bool:
    return folder.is_dir() and any((d / "sim.png").is_file() for d in folder.iterdir() if d.is_dir())


def pairs_role(folder: Path, role: str) -> list[Path]:
    """The images of one role across all samples, sorted by sample name."""
    if role not in ROLES:
        raise ValueError(f"unknown pairs role {role!r}; choose one of {', '.join(ROLES)}")
    if not is_pairs_dir(folder):
        raise ImageError(f"{folder} is not a pairs directory (no <sample>/sim.png inside)")
    found: list[Path] = []
    for sample in sorted(d for d in folder.iterdir() if d.is_dir()):
        if role == "real":
            real = sample / "real"
            if real.is_dir():
                found += sorted(p for p in real.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        elif (sample / f"{role}.png").is_file():
            found.append(sample / f"{role}.png")
    if not found:
        hint = " (run `isu-validate stylize --pairs` to write nst.png)" if role == "nst" else ""
        raise ImageError(f"pairs directory {folder} has no {role} images{hint}")
    return found


def resolve_set(spec: str) -> ImageSet:
    """``DIR`` or ``PAIRS_DIR:ROLE`` to a labelled list of image files."""
    path = Path(spec)
    if not path.exists() and ":" in spec:
        folder, role = spec.rsplit(":", 1)
        return ImageSet(spec, pairs_role(Path(folder), role))
    if is_pairs_dir(path):
        raise ImageError(f"{path} is a pairs directory: name the role, e.g. {spec}:sim or {spec}:real")
    return ImageSet(spec, *list_frames(path))
