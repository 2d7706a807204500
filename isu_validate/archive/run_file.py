"""``run.json``: what a run directory measures, written once before its first test.

A run directory is started or resumed here and nowhere else.  Starting refuses a
directory that already holds a run; resuming refuses any setting that changes what
is measured (the differences are listed, so the user sees that a different ``--sut``
or ``--seed`` was not silently ignored), a scene space that changed since the start,
and a budget smaller than the stored one (a budget may only grow).
"""
from __future__ import annotations

import os
from pathlib import Path

from ..atomic import write_json
from ..errors import UserError, in_python_words
from .output_dir import Difference, Output, claim_output, differences_between  # noqa: F401 (resume checks name them here)
from .run_dir import ARCHIVE_FILE, RUN_FILE, RunDir, RunDirError  # noqa: F401 (the run's writers name them here)

# budgets that may only grow on --resume: RunConfig field -> what the user calls it
GROWING_BUDGETS = {"budget_tests": "test budget", "budget_s": "time budget"}


class RunError(UserError, RuntimeError):
    """A run directory that cannot be started or resumed as asked; the message names the fix."""


class ResumeMismatch(RunError):
    """Resuming with settings that change what the run measures."""

    def __init__(self, run_dir: Path, differences: list[Difference]):
        self.run_dir, self.differences = run_dir, differences
        listed = "; ".join(str(d) for d in differences)
        self.template = (f"{run_dir} holds a run with a different configuration ({listed}); resume it with the "
                         "stored settings or start a new run in another folder for {out}")
        super().__init__(in_python_words(self.template, argument="run_dir"))


def read_run_file(run_dir: str | os.PathLike) -> dict:
    """run.json of a run to resume (or learn from); RunError when it cannot be read."""
    try:
        return RunDir(Path(run_dir)).info()
    except RunDirError as exc:
        raise RunError(f"{exc}; the run cannot be resumed: start a new one") from None


def write_run_file(run_dir: str | os.PathLike, content: dict) -> Path:
    """Atomically: a killed start leaves either no run.json or a whole one. The folder's marker first."""
    Output(Path(run_dir), "run", content.get("identity", {})).mark()
    return write_json(Path(run_dir) / RUN_FILE, content, indent=2, default=str)


def check_run_dir(run_dir: str | os.PathLike, identity: dict, space_hash: str, budgets: dict,
                  resume: bool) -> bool:
    """Whether ``run_dir`` starts a new run (True) or resumes the stored one (False); raises
    RunError when neither is possible as asked.  Writes nothing."""
    run_dir = Path(run_dir)
    claim_output(run_dir, "run", identity, resume=True, overwrite=None, argument="run_dir")  # another command's?
    if not (run_dir / RUN_FILE).exists():
        if resume and run_dir.exists() and any(run_dir.iterdir()):
            raise RunError(f"nothing to resume: {run_dir / RUN_FILE} is missing")
        return True
    if not resume:
        raise RunError.naming(f"{run_dir} already holds a run; pass {{resume}} to continue it or choose another "
                              "folder for {out}", argument="run_dir")
    stored = read_run_file(run_dir)
    differences = differences_between(stored.get("identity", {}), identity)
    if differences:
        raise ResumeMismatch(run_dir, differences)
    if stored.get("space_hash") != space_hash:
        raise RunError(f"the scene space changed since {run_dir} was started (hash {stored.get('space_hash')} -> "
                          f"{space_hash}); start a new run")
    _check_budgets(run_dir, stored.get("config", {}), budgets)
    return False


def _check_budgets(run_dir: Path, stored: dict, budgets: dict) -> None:
    for field, name in GROWING_BUDGETS.items():
        before, now = stored.get(field), budgets.get(field)
        if before is not None and now is not None and now < before:
            raise RunError(f"{run_dir} was started with a {name} of {before:g}; a resumed run's budget may "
                              f"only grow, not shrink to {now:g}")
