"""A dataset (``isu-validate dataset``) as training data for ``reference train --extra``.

The dataset folder is read by its own reader (``isu_validate.dataset.folder``: ``dataset.json`` and the
rows of ``metadata.jsonl``); this turns what it read into labelled images. A feature the frame hides
(the row's ``occluded``) is left out of that image's labels: the heads should not learn to see what
is not there.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Iterable

from ..errors import InputError, InputNotFound
from .feature_bank import check_made_with
from .retrain import ExtraSet


def extra_set(folder: Path, info: dict, rows: Iterable[dict], space, variants: Iterable[str] | None = None) -> ExtraSet:
    """The rows of the dataset in ``folder`` (all, or those whose ``variant`` is in ``variants``:
    ``render``, ``style1``...) as images with their labels, and what they were made with."""
    folder, wanted = Path(folder), set(variants) if variants is not None else None
    meta = {"space": info.get("space"), "space_hash": info.get("space_hash"),
            "renderer": (info.get("versions") or {}).get("renderer", info.get("renderer"))}
    check_made_with(meta, f"dataset {folder}", space, None, "", "")   # its scenes mean nothing in another space
    images, scenes, left_out = [], [], 0
    for row in rows:
        if wanted is not None and row.get("variant", "render") not in wanted:
            continue
        image = folder / row["file_name"]
        if not image.is_file():
            raise InputNotFound(f"dataset {folder}: image {row['file_name']} is missing")
        canonical = space.canonical(row["scene"])
        occluded = set(row.get("occluded") or ())
        scenes.append({k: v for k, v in canonical.items() if k not in occluded})
        left_out += len(canonical) - len(scenes[-1])
        images.append(image)
    if not images:
        raise InputError(f"dataset {folder} has no images" + (f" of variant {sorted(wanted)}" if wanted else ""))
    return ExtraSet(str(folder.resolve()), images, scenes, meta, left_out, content_hash(images, scenes),
                    source_runs(info))


def content_hash(images: list[Path], scenes: list[dict]) -> str:
    """What the retrain learned from: every image's bytes and its labels (16 hex digits)."""
    digest = hashlib.sha256()
    for image, scene in zip(images, scenes):
        digest.update(Path(image).read_bytes())
        digest.update(json.dumps(scene, sort_keys=True).encode())
    return digest.hexdigest()[:16]


def source_runs(info: dict) -> list[dict]:
    """The runs a focused dataset was drawn near, with the SUT and threshold that made their tests fail."""
    focus = info.get("focus") or {}
    judged = focus.get("judged_by")
    if judged:
        return [{k: r.get(k) for k in ("run", "sut", "sut_options", "threshold")} for r in judged]
    return [{"run": run} for run in focus.get("runs", [])]
