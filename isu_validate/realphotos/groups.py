"""Which photos of a real set belong together (one driver, one video clip): a CSV of image and group.

Frames of one driver's video are near-twins, so a set of 800 frames of 26 drivers holds far fewer than 800
independent photos; ``transfer`` then resamples whole groups for its intervals. The CSV has an image column
(as the layouts read them: ``image``, ``img``, ``filename``...) and a group column (``group``, ``subject``,
``driver``, ``clip``, ``video``, ``session``); an image is named by its path under the set's root or by its
file name alone.
"""
from __future__ import annotations

import csv
from pathlib import Path

from ..errors import InputError, InputNotFound
from .layouts import IMAGE_COLUMNS

GROUP_COLUMNS = ("group", "subject", "driver", "clip", "video", "session")


def read_groups(path: str | Path) -> dict[str, str]:
    """{image name: group}, each image by its relative path and by its file name (the latter where unique)."""
    path = Path(path)
    if not path.is_file():
        raise InputNotFound(f"groups file {path} does not exist")
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    columns = {c.lower().strip(): c for c in (rows[0].keys() if rows else ())}
    image = next((columns[c] for c in IMAGE_COLUMNS if c in columns), None)
    group = next((columns[c] for c in GROUP_COLUMNS if c in columns), None)
    if image is None or group is None:
        raise InputError(f"{path}: a groups CSV needs an image column ({', '.join(IMAGE_COLUMNS)}) and a group "
                         f"column ({', '.join(GROUP_COLUMNS)}); it has {', '.join(columns) or 'none'}")
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
