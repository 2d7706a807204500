"""COCO instance segmentation from the renderer's seg channel (uint16 instance ids, ``render/labels.py``).

One category per render instance (its id is the instance id, its supercategory the instance's class:
``driver``, ``driver_face``, ``seat_belt``, ``phone``, ``child_seat``, ``child``, ``luggage``, the
co-driver seat's objects, the cabin's parts); one annotation per instance a frame shows, its mask as
compressed RLE (pycocotools), ``area`` its pixel count and ``bbox`` [x, y, w, h] its extent, both taken
from that RLE, so they agree with the mask by construction. Instances never in a scene frame (the
calibration board) are not categories.
"""
from __future__ import annotations

from typing import Iterable

import numpy as np

from ..render.labels import INSTANCES

NOT_IN_SCENES = ("board",)
CATEGORIES = [{"id": i, "name": name, "supercategory": cls}
              for i, (name, cls) in sorted(INSTANCES.items()) if name not in NOT_IN_SCENES]
CATEGORY_IDS = frozenset(c["id"] for c in CATEGORIES)


def instance_annotations(ids: np.ndarray) -> list[dict]:
    """Annotations (without ``id`` and ``image_id``) of every category instance in an instance-id image."""
    from pycocotools import mask as rle_codec

    out = []
    for i in np.unique(ids):
        if int(i) not in CATEGORY_IDS:
            continue
        rle = rle_codec.encode(np.asfortranarray(ids == i, dtype=np.uint8))
        out.append({"category_id": int(i), "segmentation": {"size": [int(s) for s in rle["size"]],
                                                            "counts": rle["counts"].decode("ascii")},
                    "area": int(rle_codec.area(rle)), "bbox": [float(v) for v in rle_codec.toBbox(rle)],
                    "iscrowd": 0})
    return out


def coco_document(images: Iterable[dict], info: dict, licenses: list[dict]) -> dict:
    """The annotations.json document. ``images``: {"file_name", "width", "height", "annotations"} in order;
    image and annotation ids are assigned here, from 1."""
    doc = {"info": info, "licenses": licenses, "images": [], "annotations": [], "categories": CATEGORIES}
    for image_id, image in enumerate(images, 1):
        doc["images"].append({"id": image_id, "file_name": image["file_name"], "width": image["width"],
                              "height": image["height"]})
        for ann in image["annotations"]:
            doc["annotations"].append({"id": len(doc["annotations"]) + 1, "image_id": image_id, **ann})
    return doc
