"""A run directory read for analysis: its configuration, scene space and tests in time order."""
from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime
from functools import cached_property
from pathlib import Path

from ..archive import RunDir, RunDirError, TestRecord, open_run
from ..space import SceneSpace, SpaceError, load_space, space_from_dict
from .thresholds import DEFAULT_THRESHOLD, METRIC_KEYS, thresholds_for


@dataclass
class Run:
    path: Path
    info: dict                  # run.json
    space: SceneSpace
    records: list[TestRecord]   # in the order they were evaluated
    name: str = ""              # unique among the runs of one report (the folder name unless ambiguous)

    def __post_init__(self):
        self.name = self.name or self.path.name

    # ---- identity
    @property
    def config(self) -> dict:
        return self.info.get("config", {})

    @property
    def pipeline(self) -> dict:
        return self.config.get("pipeline", {})

    @property
    def sut(self) -> str:
        return str(self.pipeline.get("sut", "?"))

    @property
    def mode(self) -> str:
        return str(self.pipeline.get("mode", "vqa"))

    @property
    def algorithm(self) -> str:
        return str(self.config.get("algorithm", "?"))

    @property
    def seed(self) -> int | str:
        return self.config.get("seed", "?")

    @property
    def group(self) -> tuple[str, str]:
        """Runs are compared within one SUT and mode."""
        return self.sut, self.mode

    @property
    def label(self) -> str:
        return f"{self.algorithm} seed {self.seed} ({self.name})"

    # ---- tests
    @property
    def thresholds(self) -> tuple[float, ...]:
        return thresholds_for(self.mode)

    @property
    def oracle_threshold(self) -> float | None:
        """The threshold the run's oracle judged at (its setting, else the mode's default)."""
        value = self.pipeline.get("threshold")
        return float(value) if isinstance(value, (int, float)) else DEFAULT_THRESHOLD.get(self.mode)

    @property
    def metric_key(self) -> str:
        return METRIC_KEYS.get(self.mode, "primary")

    def metric(self, record: TestRecord) -> float | None:
        """The fitness the failure thresholds apply to; None for a test without a verdict."""
        if record.errored:
            return None
        value = record.fitness.get(self.metric_key, record.primary)
        return None if value is None or not math.isfinite(float(value)) else float(value)

    @cached_property
    def valid(self) -> list[TestRecord]:
        """Tests with a verdict (no SUT or render error)."""
        return [r for r in self.records if not r.errored]

    @cached_property
    def failures(self) -> list[TestRecord]:
        """Tests the run's oracle judged failing (errors are never failures)."""
        return [r for r in self.valid if r.failed]

    @property
    def sut_errors(self) -> list[TestRecord]:
        return [r for r in self.records if r.sut_error]

    @property
    def render_errors(self) -> list[TestRecord]:
        return [r for r in self.records if r.render_error and not r.sut_error]

    @cached_property
    def started(self) -> float | None:
        """Unix time the run started (run.json), else when its first test was committed."""
        stamp = self.info.get("started")
        if stamp:
            try:
                return datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%S%z").timestamp()
            except ValueError:
                pass
        return min((r.created for r in self.records), default=None)

    def elapsed(self, record: TestRecord) -> float:
        """Seconds from the start of the run until this test was committed."""
        return max(0.0, record.created - (self.started or record.created))

    def truth(self, record: TestRecord) -> dict[str, str]:
        """The correct answer for each question the test asked."""
        return {q.key: q.truth for q in self.space.questions(record.canonical)}

    @property
    def directory(self) -> RunDir:
        """The run's files (labels, images)."""
        return RunDir(self.path)

    def image_path(self, record: TestRecord) -> Path | None:
        return self.directory.image_path(record)


def load_run(path: str | Path) -> Run:
    run_dir = open_run(path)
    info = run_dir.info()
    records = run_dir.records()   # none for a run that stopped before its first test
    records.sort(key=lambda r: (r.created, r.generation, r.index))
    return Run(path=run_dir.path, info=info, space=_space_of(info, run_dir), records=records)


def _space_of(info: dict, run_dir: RunDir) -> SceneSpace:
    """The space as the run recorded it; the named space only if that record is unusable."""
    if isinstance(info.get("space"), dict):
        try:
            return space_from_dict(info["space"], where=f"{run_dir.run_file} [space]")
        except SpaceError:
            pass
    name = info.get("config", {}).get("pipeline", {}).get("space", "isu-paper")
    try:
        return load_space(name)
    except SpaceError as exc:
        raise RunDirError(f"{run_dir.path}: cannot rebuild the run's scene space: {exc}") from None


def name_uniquely(runs: list[Run]) -> list[Run]:
    """Folder names, lengthened with parent folders where two runs share one (exp1/rs-1, exp2/rs-1)."""
    depth = 1
    while depth < 8:
        names = ["/".join(r.path.resolve().parts[-depth:]) for r in runs]
        if len(set(names)) == len(names):
            break
        depth += 1
    for run, name in zip(runs, names):
        run.name = name
    return runs
