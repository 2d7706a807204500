"""Image sets: a folder of images, or one role (sim, real, nst) of a sim/real pairs directory.

The pairs layout is read by ``isu_validate.pairs`` (the one place that knows it).
A set is written ``DIR`` (a folder of images) or ``PAIRS_DIR:ROLE``. A set of captures (the real
role, or a folder holding stand-ins) knows which of its frames are stand-in renders (``provenance``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from capture.sidecar import Provenance, provenance

from ..pairs import ROLES, PairsDir, PairsError
from .images import ImageError, list_frames


@dataclass
class ImageSet:
    label: str
    paths: list[Path]
    left_out: list[Path] = field(default_factory=list)  # render by-products in the folder (contact sheet...)
    role: str | None = None                               # the pairs role, when the set is one

    def provenance(self) -> Provenance | None:
        """Stand-ins and real captures of a set taken for reality (a pairs real role, or any set holding
        stand-ins); None for a set of renders."""
        marks = provenance(self.paths)
        return marks if self.role == "real" or marks.stand_in else None


def is_pairs_dir(folder: Path) -> bool:
    return PairsDir.looks_like(folder)


def pairs_role(folder: Path, role: str) -> list[Path]:
    """The images of one role across all samples, sorted by sample name (read by ``isu_validate.pairs``)."""
    if role not in ROLES:
        raise ImageError(f"unknown pairs role {role!r}; choose one of {', '.join(ROLES)}")
    try:
        return PairsDir(folder).role_images(role)
    except PairsError as exc:
        raise ImageError(str(exc)) from None


def resolve_set(spec: str) -> ImageSet:
    """``DIR`` or ``PAIRS_DIR:ROLE`` to a labelled list of image files."""
    path = Path(spec)
    if not path.exists() and ":" in spec:
        folder, role = spec.rsplit(":", 1)
        return ImageSet(spec, pairs_role(Path(folder), role), role=role)
    if is_pairs_dir(path):
        raise ImageError(f"{path} is a pairs directory: name the role, e.g. {spec}:sim or {spec}:real")
    return ImageSet(spec, *list_frames(path))
