"""Earlier runs of the same SUT a new search learns from first (``run --learn-from RUN...``).

A test team tests one SUT again and again (each build, each prompt); what earlier runs found
says where to look.  Their tests are read here, checked to come from the same SUT, mode and
scene space, and handed to the search before its first generation: they are learnt from, never
proposed again, and do not count in the budget (every failure the new run reports is a test it
ran itself).  Their digest is part of the run's identity, so a resumed run learns from exactly
the same tests or is refused.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from ..archive import RunDir, TestRecord
from ..archive.run_file import ARCHIVE_FILE, RunError, read_run_file

CHECKED = ("sut", "mode", "space")   # pipeline settings an earlier run must share with this one


@dataclass
class PriorTests:
    records: list[TestRecord]   # tests with a verdict, run by run
    digest: str                 # of every test's scene and fitness: what the search learnt from


def read_prior_tests(run_dirs, pipeline, space, this_run) -> PriorTests:
    """The tests of ``run_dirs`` (finished or not), refused with the fix named where a folder is not
    a run of the same SUT, mode and space as ``pipeline``, or is the run ``this_run`` itself."""
    records = []
    for folder in map(Path, run_dirs):
        if folder.resolve() == Path(this_run).resolve():
            raise RunError(f"--learn-from {folder}: that is this run's own folder; name earlier runs")
        if not RunDir(folder).has_archive():
            raise RunError(f"--learn-from {folder}: not a run directory (no {ARCHIVE_FILE}); name the --out "
                           "folders of earlier runs of the same SUT")
        _check_same_setup(folder, read_run_file(folder), pipeline, space)
        records += [r for r in RunDir(folder).records() if not r.errored and r.primary is not None]
    if not records:
        raise RunError(f"--learn-from {', '.join(map(str, run_dirs))}: no test with a verdict to learn from")
    digest = hashlib.sha256(json.dumps([(r.scene_key, r.primary) for r in records]).encode()).hexdigest()[:16]
    return PriorTests(records, digest)


def _check_same_setup(folder: Path, stored: dict, pipeline, space) -> None:
    before = stored.get("config", {}).get("pipeline", {})
    for setting in CHECKED:
        if before.get(setting) != getattr(pipeline, setting):
            raise RunError(f"--learn-from {folder}: that run's {setting} is {before.get(setting)!r}, this run's "
                           f"{getattr(pipeline, setting)!r}; learn only from runs of the same SUT, mode and space")
    if stored.get("space_hash") != space.hash:
        raise RunError(f"--learn-from {folder}: its scene space {space.name!r} has changed since (hash "
                       f"{stored.get('space_hash')} -> {space.hash}); its scenes may no longer be valid ones")
