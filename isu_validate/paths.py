"""Where the shipped rigs/ and data/ folders are found.

A source checkout has them beside the package; a wheel install puts them under
``<prefix>/share/isu-validate``.  ``ISU_VALIDATE_HOME`` overrides both.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

from .errors import InputNotFound


def _candidates() -> list[Path]:
    found = []
    if os.environ.get("ISU_VALIDATE_HOME"):
        found.append(Path(os.environ["ISU_VALIDATE_HOME"]))
    found.append(Path(__file__).resolve().parent.parent)
    found.append(Path(sys.prefix) / "share" / "isu-validate")
    return found


def home() -> Path:
    """The folder that holds ``rigs/`` and ``data/``."""
    for root in _candidates():
        if (root / "rigs").is_dir():
            return root
    raise InputNotFound(
        "cannot find isu-validate's rigs/ folder; set ISU_VALIDATE_HOME to the folder that holds rigs/ and data/"
    )


def rigs_dir() -> Path:
    return home() / "rigs"


def data_dir() -> Path:
    return home() / "data"


def resolve_rig(kind: str, name_or_path: str | os.PathLike) -> Path:
    """A rig given by name (``default``) or path (``my/rig.toml``)."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        if not path.exists():
            raise InputNotFound(f"{kind} rig file {path} does not exist")
        return path
    shipped = rigs_dir() / kind / f"{name_or_path}.toml"
    if not shipped.exists():
        names = sorted(p.stem for p in (rigs_dir() / kind).glob("*.toml"))
        raise InputNotFound(f"no {kind} rig named {name_or_path!r}; shipped ones: {', '.join(names) or 'none'}")
    return shipped
