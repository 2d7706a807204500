"""The on-disk cache of people: topologies (triangles, UVs, material regions, head split, hair) and
posed states (vertices in the cabin, hair, belt straps, the phone in the hand), as .npz files.

An entry's key hashes everything that decides its content: the code that made it (PEOPLE_VERSION and
the source of the modules that decide it, ``CONTENT_MODULES``, so a changed pose or region never comes
back from an old cache), anny's version, the parts of the cabin rig the pose depends on, and the inputs
(gender, classes, expression, phone position...). Entries are written to a temporary file and renamed into place, so
the processes of a pool can share the folder. It lives beside anny's model cache (``ANNY_CACHE_DIR``,
default ``<sys.prefix>/share/anny``) in ``isu-validate-people/``; ``ISU_PEOPLE_CACHE`` moves it.

Posing (anny, torch) stays on the CPU whatever ``--device`` says: a body of a few thousand vertices, posed
once and kept here; a GPU's start-up and copies would cost more than the work, and the cached vertices, part
of every render, stay the same on every desk. (Said here: a comment in a ``CONTENT_MODULES`` file would
change every cache key.)"""
from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path

import numpy as np

from ...atomic import atomic_open
from .model import anny_cache_dir, anny_version

# bump when posing, regions, hair, belt or expressions change what an entry holds
PEOPLE_VERSION = "people-1"


def people_cache_dir() -> Path:
    return Path(os.environ.get("ISU_PEOPLE_CACHE") or anny_cache_dir() / "isu-validate-people")


# the modules whose code decides what an entry holds (posing reads the seat and wheel from cabin_geometry);
# the cache's own tools (store, warm, checks) are not among them, so changing them keeps the cache
CONTENT_MODULES = ("accessories", "belt", "child", "expressions", "garments", "hair", "hands", "limbs", "model",
                   "people", "phenotype", "regions", "seated", "skeleton", "surface", "../cabin_geometry")


@lru_cache(maxsize=1)
def code_version() -> str:
    """PEOPLE_VERSION and a hash of the source of ``CONTENT_MODULES``."""
    digest = hashlib.sha256(PEOPLE_VERSION.encode())
    for name in CONTENT_MODULES:
        digest.update((Path(__file__).parent / f"{name}.py").read_bytes())
    return f"{PEOPLE_VERSION}-{digest.hexdigest()[:12]}"


def entry_key(kind: str, inputs: dict) -> str:
    content = {"version": code_version(), "anny": anny_version(), "kind": kind, **inputs}
    return hashlib.sha256(json.dumps(content, sort_keys=True, default=str).encode()).hexdigest()


class PeopleStore:
    def __init__(self, root: str | os.PathLike | None = None):
        self.root = Path(root) if root else people_cache_dir()

    def path(self, kind: str, key: str) -> Path:
        return self.root / kind / f"{key[:24]}.npz"

    def get(self, kind: str, key: str) -> Path | None:
        path = self.path(kind, key)
        return path if path.is_file() else None

    def put(self, kind: str, key: str, arrays: dict) -> Path:
        path = self.path(kind, key)
        with atomic_open(path, "wb") as f:   # a reader never sees half an entry
            np.savez(f, **arrays)
        return path

    def load(self, kind: str, key: str) -> dict | None:
        path = self.get(kind, key)
        return None if path is None else load_entry(path)


def load_entry(path: str | os.PathLike) -> dict:
    """An entry's arrays by name."""
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}
