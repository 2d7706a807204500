"""Which files are images: the one list of suffixes every image reader of isu-validate accepts.

Image sets, pairs, stylize inputs, calibration views and camera-model frames take these suffixes
(compared lower-case); the list is a contract (docs/ARCHITECTURE.md, "Image sets"). A leaf: imports
only the project's errors.
"""
from __future__ import annotations

from pathlib import Path

from .errors import InputError, InputNotFound

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


def expand_images(items, kind: str = "", suffixes: tuple[str, ...] = IMAGE_SUFFIXES) -> list[Path]:
    """Files and folders to image files: a folder gives its images (sorted, hidden files left out), a
    file itself. One-line errors name a folder without images or a path that does not exist; ``kind``
    prefixes what they call it ("style " -> "style folder ...", "style image ..."); ``suffixes`` are the
    files a folder gives (a command that refuses some of them with its own words can take those too)."""
    paths: list[Path] = []
    for item in map(Path, items):
        if item.is_dir():
            found = sorted(p for p in item.iterdir() if p.is_file()
                           and p.suffix.lower() in suffixes and not p.name.startswith("."))
            if not found:
                raise InputError(f"{kind}folder {item} holds no images ({', '.join(IMAGE_SUFFIXES)})")
            paths += found
        elif item.is_file():
            paths.append(item)
        else:
            raise InputNotFound(f"{kind}image {item} does not exist")
    return paths
