"""Atomic file writes: a reader (a parallel worker, a resumed run) sees the old file or the whole new one.

Everything is written to a temporary file in the target's own folder (a rename across file systems
is not atomic) and renamed over the target; on any error the temporary file is removed and the old
file stays as it was. The temporary name is ``.tmp-<name>.<random>.tmp``: hidden, recognisable, and
never taken for an image or an entry should a killed process leave it; a writer that infers the
format from the name (``cv2.imwrite``) asks for the target's suffix after it (``keep_suffix``).

A leaf: imports nothing of the project.
"""
from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from typing import IO, Any, Iterator

__all__ = ["atomic_open", "atomic_path", "write_bytes", "write_json", "write_text"]


@contextmanager
def atomic_path(path: str | os.PathLike, keep_suffix: bool = False) -> Iterator[Path]:
    """A temporary path to write ``path``'s new content into; renamed over ``path`` when the block ends
    without an error. ``with atomic_path(out, keep_suffix=True) as tmp: cv2.imwrite(str(tmp), image)``"""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = f".tmp{path.suffix}" if keep_suffix else ".tmp"
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".tmp-{path.name}.", suffix=suffix)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        _as_plain_file(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", **kwargs) -> Iterator[IO]:
    """``open`` for writing, atomically: ``with atomic_open(out, newline="") as f: csv.writer(f)...``"""
    if "w" not in mode:
        raise ValueError(f"atomic_open writes a whole file: mode {mode!r} has no 'w'")
    if "b" not in mode:
        kwargs.setdefault("encoding", "utf-8")
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: str | os.PathLike, obj: Any, **dumps: Any) -> Path:
    """``obj`` as JSON (``dumps``: ``json.dumps`` options, e.g. ``indent=2``), atomically."""
    return write_text(path, json.dumps(obj, **dumps))


def _as_plain_file(tmp: Path) -> None:
    """The permissions ``open`` would have given (mkstemp makes the file private to its owner)."""
    os.chmod(tmp, 0o666 & ~_umask())


@cache
def _umask() -> int:
    """The process's umask, read once: reading it means setting it, which races with other threads."""
    umask = os.umask(0o022)
    os.umask(umask)
    return umask
