"""On-disk cache of SUT replies, keyed by (image hash, prompt hash, SUT fingerprint, repeat index).

A resumed or repeated run does not pay twice.  Only replies are cached, never
transport errors (a timeout deserves another try next time).  We store the reply
as the SUT gave it and parse it again on every hit, so a better parser improves
old runs too.  Writes are atomic (temp file + rename), so parallel workers and
killed runs never leave half an entry.
"""
from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

from ..atomic import write_json
from ..protocols import SUTRequest

CACHE_VERSION = 1


@lru_cache(maxsize=512)
def _file_hash(path: str, size: int, mtime_ns: int) -> str:
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def image_hash(path: str | os.PathLike) -> str:
    stat = os.stat(path)
    return _file_hash(str(path), stat.st_size, stat.st_mtime_ns)


def prompt_hash(request: SUTRequest) -> str:
    blob = json.dumps({"mode": request.mode, "prompt": request.prompt,
                       "questions": [q.to_dict() for q in request.questions]}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


class ResponseCache:
    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)

    def key(self, request: SUTRequest, fingerprint: str, repeat: int) -> str:
        parts = [image_hash(request.image), prompt_hash(request), fingerprint, str(repeat)]
        return hashlib.sha256("|".join(parts).encode()).hexdigest()

    def _path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.json"

    def get(self, key: str) -> dict[str, Any] | None:
        try:
            entry = json.loads(self._path(key).read_text())
        except (OSError, ValueError):
            return None  # absent, or unreadable: ask again
        return entry if entry.get("version") == CACHE_VERSION else None

    def put(self, key: str, entry: dict[str, Any]) -> None:
        write_json(self._path(key), {"version": CACHE_VERSION, **entry})
