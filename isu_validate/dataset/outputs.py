"""The files of a complete dataset, written from its manifest (each atomically): ``metadata.jsonl`` (the
Hugging Face image-folder convention: at the root, ``file_name`` relative to it, one row per image),
``vqa.jsonl``, ``annotations.json`` (COCO), and ``dataset.json`` and the card."""
from __future__ import annotations

import json
import time

from ..atomic import atomic_open, write_json, write_text
from ..space import SceneSpace
from .card import card_markdown
from .coco import coco_document
from .folder import ANNOTATIONS_FILE, CARD_FILE, METADATA_FILE, VQA_FILE, DatasetDir
from .vqa import vqa_row


def metadata_rows(space: SceneSpace, entry: dict) -> list[dict]:
    """One row per image of a slot: the run label's fields (space, scene_key, scene, truth, visibility,
    occluded) with the file, its variant and the render it was made from (and, in a varied dataset, the camera
    jitter and sensor effects drawn for it: ``variety``)."""
    scene = entry["scene"]
    label = {"space": space.name, "space_hash": space.hash, "scene_key": space.key(scene), "scene": scene,
             "truth": {q.key: q.truth for q in space.questions(scene)}, "visibility": entry["visibility"],
             "occluded": entry["occluded"]}
    render = entry["files"][0]["file_name"]
    return [{"file_name": f["file_name"], **label, "variant": f["variant"], "source": render,
             "style": f.get("style"), "slot": entry["slot"], "region": entry["region"],
             **({"variety": entry["variety"]} if entry.get("variety") else {})} for f in entry["files"]]


def write_outputs(folder: DatasetDir, space: SceneSpace, entries: list[dict], info: dict, prompt_style: str) -> None:
    rows = [row for entry in entries for row in metadata_rows(space, entry)]
    with atomic_open(folder.path / METADATA_FILE) as fh:
        fh.writelines(json.dumps(row) + "\n" for row in rows)
    with atomic_open(folder.path / VQA_FILE) as fh:
        fh.writelines(json.dumps(vqa_row(space, row["scene"], row["file_name"], row["occluded"], prompt_style)) + "\n"
                      for row in rows)
    images = [{"file_name": f["file_name"], "width": e["width"], "height": e["height"],
               "annotations": e["annotations"]} for e in entries for f in e["files"]]
    coco_info = {"description": f"isu-validate dataset of scene space {space.name} ({space.hash})",
                 "version": info["format"], "year": int(time.strftime("%Y")), "date_created": info.get("finished")}
    licenses = [{"id": k, "name": entry["licence"], "url": ""} for k, entry in enumerate(info["licences"], 1)]
    write_json(folder.path / ANNOTATIONS_FILE, coco_document(images, coco_info, licenses))
    folder.write_info(info)
    write_text(folder.path / CARD_FILE, card_markdown(info))
