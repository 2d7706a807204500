"""A per-image feature cache: each image's Inception features are computed once.

Keys are content hashes, so a render copied into a pairs directory, or compared against
several sets, hits the cache; the extractor's fingerprint (weights sha1, resize filter and
size, input scaling) names the cache folder, so changing any of them never mixes features.
Writes are atomic (temp file + rename), so concurrent runs and interrupts are safe.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from ..atomic import atomic_open


def default_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "isu-validate" / "inception-features"


def content_key(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, lambda: hashlib.blake2b(digest_size=20)).hexdigest()


class FeatureCache:
    def __init__(self, root: Path, fingerprint: str, dim: int):
        self.folder = Path(root) / fingerprint
        self.dim = dim
        self.hits = 0
        self.misses = 0

    def _file(self, key: str) -> Path:
        return self.folder / key[:2] / f"{key}.npy"

    def get(self, key: str) -> np.ndarray | None:
        try:
            vec = np.load(self._file(key), allow_pickle=False)
        except (OSError, ValueError):
            self.misses += 1
            return None
        if vec.shape != (self.dim,) or not np.isfinite(vec).all():
            self.misses += 1  # damaged entry: recompute rather than trust it
            return None
        self.hits += 1
        return vec

    def put(self, key: str, vec: np.ndarray) -> None:
        with atomic_open(self._file(key), "wb") as fh:
            np.save(fh, np.asarray(vec, dtype=np.float32), allow_pickle=False)
