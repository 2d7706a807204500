"""The run as ``replay`` reads it: its tests with a verdict and how it asked and judged them.

Everything comes from the run directory (``archive.open_run`` through ``analysis.runs.load_run``): the
scene space as the run recorded it (its truth and weights, even if the space file changed since), the
prompt settings, the oracle threshold, and each record's own occluded features.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from ..analysis.runs import Run, load_run
from ..archive import TestRecord
from ..config import PipelineConfig
from ..errors import InputError


@dataclass
class StoredRun:
    run: Run
    pipeline: PipelineConfig     # the run's settings as stored (run_dir: the run itself)
    tests: list[TestRecord]      # the tests with a verdict, in test-id order
    without_verdict: int         # render or SUT errors in the run: nothing to compare with

    @property
    def path(self) -> Path:
        return self.run.path

    @property
    def space(self):
        return self.run.space

    @property
    def space_hash(self) -> str:
        return str(self.run.info.get("space_hash") or self.run.space.hash)

    @property
    def threshold(self) -> float:
        """The threshold the run's oracle judged at."""
        return float(self.run.oracle_threshold)

    def renderer_version(self, test_id: str) -> str | None:
        """The renderer that made the test's frame: its render label says, else run.json (the version the
        run started with); None when neither does."""
        label = self.run.directory.render_label(test_id) or {}
        return label.get("renderer") or (self.run.info.get("versions") or {}).get("renderer")


def read_run(path) -> StoredRun:
    """The run at ``path``; InputError for a run replay cannot judge as the run did."""
    run = load_run(path)
    if run.mode != "vqa":
        raise InputError(f"{run.path} is a captioning run (mode {run.mode}); replay compares VQA answers "
                         "feature by feature and replays VQA runs only")
    tests = sorted((r for r in run.records if run.metric(r) is not None), key=lambda r: r.test_id)
    return StoredRun(run, _pipeline(run), tests, len(run.records) - len(tests))


def _pipeline(run: Run) -> PipelineConfig:
    """The stored pipeline settings; a setting the run predates takes today's default."""
    known = {f.name for f in fields(PipelineConfig)}
    stored = {k: v for k, v in run.pipeline.items() if k in known}
    stored["channels"] = tuple(stored.get("channels") or ())
    stored["run_dir"] = str(run.path)
    return PipelineConfig(**stored)
