"""One frame through the three yardsticks: a JSON-able record of what each said, and the crops it read."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .expression import HAPPY, LABELS, ExpressionReader
from .faces import FaceDetector, match
from .frames import Frame, read_image
from .objects import ObjectRecogniser, hits, square_crop, upright_crop


@dataclass
class Yardsticks:
    """The three photo-trained models, loaded once."""
    faces: FaceDetector
    expression: ExpressionReader
    objects: ObjectRecogniser

    @classmethod
    def load(cls, device: str = "cpu") -> "Yardsticks":
        return cls(FaceDetector(device), ExpressionReader(device), ObjectRecogniser(device))

    def describe(self) -> dict:
        return {"face": self.faces.name, "expression": self.expression.name, "objects": self.objects.name}


def read_frame(frame: Frame, models: Yardsticks) -> tuple[dict, list[tuple[np.ndarray, str]]]:
    """The frame's record (``frames.jsonl``) and its (crop, caption) pairs for the contact sheet."""
    rgb = read_image(frame.image)
    boxes = frame.boxes_for(rgb.shape[1], rgb.shape[0])
    ups = frame.up_for(rgb.shape[1], rgb.shape[0])
    record = {"name": frame.name, "image": str(frame.image), "kind": frame.kind, "preset": frame.preset,
              **frame.light(), "size": [int(rgb.shape[1]), int(rgb.shape[0])], "own_boxes": frame.own_boxes,
              "items": []}
    crops = []
    faces = models.faces.detect(rgb)
    record["faces_detected"] = len(faces)
    objects = []
    for unit, status in frame.units():
        item = {"feature": unit.name, "instance": unit.instance, "status": status,
                "box": list(boxes[unit.instance]) if unit.instance in boxes else None}
        if unit.instance in ups:
            item["up"] = [round(float(v), 4) for v in ups[unit.instance]]
        if unit.name == "face":
            item["emotion"] = frame.scene.get("driver_emotion")
        record["items"].append(item)
        if unit.name == "face":
            crops.append(_face(item, frame, rgb, faces, models))
        elif status == "visible":
            objects.append(item)
    crops += _objects(objects, rgb, models)
    return record, [c for c in crops if c is not None]


def _face(item: dict, frame: Frame, rgb: np.ndarray, faces, models: Yardsticks):
    import cv2

    truth = tuple(item["box"]) if item["box"] and frame.own_boxes else None
    found = match(faces, truth)
    item.update(found=found is not None, p=found.p if found else None,
                detected_box=[round(v, 1) for v in found.box] if found else None,
                width_px=round(found.width, 1) if found else None,
                truth_width_px=(item["box"][2] - item["box"][0]) if item["box"] else None)
    if item["status"] != "visible":
        return None
    # expression is read on the detector's box (as fer does), else on the head mask's box: so a missed
    # detection does not hide what the expression model makes of the face
    box = found.xywh() if found else _xywh(item["box"]) if item["box"] else None
    if box is None:
        return None
    probs = models.expression.read(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), [box])[0]
    truth_emotion = item["emotion"]
    item["expression"] = {"truth": truth_emotion, "box_from": "detector" if found else "mask",
                          "read": LABELS[int(probs.argmax())], "p_happy": round(float(probs[HAPPY]), 4),
                          "probs": {k: round(float(v), 4) for k, v in zip(LABELS, probs, strict=True)}}
    said = f"{'face' if found else 'NO face'} | {truth_emotion}->{item['expression']['read']}"
    return _crop(rgb, tuple(int(v) for v in (found.box if found else item["box"]))), said


def _objects(items: list[dict], rgb: np.ndarray, models: Yardsticks):
    """Each thing read as seen and, where its label says where its top points, turned upright too
    (``item["upright"]``): the classifier's view of the thing, apart from the pose it lies in."""
    crops = [square_crop(rgb, tuple(item["box"])) for item in items]
    turned = [i for i, item in enumerate(items) if "up" in item]
    upright = [upright_crop(rgb, tuple(items[i]["box"]), tuple(items[i]["up"])) for i in turned]
    reads = models.objects.top(crops + upright)
    out = []
    for item, crop, top in zip(items, crops, reads[:len(items)], strict=True):
        top1, top5 = hits(item["feature"], top)
        item.update(top=[[c, round(p, 4)] for c, p in top], top1=top1, top5=top5, crop_px=int(crop.shape[0]))
        out.append((crop, f"{item['feature']}: {top[0][0]}{' (top-5 hit)' if top5 else ''}"))
    for i, crop, top in zip(turned, upright, reads[len(items):], strict=True):
        item = items[i]
        top1, top5 = hits(item["feature"], top)
        item["upright"] = {"top": [[c, round(p, 4)] for c, p in top], "top1": top1, "top5": top5}
        out.append((crop, f"{item['feature']} upright: {top[0][0]}{' (top-5 hit)' if top5 else ''}"))
    return out


def _xywh(box) -> tuple:
    return box[0], box[1], box[2] - box[0], box[3] - box[1]


def _crop(rgb: np.ndarray, box: tuple) -> np.ndarray:
    x0, y0, x1, y1 = (max(0, v) for v in box)
    return rgb[y0:max(y1, y0 + 1), x0:max(x1, x0 + 1)]
