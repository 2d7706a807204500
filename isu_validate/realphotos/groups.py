"""Which photos of a real set belong together (one driver, one video clip): a CSV of image and group.

Frames of one driver's video are near-twins, so a set of 800 frames of 26 drivers holds far fewer than 800
independent photos; ``transfer`` then resamples whole groups for its intervals. The CSV has an image column
(as the layouts read them: ``image``, ``img``, ``filename``...) and a group column (``group``, ``subject``,
``driver``, ``clip``, ``video``, ``session``); an image is named by its path under the set's root or by its
file name alone.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import InputNotFound
from .layouts import IMAGE_COLUMNS, read_csv

GROUP_COLUMNS = ("group", "subject", "driver", "clip", "video", "session")


def read_groups(path: str | Path) -> dict[str, str]:
    """{image name: group}, each image by its relative path and by its file name (the latter where unique)."""
    path = Path(path)
    if not path.is_file():
        raise InputNotFound(f"groups file {path} does not exist")
    rows, (image, group) = read_csv(path, "a groups CSV", image=IMAGE_COLUMNS, group=GROUP_COLUMNS)
    out: dict[str, str] = {}
    names: dict[str, set] = {}
    for row in rows:
        key, value = str(row[image]).strip(), str(row[group]).strip()
        out[key] = value
        names.setdefault(Path(key).name, set()).add(value)
    out.update({name: next(iter(v)) for name, v in names.items() if len(v) == 1 and name not in out})
    return out


def group_of(groups: dict[str, str], photo: Path, root: Path) -> str | None:
    relative = str(photo.relative_to(root)) if photo.is_relative_to(root) else str(photo)
    return groups.get(relative, groups.get(photo.name))
