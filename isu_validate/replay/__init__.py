"""``replay``: ask a new SUT (or a new version of the same one) about a run's stored images and judge the
answers exactly as the run judged them; which failures were fixed, which are new, and is the change real?

    result = replay_run("runs/rs-s1", "replay/", ReplaySettings(sut="reference",
                        sut_options={"model_dir": "runs/reference-training/model"}))
    result.fixed, result.new, result.p, result.rates[0.8]

Rooms: ``stored`` (the run: tests with a verdict, its settings), ``coverage`` (does the SUT's model know
the run's space?), ``frames`` (the stored image, or a faithful re-render of a missing one), ``ask`` (the
run's request and judge), ``compare`` (paired outcomes, rates, per feature, McNemar), ``report`` (HTML).
Outputs (a contract, docs/ARCHITECTURE.md "Replay folder"): ``summary.json``, ``replay.csv``,
``report.html``; replies cached in ``cache/sut``, so an interrupted replay run again pays no SUT call twice.
"""
from __future__ import annotations

import csv
import json
import os
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..archive.output_dir import claim_output
from ..atomic import atomic_open, write_text
from ..config import DEFAULT_SUT_ERROR_LIMIT
from ..errors import InputError
from ..progress import Progress
from ..sut.version import sut_version
from .compare import CSV_COLUMNS, Replayed, rows, summarise
from .stored import StoredRun, read_run

__all__ = ["ReplayResult", "ReplaySettings", "replay_run"]


@dataclass
class ReplaySettings:
    """The SUT ``replay`` asks and how (``isu-validate replay`` flags); None takes the run's own setting.

        ReplaySettings(sut="reference", sut_options={"model_dir": "runs/reference-training/model"})
    """
    sut: str
    sut_options: dict = field(default_factory=dict)
    threshold: float | None = None      # the counts' threshold; None: the run's oracle threshold
    repeats: int | None = None          # None: the run's
    sut_timeout_s: float | None = None  # None: the run's
    stop_after_sut_errors: int = DEFAULT_SUT_ERROR_LIMIT   # SUT errors in a row, no answer between; 0 never
    device: str = "auto"                # an embedded SUT's torch work (devices.py)


@dataclass
class ReplayResult:
    summary: dict           # summary.json
    rows: list[dict]        # replay.csv
    out: Path

    @property
    def fixed(self) -> int:
        return self.summary["fixed"]

    @property
    def new(self) -> int:
        return self.summary["new"]

    @property
    def persisting(self) -> int:
        return self.summary["persisting"]

    @property
    def still_passing(self) -> int:
        return self.summary["still_passing"]

    @property
    def p(self) -> float:
        """McNemar's exact p of the paired outcomes at the summary's threshold."""
        return self.summary["mcnemar"]["p"]

    @property
    def rates(self) -> dict[float, tuple[float | None, float | None]]:
        """Threshold -> (failure rate in the run, now), over the tests replayed with a verdict."""
        return {r["threshold"]: (r["rate_before"], r["rate_after"]) for r in self.summary["rates"]}

    @property
    def exit_code(self) -> int:
        """0 when tests were replayed (some may be listed as not replayable); 1 when none was, or the
        replay stopped because the SUT kept failing."""
        return 0 if self.summary["n_replayed"] and not self.summary["stopped"] else 1


def replay_run(run: str | os.PathLike, out: str | os.PathLike, settings: ReplaySettings, log=None,
               overwrite: bool = False) -> ReplayResult:
    """Ask ``settings.sut`` about every test of ``run`` that had a verdict, judge as the run judged, and
    compare (``isu-validate replay``): writes ``out/summary.json``, ``replay.csv``, ``report.html``.
    ``out`` must be new, or this replay's own folder (same run, SUT, model and settings: it goes on where it
    stopped); another command's output or another replay is refused unless ``overwrite``.

        result = replay_run("runs/rs-s1", "replay/", ReplaySettings(sut="reference", threshold=0.8))
        print(result.fixed, result.new, result.persisting, result.still_passing, result.p)
    """
    log = log or (lambda text: print(f"replay: {text}", file=sys.stderr, flush=True))
    stored = read_run(run)
    threshold = _threshold(stored, settings.threshold)
    if settings.stop_after_sut_errors < 0:
        raise InputError(f"--stop-after-sut-errors must be 0 (never stop) or more, "
                         f"got {settings.stop_after_sut_errors}")
    out = Path(out)
    problems: list[str] = []

    def problem(text: str) -> None:
        problems.append(text)
        log(text)

    sut = _open_sut(stored, settings, out)
    try:
        from .coverage import check_covers
        check_covers(sut, settings.sut, stored.path, stored.space.name, stored.space_hash)
        claim_output(out, "replay", _identity(stored, settings, sut), overwrite=overwrite).mark()
        from .frames import find_frames
        frames = find_frames(stored, out, problem)
        items, stopped = _replay(stored, sut, frames, threshold, settings.stop_after_sut_errors, problem)
    finally:
        sut.close()
    summary = summarise(items, threshold, stored.space)
    summary.update(run_without_verdict=stored.without_verdict, stopped=stopped, problems=problems,
                   settings=_settings(stored, settings, sut))
    table = rows(items, threshold)
    _write(out, summary, table)
    from .report import write_report
    write_report(out / "report.html", summary, items, stored.space)
    return ReplayResult(summary, table, out)


def _identity(stored: StoredRun, settings: ReplaySettings, sut) -> dict:
    """What decides a replay folder's content (named as in summary.json's settings, so a folder from before
    the marker is compared too): the run, the SUT's fingerprint (its model: the spec's spelling or the path to
    the same model does not matter), the threshold and repeats."""
    return {"run": str(stored.path), "sut_fingerprint": sut.adapter.fingerprint, "threshold": settings.threshold,
            "repeats": sut.repeats}


def _threshold(stored: StoredRun, given: float | None) -> float:
    if given is None:
        return stored.threshold
    from ..evaluate.oracles import check_threshold
    return check_threshold(given, "--threshold")


def _open_sut(stored: StoredRun, settings: ReplaySettings, out: Path):
    from ..sut import open_sut
    pipeline = stored.pipeline
    repeats = pipeline.repeats if settings.repeats is None else settings.repeats
    timeout = pipeline.sut_timeout_s if settings.sut_timeout_s is None else settings.sut_timeout_s
    return open_sut(settings.sut, space=stored.space, repeats=repeats, cache_dir=out / "cache" / "sut",
                    timeout_s=timeout, device=settings.device, **settings.sut_options)


def _replay(stored: StoredRun, sut, frames: dict, threshold: float, limit: int,
            problem) -> tuple[list[Replayed], str | None]:
    """Every test with a verdict, asked in test-id order; stops after ``limit`` SUT errors in a row."""
    from .ask import Asker
    asker, items, streak, stopped = Asker(stored, sut), [], 0, None
    progress = Progress(len(stored.tests), label="tests")
    try:
        for record in stored.tests:
            frame, before = frames[record.test_id], asker.before(record)
            if frame.image is None or stopped:
                items.append(Replayed(record, before, image=str(frame.image or ""), skipped=stopped or frame.skipped))
                continue
            after, cached = asker.ask(record, frame.image)
            items.append(Replayed(record, before, after, str(frame.image), rerendered=frame.rerendered))
            if after.error:
                problem(f"{record.test_id}: SUT error (not counted as a failure): {after.error}")
            streak = streak + 1 if after.error else 0
            if limit and streak >= limit:
                stopped = (f"stopped after {streak} SUT errors in a row with no answer in between "
                           f"(--stop-after-sut-errors {limit}); last SUT error: {after.error}")
                problem(stopped)
            progress.update(failed=items[-1].status(threshold) in ("new", "persisting"),
                            errored=bool(after.error), resumed=cached)
    finally:
        progress.close()
    _check_rejudged(items, problem)
    return items, stopped


def _check_rejudged(items: list[Replayed], problem) -> None:
    """The run's answers judged again must give the run's F_qa; else the judge or space differs from the run's."""
    differ = [i for i in items if i.before.rejudged is None or abs(i.before.rejudged - i.before.f_qa) > 1e-9]
    if differ:
        first = differ[0]
        problem(f"{len(differ)} test(s) (e.g. {first.record.test_id}: F_qa {first.before.f_qa:.4g} in the run, "
                f"{first.before.rejudged} judging its stored answers again) do not reproduce the run's verdict: the "
                "run was judged by another judge; 'before' keeps the run's F_qa, the per-feature changes use "
                "today's judge")


def _settings(stored: StoredRun, settings: ReplaySettings, sut) -> dict:
    pipeline = stored.pipeline
    return {**asdict(settings), "repeats": sut.repeats, "threshold_run": stored.threshold,
            "run": str(stored.path), "run_sut": pipeline.sut, "run_sut_options": pipeline.sut_options,
            "sut_fingerprint": sut.adapter.fingerprint, "sut_version": sut_version(settings.sut, sut.adapter),
            "mode": "vqa", "space": stored.space.name,
            "space_hash": stored.space_hash, "prompt_style": pipeline.prompt_style,
            "sut_device": getattr(sut.adapter, "device", None)}   # None: the SUT runs elsewhere


def _write(out: Path, summary: dict, table: list[dict]) -> None:
    with atomic_open(out / "replay.csv", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(table)
    write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
