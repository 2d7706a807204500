"""Reading the project's TOML files (spaces, rigs, camera files) with errors that name the file."""
from __future__ import annotations

import os
import tomllib
from pathlib import Path

from .errors import InputNotFound


def read_toml(path: str | os.PathLike, error: type[Exception], what: str = "file") -> dict:
    """The file's tables; FileNotFoundError when missing, ``error`` (naming the file) when not TOML."""
    path = Path(path)
    if not path.exists():
        raise InputNotFound(f"{what} {path} does not exist")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None
