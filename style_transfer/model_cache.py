"""The fast net for a style set, trained once and kept: train-or-load by the set's fingerprint.

The key is the style photos' content hashes (not their names or order) and every training setting.
The renders it trains on are not in the key: any renders of the cabin teach the same look, and a
pair added later must not cost a retraining; the model's metadata records how many it saw. Training
checkpoints into the cache folder, so an interrupted run resumes where it stopped, and the model file
appears atomically, so a reader sees no model or a whole one.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

from isu_validate.errors import InputError

from .fast import FORMAT, FastTrainConfig, load_model, train_fast
from .fast_net import FastStyleNet
from .style_set import fingerprint, style_paths


# What `stylize --pairs` trains. On 8 stand-in pairs (640x480 renders, one style photo; style gap closed
# at 256 px, 4 renders) Gatys closed 0.66; the fast net (zero-initialised output, net at FAST_SIZE):
# style weight 1, content relu2_2 plateaued near 0.30 by step 100; weight 5: 0.48 at 100 steps, 0.50
# at 150; weight 10 with Gatys' content layer relu4_2 (which lets colour and noise change but holds the
# layout): 0.47 at 100; weight 20, relu4_2: 0.51 at 50 steps, 0.56 at 150, SSIM-luma 0.96 (Gatys 0.88).
# Then on all 8 pairs of runs/rq3/pairs8 (standard 640x480 renders, stand-in frames as the style set,
# quiet machine): weight 40, 150 steps closed 0.63 at SSIM-luma 0.91; weight 80 no more (0.63) at 0.85;
# weight 40, 220 steps 0.65 at 0.93, training 208 s (0.94 s a step): what the 5-minute budget for the
# paper's 53 pairs leaves after the styling itself (about 30 s), with a margin.
AUTO_TRAIN = replace(FastTrainConfig(), steps=220, style_weight=40.0, content_layers=("relu4_2",))
# the longer side the net runs at (stylize_fast(size=...)): near the scale it trains at (crops of renders
# scaled to a 160 px short side, style photos at 256 px). At the full 640x480 the same net closed the
# style gap about as much (0.32 against 0.30) but its noise, drawn at full resolution, cost SSIM-luma
# (0.83 against 0.96); the change made at 256 px and upsampled leaves the render's detail alone.
FAST_SIZE = 256


def default_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "isu-validate" / "fast-style"


def model_key(styles: Sequence[Path], cfg: FastTrainConfig) -> str:
    settings = json.dumps({"format": FORMAT, "styles": fingerprint(styles), "train": asdict(cfg)}, sort_keys=True)
    return hashlib.sha256(settings.encode()).hexdigest()[:20]


@dataclass
class CachedModel:
    net: FastStyleNet
    meta: dict
    path: Path
    trained: bool            # False: loaded from the cache
    train_seconds: float     # this call's training time (0 on a cache hit)


def fast_model_for(styles: Sequence[str | Path], renders: Sequence[Path], cfg: FastTrainConfig | None = None,
                   cache_dir: Path | None = None,
                   progress: Callable[[int, int, float], None] | None = None, device: str = "cpu") -> CachedModel:
    """The fast net for the style photos ``styles`` (files or folders): loaded when the cache holds one
    for the same photos and settings, otherwise trained on crops of ``renders`` (resuming a checkpoint
    an interrupted training left) and stored. Style photos that cannot be read raise one-line InputErrors.

    The key holds no device: a net trained on a GPU is a net of the same settings (training is not bit
    for bit reproducible anyway), and running it elsewhere only rounds floats differently; its meta says
    where it was trained (``trained_on``). The net comes back on ``device``."""
    cfg = cfg or AUTO_TRAIN
    photos = style_paths(styles)
    path = Path(cache_dir or default_cache_dir()) / f"{model_key(photos, cfg)}.pt"
    if path.is_file():
        try:
            net, meta = load_model(path)
            return CachedModel(net.to(device), meta, path, False, 0.0)
        except InputError:  # damaged (a disk fault; writes are atomic): a cache entry is only ever retrained
            path.unlink()
    start = time.perf_counter()
    train_fast(photos, list(renders), path, cfg, resume=True, progress=progress, device=device)
    net, meta = load_model(path)
    return CachedModel(net.to(device), meta, path, True, time.perf_counter() - start)
