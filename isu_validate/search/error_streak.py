"""Stopping a run whose SUT keeps failing: a broken setup must not burn the budget.

A closed port, a wrong script or a server that answers garbage makes every test a SUT
error.  Such tests are recorded (they are no failures of the SUT's understanding), but
after ``limit`` SUT errors in a row with no answer in between the run stops with the last
error; everything evaluated stays in the archive and ``--resume`` continues after the fix.
Render errors neither count nor break the streak: they say nothing about the SUT.
"""
from __future__ import annotations

from ..archive import TestRecord
from ..archive.run_file import RunError
from ..config import DEFAULT_SUT_ERROR_LIMIT as DEFAULT_LIMIT


class SUTErrorStreak:
    def __init__(self, limit: int = DEFAULT_LIMIT):
        if limit < 0:
            raise ValueError(f"the SUT error limit must be 0 (never stop) or more, got {limit}")
        self.limit = limit
        self.length = 0
        self.last_error: str | None = None

    def add(self, record: TestRecord) -> None:
        """A test evaluated now (tests taken from the archive on resume do not count)."""
        if record.sut_error:
            self.length += 1
            self.last_error = record.sut_error
        elif not record.render_error:
            self.length = 0

    @property
    def tripped(self) -> bool:
        return bool(self.limit) and self.length >= self.limit


class SUTErrorsStop(RunError):
    """The run stopped because the SUT failed ``limit`` times in a row; carries the summary so far."""

    def __init__(self, streak: SUTErrorStreak, summary):
        self.summary, self.last_error = summary, streak.last_error
        run_dir = summary.run_dir
        super().__init__(
            f"the SUT failed {streak.length} times in a row with no answer in between, so the run stopped "
            f"(--stop-after-sut-errors {streak.limit}; 0 never stops).\n"
            f"last SUT error: {streak.last_error}\n"
            f"{summary.tests} tests are kept in {run_dir}. Fix the SUT (`isu-validate sut check --sut SPEC IMAGE` "
            f"shows what it answers), then continue: isu-validate run --out {run_dir} --resume")
