"""Which files are images: the one list of suffixes every image reader of isu-validate accepts.

Image sets, pairs, stylize inputs, calibration views and camera-model frames take these suffixes
(compared lower-case); the list is a contract (docs/ARCHITECTURE.md, "Image sets"). A leaf: imports
only the project's errors.
"""
from __future__ import annotations

from pathlib import Path

from .errors import InputError, InputNotFound

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


def expand_images(items, kind: str = "") -> list[Path]:
    """Files and folders to image files: a folder gives its images (sorted, hidden files left out), a
    file itself. One-line errors name a folder without images or a path that does not exist; ``kind``
    prefixes what they call it ("style " -> "style folder ...", "style image ...")."""
    paths: list[Path] = []
    for item in map(Path, items):
        if item.is_dir():
            found = sorted(p for p in item.iterdir()
                           if p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith("."))
            if not found:
                raise InputError(f"{kind}folder {item} holds no images ({', '.join(IMAGE_SUFFIXES)})")
            paths += found
        elif item.is_file():
            paths.append(item)
        else:
            raise InputNotFound(f"{kind}image {item} does not exist")
    return paths
