"""``isu-validate run`` (search) and ``isu-validate export`` (the tests table)."""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..pipeline import PipelineConfig
from .sut import parse_options
from ..search import ALGORITHMS, RunConfig, RunError, run_search

DEFAULT_BUDGET = 40


def register(sub) -> None:
    run = sub.add_parser("run", help="search the scene space for scenes the SUT gets wrong")
    add_run_options(run)
    run.set_defaults(func=cmd_run)

    export = sub.add_parser("export", help="write a run's tests table")
    export.add_argument("run_dir", type=Path, metavar="RUN")
    export.add_argument("--format", choices=["csv"], default="csv")
    export.add_argument("--out", type=Path, help="file to write (default: stdout)")
    export.set_defaults(func=cmd_export)


def add_run_options(p) -> None:
    p.add_argument("--out", type=Path, default=Path("runs/latest"), help="run directory (default runs/latest)")
    p.add_argument("--resume", action="store_true", help="continue the run in --out after a crash or kill")
    p.add_argument("--sut", default="reference", help="reference | openai:MODEL@BASE_URL | command:PROG ARGS | http:URL")
    p.add_argument("--mode", choices=["vqa", "vc"], default="vqa", help="visual question answering or captioning")
    p.add_argument("--space", default="isu-paper", help="scene space: shipped name or TOML path")
    p.add_argument("--algorithm", choices=ALGORITHMS, default=ALGORITHMS[0],
                   help="surrogate (default: surrogate-assisted, learns where the SUT errs), nsga2 (the paper's "
                        "NSGA-II, for replication), rs (random search, the baseline)")
    p.add_argument("--pop-size", type=int, default=10)
    p.add_argument("--budget", type=int, help=f"number of tests (default {DEFAULT_BUDGET}; with --resume: extend the budget)")
    p.add_argument("--budget-time", type=float, help="wall-clock budget in seconds (instead of, or with, --budget)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--threshold", type=float, help="oracle threshold (default: 1.0 for vqa, F_emb 0.65 for vc)")
    p.add_argument("--prompt", help="override the prompt sent to the SUT")
    p.add_argument("--repeats", type=int, default=1, help="ask each scene K times, majority vote")
    p.add_argument("--preset", default="draft", help="render preset: draft | standard | final")
    p.add_argument("--camera", default="default", help="camera rig: shipped name or TOML path")
    p.add_argument("--cabin", default="default", help="cabin rig: shipped name or TOML path")
    p.add_argument("--channels", default="", help="extra render channels, e.g. seg,depth")
    p.add_argument("--sut-timeout", type=float, default=60.0, help="seconds per SUT request")
    p.add_argument("--sut-option", action="append", default=[], metavar="NAME=VALUE",
                   help="adapter option, repeatable (see `isu-validate sut check --help`)")
    p.add_argument("--workers", type=int, default=1, help="parallel evaluation processes")
    p.add_argument("--cluster", help="Dask scheduler address (instead of local workers)")
    p.add_argument("--no-report", action="store_true", help="do not write report.html at the end")
    # where the renderer, SUT and judge come from (module:function); an extension point
    p.add_argument("--pipeline-factory", default=PipelineConfig.factory, help=argparse.SUPPRESS)


def config_from_args(args) -> RunConfig:
    if args.resume and (args.out / "run.json").exists():
        stored = json.loads((args.out / "run.json").read_text())["config"]
        stored_pipeline = stored.pop("pipeline")
        pipeline = PipelineConfig(**{**stored_pipeline, "run_dir": str(args.out),
                                     "channels": tuple(stored_pipeline["channels"]),
                                     "render_threads": render_threads(args.workers)})
        stored.update(workers=args.workers, cluster=args.cluster)
        if args.budget is not None:
            stored["budget_tests"] = args.budget
        if args.budget_time is not None:
            stored["budget_s"] = args.budget_time
        return RunConfig(pipeline=pipeline, **stored)
    budget_tests = args.budget if args.budget is not None else (None if args.budget_time else DEFAULT_BUDGET)
    if budget_tests is not None and budget_tests < 1:
        raise ValueError(f"--budget must be at least 1 test, got {budget_tests}")
    pipeline = PipelineConfig(
        run_dir=str(args.out), space=args.space, sut=args.sut, mode=args.mode, threshold=args.threshold,
        prompt=args.prompt, repeats=args.repeats, preset=args.preset, camera=args.camera, cabin=args.cabin,
        channels=tuple(c for c in args.channels.split(",") if c), sut_timeout_s=args.sut_timeout,
        sut_options=parse_options(args.sut_option), render_threads=render_threads(args.workers),
        factory=args.pipeline_factory)
    return RunConfig(pipeline=pipeline, algorithm=args.algorithm, pop_size=args.pop_size, seed=args.seed,
                     budget_tests=budget_tests, budget_s=args.budget_time, workers=args.workers,
                     cluster=args.cluster)


def render_threads(workers: int) -> int:
    """Split the cores between parallel renderers (0 = Blender takes all, for one worker)."""
    return 0 if workers <= 1 else max(1, (os.cpu_count() or 1) // workers)


def cmd_run(args) -> int:
    config = config_from_args(args)
    try:
        summary = run_search(config, resume=args.resume)
    except RunError as exc:
        print(f"isu-validate run: error: {exc}", file=sys.stderr)
        return 2
    print(f"{summary.tests} tests ({summary.evaluated_now} evaluated now), {summary.failures} failing, "
          f"{summary.errors} with SUT/render errors; {summary.stopped_because}")
    if not args.no_report:
        print(f"report: {write_report(summary.run_dir)}")
    print(f"run directory: {summary.run_dir}")
    return 0


def write_report(run_dir: Path) -> Path:
    from ..analysis import write_run_report

    return write_run_report(run_dir)


def cmd_export(args) -> int:
    from ..archive.export import write_csv

    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        with open(args.out, "w", newline="") as fh:
            n = write_csv(args.run_dir, fh)
        print(f"{n} tests written to {args.out}", file=sys.stderr)
    else:
        write_csv(args.run_dir, sys.stdout)
    return 0
