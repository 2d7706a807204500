"""Which command's output a folder holds: the one check every command makes before it writes a folder.

Each command that writes a folder (``run``, ``dataset``, ``replay``, ``reference train``, ``report``,
``agree``, ``recreate``, ``stylize``, ``exposure``, ``bench ...``) calls ``claim_output`` at its top,
before anything is written, and ``Output.mark()`` when it starts writing. The marker, ``.isu-validate.json``,
names the command and the settings that decide the folder's content (with their digest). A later
command refuses the folder when it holds another command's output, or the same command's output made
with other settings, unless the user resumes it (``resume``: the command checks the details itself) or
says ``overwrite``. Folders written before the marker existed are recognised by their files (``run.json``,
``dataset.json``, ``heads.json``...): the outputs users already have are protected too.

    output = claim_output(out, "replay", {"run": "...", "sut": "reference"}, overwrite=False)
    ...                      # checks that write nothing
    output.mark()            # the folder is this command's from here on
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..atomic import write_json
from ..errors import UserError

__all__ = ["MARKER", "Difference", "Output", "OutputInUse", "claim_output", "claim_output_file",
           "differences_between", "holder", "is_empty"]

MARKER = ".isu-validate.json"
# files that name the command whose output a folder holds, for folders from before the marker (first match
# wins: a run folder may also hold a report.html); with the JSON file and key that kept its settings
SIGNATURES: tuple[tuple[str, str, tuple[str, str] | None], ...] = (
    ("run.json", "run", ("run.json", "identity")),
    ("dataset.json", "dataset", ("dataset.json", "identity")),
    ("heads.json", "reference train", None),
    ("model_card.json", "reference train", None),
    ("replay.csv", "replay", ("summary.json", "settings")),
    ("agreement.csv", "agree", ("summary.json", "settings")),
    ("pairs.json", "recreate", None),
    ("report.json", "report", None),
    ("check.json", "exposure check", None),
    ("stylize.json", "stylize", None),
    ("stages.json", "bench augment", None),
    ("session.json", "capture shoot", None),
    ("frames.jsonl", "recognise", ("summary.json", "settings")),
)


class OutputInUse(UserError):
    """An output folder that holds another command's output, or this command's with other settings."""


@dataclass(frozen=True)
class Difference:
    setting: str     # e.g. "seed" or "pipeline.sut"
    stored: Any
    now: Any

    def __str__(self) -> str:
        return f"{self.setting}: {self.stored!r} in the stored run, {self.now!r} now"


def differences_between(stored: dict, now: dict, prefix: str = "") -> list[Difference]:
    """Every setting (nested dicts flattened to dotted names, adapter options kept whole) whose value differs."""
    out = []
    for key in sorted(set(stored) | set(now)):
        a, b = stored.get(key), now.get(key)
        if isinstance(a, dict) and isinstance(b, dict) and key != "sut_options":
            out += differences_between(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(Difference(prefix + key, a, b))
    return out


@dataclass(frozen=True)
class Holder:
    """What a folder holds: the command, its settings when known, and how we know (the marker or a file)."""
    command: str
    settings: dict | None
    evidence: str


@dataclass(frozen=True)
class Output:
    """A folder this command may write; ``mark()`` records it as this command's (call it as writing starts)."""
    path: Path
    command: str
    settings: dict

    def mark(self) -> Path:
        return write_json(self.path / MARKER, {"command": self.command, "digest": digest(self.settings),
                                               "settings": _plain(self.settings),
                                               "marked": time.strftime("%Y-%m-%dT%H:%M:%S%z")}, indent=2)


def claim_output(path: str | os.PathLike, command: str, settings: dict, *, resume: bool = False,
                 overwrite: bool | None = False, argument: str = "out") -> Output:
    """``path`` as ``command``'s output folder, made with ``settings`` (what decides its content); writes
    nothing. Raises ``OutputInUse`` for a folder that holds another command's output, or this command's made
    with other settings (each difference named), unless ``overwrite``; with ``resume`` this command's own
    output is accepted whatever its settings (the command compares them). ``overwrite=None``: the command
    cannot write over an output (``run``, ``dataset``), so the error does not offer it. ``argument`` is the
    Python argument the error names (``--out`` on the command line)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputInUse.naming(f"{path} is a file; {command} writes a folder: name a folder for {{out}}", argument)
    found = None if overwrite or is_empty(path) else holder(path)
    if found and found.command != command:
        raise OutputInUse.naming(
            f"{path} holds the output of `isu-validate {found.command}` ({found.evidence}); `isu-validate {command}` "
            f"would change it: choose another folder for {{out}}{_or_overwrite(overwrite, 'write over it')}", argument)
    if found and not resume and found.settings is not None:
        stored = {k: v for k, v in found.settings.items() if k in settings}
        differences = differences_between(stored, _plain(settings))
        if differences:
            listed = "; ".join(f"{d.setting}: {_shown(d.stored)} then, {_shown(d.now)} now" for d in differences)
            raise OutputInUse.naming(
                f"{path} holds `isu-validate {command}` output made with other settings ({listed}); choose "
                f"another folder for {{out}} to keep both{_or_overwrite(overwrite, 'replace it')}", argument)
    return Output(path, command, settings)


def claim_output_file(path: str | os.PathLike, command: str, *, overwrite: bool = False,
                      argument: str = "out") -> Path:
    """``path`` as a file ``command`` writes (``realism --out``): refused, unless ``overwrite``, when it is
    already there (a file the user made earlier) or when its folder holds another command's output. Writes
    nothing."""
    path = Path(path)
    if path.is_dir():
        raise OutputInUse.naming(f"{path} is a folder; {command} writes a file: name a file for {{out}}", argument)
    found = None if overwrite else holder(path.parent)
    if found:
        raise OutputInUse.naming(
            f"{path} is inside the output of `isu-validate {found.command}` ({path.parent / found.evidence}); "
            f"choose a file elsewhere for {{out}}, or pass {{overwrite}} to write it there", argument)
    if path.exists() and not overwrite:
        raise OutputInUse.naming(f"{path} already exists; choose another file for {{out}}, or pass {{overwrite}} "
                                 "to replace it", argument)
    return path


def is_empty(path: str | os.PathLike) -> bool:
    """No folder yet, or one that holds nothing but a marker (a start killed right after ``mark``)."""
    path = Path(path)
    return not path.exists() or (path.is_dir() and all(p.name == MARKER for p in path.iterdir()))


def holder(path: Path) -> Holder | None:
    """Which command's output ``path`` holds: from its marker, else from a file only that command writes."""
    marker = path / MARKER
    if marker.is_file():
        content = _read_json(marker) or {}
        return Holder(content.get("command", "?"), content.get("settings"), MARKER)
    for name, command, kept in SIGNATURES:
        if (path / name).is_file():
            settings = (_read_json(path / kept[0]) or {}).get(kept[1]) if kept else None
            return Holder(command, settings if isinstance(settings, dict) else None, name)
    return None


def _or_overwrite(overwrite: bool | None, what: str) -> str:
    return "" if overwrite is None else f", or pass {{overwrite}} to {what}"


def digest(settings: dict) -> str:
    return hashlib.sha256(json.dumps(_plain(settings), sort_keys=True).encode()).hexdigest()[:16]


def _plain(settings: dict) -> dict:
    """As JSON gives it back (tuples as lists, paths as text): what is stored compares equal to what is given."""
    return json.loads(json.dumps(settings, default=str))


def _read_json(path: Path) -> dict | None:
    try:
        content = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return content if isinstance(content, dict) else None


def _shown(value) -> str:
    return "(default)" if value is None else repr(value)
