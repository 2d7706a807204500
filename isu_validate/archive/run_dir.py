"""A run directory: where its files lie and how they are read, for every reader of a run.

The layout is a contract (docs/ARCHITECTURE.md, "Run directory")::

    RUN/run.json                what the run measures, written once before the first test (run_file.py)
    RUN/archive.sqlite          one row per evaluated test (store.py)
    RUN/images/<test_id>.png    the rendered frame (and its channels and .label.json beside it)
    RUN/labels/<test_id>.json   the scene as the judge saw it

Analysis, export, recreation, ``run --learn-from`` and the benchmark's emulated SUT read runs through
``RunDir``; ``find_runs`` picks the run directories out of what a user named.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ..errors import UserError
from .store import TestRecord, read_records

RUN_FILE = "run.json"
ARCHIVE_FILE = "archive.sqlite"
IMAGES_DIR = "images"
LABELS_DIR = "labels"


class RunDirError(UserError, FileNotFoundError):
    """A folder that is not a run directory; the message says what to pass instead."""


@dataclass(frozen=True)
class RunDir:
    path: Path

    @property
    def run_file(self) -> Path:
        return self.path / RUN_FILE

    @property
    def archive_file(self) -> Path:
        return self.path / ARCHIVE_FILE

    def is_run(self) -> bool:
        """Whether a run was started here (its run.json is written before anything else)."""
        return self.run_file.is_file()

    def has_archive(self) -> bool:
        return self.archive_file.is_file()

    def info(self) -> dict:
        """The contents of run.json; RunDirError when it is missing or not valid JSON."""
        try:
            return json.loads(self.run_file.read_text())
        except FileNotFoundError:
            raise _not_a_run(self.path) from None
        except ValueError as exc:
            raise RunDirError(f"{self.run_file} is not valid JSON ({exc})") from None

    def records(self) -> list[TestRecord]:
        """Every evaluated test in run order; none for a run that stopped before its first test."""
        return read_records(self.archive_file) if self.has_archive() else []

    def image_file(self, test_id: str) -> Path:
        return self.path / IMAGES_DIR / f"{test_id}.png"

    def label_file(self, test_id: str) -> Path:
        return self.path / LABELS_DIR / f"{test_id}.json"

    def render_label(self, test_id: str) -> dict | None:
        """The renderer's label of the test's frame (``images/<test_id>.label.json``); None when absent or
        unreadable (test doubles write none)."""
        try:
            label = json.loads((self.path / IMAGES_DIR / f"{test_id}.label.json").read_text())
        except (OSError, ValueError):
            return None
        return label if isinstance(label, dict) else None

    def image_path(self, record: TestRecord) -> Path | None:
        """The test's rendered frame where it exists (records hold it relative to the run directory)."""
        if not record.image:
            return None
        path = Path(record.image)
        path = path if path.is_absolute() else self.path / path
        return path if path.is_file() else None


def open_run(path: str | os.PathLike) -> RunDir:
    """The run directory at ``path``; RunDirError when no run was started there."""
    run = RunDir(Path(path))
    if not run.is_run():
        raise _not_a_run(run.path)
    return run


def find_runs(paths: list[str | os.PathLike]) -> list[Path]:
    """Run directories among ``paths``; a folder of runs stands for every run directly inside it."""
    found: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if RunDir(path).is_run():
            found.append(path)
        elif path.is_dir() and (inner := sorted(p.parent for p in path.glob(f"*/{RUN_FILE}"))):
            found.extend(inner)
        else:
            raise RunDirError(f"{path} is neither a run directory nor a folder of runs (no {RUN_FILE} in it "
                              "or its subfolders); give the folders `isu-validate run --out` wrote")
    return list(dict.fromkeys(p.resolve() for p in found))


def _not_a_run(path: Path) -> RunDirError:
    return RunDirError(f"{path} is not a run directory (no {RUN_FILE}); "
                       "give a folder that `isu-validate run --out` wrote")
