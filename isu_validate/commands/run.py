"""``isu-validate run`` (search) and ``isu-validate export`` (the tests table).

Options that decide what a run measures default to None here, so that ``--resume`` can
tell the options a user typed from the ones left out: left out, the stored run's value
is used; typed, it must equal the stored one (the run loop lists every difference).
The defaults themselves live in ``RunConfig`` and ``PipelineConfig``.
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import fields
from pathlib import Path

from ..archive.run_file import RUN_FILE, ResumeMismatch, RunError, read_run_file
from ..config import DEFAULT_MIN_VISIBLE, PipelineConfig, RunConfig
from ..devices import add_device_argument, add_render_device_argument
from ..search.algorithm_names import ALGORITHMS, algorithm_option
from ..sut.prompt import PROMPT_STYLES
from .sut import parse_options

_PIPELINE, _RUN = PipelineConfig(run_dir=""), RunConfig(pipeline=PipelineConfig(run_dir=""))
DEFAULT_BUDGET = _RUN.budget_tests
# option (argparse dest) -> (RunConfig or PipelineConfig, field)
SETTINGS = {
    "sut": ("pipeline", "sut"), "mode": ("pipeline", "mode"), "space": ("pipeline", "space"),
    "threshold": ("pipeline", "threshold"), "prompt": ("pipeline", "prompt"), "repeats": ("pipeline", "repeats"),
    "prompt_style": ("pipeline", "prompt_style"), "caption_template": ("pipeline", "caption_template"),
    "preset": ("pipeline", "preset"), "camera": ("pipeline", "camera"), "cabin": ("pipeline", "cabin"),
    "channels": ("pipeline", "channels"), "sut_timeout": ("pipeline", "sut_timeout_s"),
    "extrinsics_from": ("pipeline", "extrinsics_from"), "min_visible": ("pipeline", "min_visible"),
    "sut_option": ("pipeline", "sut_options"), "pipeline_factory": ("pipeline", "factory"),
    "algorithm": ("run", "algorithm"), "pop_size": ("run", "pop_size"), "seed": ("run", "seed"),
    "budget": ("run", "budget_tests"), "budget_time": ("run", "budget_s"), "workers": ("run", "workers"),
    "cluster": ("run", "cluster"), "stop_after_sut_errors": ("run", "stop_after_sut_errors"),
    "learn_from": ("run", "learn_from"),
}
EPILOG = """API keys come from the environment only, never from a flag or a file, and are never
written to run.json, the archive, logs or reports:
  openai:MODEL@URL   the key is read from $OPENAI_API_KEY, or from the variable named by
                     --sut-option api_key_env=NAME (a local server without a key needs none)
  http:URL           sent as "Authorization: Bearer ..." when --sut-option api_key_env=NAME names one
  command:PROGRAM    the program inherits this environment and reads what it needs itself

--resume continues the run in --out with its stored settings: leave the options out, or
give the same values; a different value is refused and listed (a resumed run never
silently measures something else). Only the budget may grow (--budget, --budget-time);
--workers, --cluster and --stop-after-sut-errors may change (they do not change what is measured).

exit status: 0 done; 1 stopped after --stop-after-sut-errors SUT errors in a row (the last
error is printed; fix the SUT, then --resume); 2 a setting is wrong (nothing was written);
130 interrupted (resume with --resume)."""


def register(sub) -> None:
    run = sub.add_parser("run", help="search the scene space for scenes the SUT gets wrong", epilog=EPILOG,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    add_run_options(run)
    run.set_defaults(func=cmd_run)

    export = sub.add_parser("export", help="write a run's tests table")
    export.add_argument("run_dir", type=Path, metavar="RUN")
    export.add_argument("--format", choices=["csv"], default="csv")
    export.add_argument("--out", type=Path, help="file to write (default: stdout)")
    export.set_defaults(func=cmd_export)


def add_run_options(p) -> None:
    d, r = _PIPELINE, _RUN
    p.add_argument("--out", type=Path, default=Path("runs/latest"), help="run directory (default runs/latest)")
    p.add_argument("--resume", action="store_true", help="continue the run in --out after a crash, a kill or a stop")
    p.add_argument("--sut", help=f"reference | openai:MODEL@BASE_URL | command:PROG ARGS | http:URL (default {d.sut}; "
                                 "API keys: see below)")
    p.add_argument("--mode", choices=["vqa", "vc"], help=f"visual question answering or captioning (default {d.mode})")
    p.add_argument("--space", help=f"scene space: shipped name or TOML path (default {d.space})")
    p.add_argument("--algorithm", type=algorithm_option, metavar="|".join(ALGORITHMS),
                   help=f"search algorithm (default {r.algorithm}): surrogate (surrogate-assisted, learns "
                        "where the SUT errs), nsga2 (the paper's NSGA-II, for replication), "
                        "rs (random search, the baseline)")
    p.add_argument("--pop-size", type=int, help=f"population size (default {r.pop_size})")
    p.add_argument("--learn-from", nargs="+", metavar="RUN",
                   help="earlier runs of the same SUT, mode and space the surrogate learns from before its first "
                        "generation (their tests are not run again and do not count in the budget)")
    p.add_argument("--budget", type=int,
                   help=f"number of tests (default {DEFAULT_BUDGET}; with --resume: extend the budget)")
    p.add_argument("--budget-time", type=float, help="wall-clock budget in seconds (instead of, or with, --budget)")
    p.add_argument("--seed", type=int, help=f"random seed of the search (default {r.seed})")
    p.add_argument("--threshold", type=float,
                   help="oracle threshold in 0..1 (default: 1.0 for vqa, i.e. any mistake fails; F_emb 0.65 for vc)")
    p.add_argument("--prompt", help="override the prompt sent to the SUT")
    p.add_argument("--prompt-style", choices=sorted(PROMPT_STYLES),
                   help=f"wording of the VQA prompt: paper (the paper's Figure 2) or compact (isu-validate's "
                        f"earlier, shorter wording) (default {d.prompt_style})")
    p.add_argument("--caption-template", metavar="NAME|FILE",
                   help="reference-caption template for --mode vc: a name in data/captions (isu-paper: the paper's "
                        "captioning figure, the default for isu-paper; isu-paper-compact: the earlier wording) "
                        "or a .toml file (default: the one named after the space)")
    p.add_argument("--repeats", type=int, help=f"ask each scene K times, majority vote (default {d.repeats})")
    p.add_argument("--preset", help=f"render preset: draft | standard | final (default {d.preset})")
    p.add_argument("--camera", help=f"camera rig: shipped name or TOML path (default {d.camera}); with an imaging "
                                    "model from `isu-validate exposure`, renders are developed the way that "
                                    "camera would")
    p.add_argument("--extrinsics-from", metavar="RIG",
                   help="take the camera's pose in the cabin from this registered rig (for a calibrated camera "
                        "file whose pose was never registered); recorded in run.json")
    p.add_argument("--min-visible", action="append", metavar="SHARE|FEATURE=SHARE",
                   help="a feature whose parts are seen less than this share is occluded: not judged, counted "
                        f"apart (default: the space's min_visible, else {DEFAULT_MIN_VISIBLE}); repeatable")
    p.add_argument("--cabin", help=f"cabin rig: shipped name or TOML path (default {d.cabin})")
    p.add_argument("--channels", help="extra render channels, e.g. seg,depth (default none)")
    p.add_argument("--sut-timeout", type=float, help=f"seconds per SUT request (default {d.sut_timeout_s:g})")
    p.add_argument("--sut-option", action="append", metavar="NAME=VALUE",
                   help="adapter option, repeatable (see `isu-validate sut check --help`)")
    p.add_argument("--stop-after-sut-errors", type=int, metavar="N",
                   help=f"stop the run after N SUT errors in a row with no answer in between (default "
                        f"{r.stop_after_sut_errors}; 0 never stops)")
    p.add_argument("--workers", type=int, help="parallel evaluation processes (default 1)")
    p.add_argument("--cluster", help="Dask scheduler address (instead of local workers)")
    add_render_device_argument(p)
    add_device_argument(p)
    p.add_argument("--no-report", action="store_true", help="do not write report.html at the end")
    # where the renderer, SUT and judge come from (module:function); an extension point
    p.add_argument("--pipeline-factory", help=argparse.SUPPRESS)


def given_settings(args) -> dict[str, dict]:
    """The options the user typed, as config values: {"run": {field: value}, "pipeline": {...}}."""
    from ..render.visibility import parse_min_visible

    out: dict[str, dict] = {"run": {}, "pipeline": {}}
    for dest, (part, field) in SETTINGS.items():
        value = getattr(args, dest, None)
        if value is None:
            continue
        if dest == "channels":
            value = tuple(c.strip() for c in value.split(",") if c.strip())
        elif dest == "sut_option":
            value = parse_options(value)
        elif dest == "min_visible":
            value = parse_min_visible(value)
        elif dest == "learn_from":
            value = tuple(str(Path(p).resolve()) for p in value)
        out[part][field] = value
    return out


def config_from_args(args) -> RunConfig:
    from ..execution import render_threads

    given = given_settings(args)
    run, pipeline = given["run"], given["pipeline"]
    if "budget_s" in run and "budget_tests" not in run:
        run["budget_tests"] = None  # a time budget alone: no test budget
    # how the work is spread and when to stop: this invocation's choice, not the stored run's
    volatile = {k: run.pop(k, getattr(_RUN, k)) for k in ("workers", "cluster", "stop_after_sut_errors")}
    if args.resume and (args.out / RUN_FILE).exists():
        stored = read_run_file(args.out).get("config", {})
        stored_pipeline = _known(PipelineConfig, stored.get("pipeline", {}))
        stored_pipeline["channels"] = tuple(stored_pipeline.get("channels", ()))
        pipeline = {**stored_pipeline, **pipeline}
        run = {**_known(RunConfig, stored), **run}
    run.pop("pipeline", None)
    config = PipelineConfig(**{**pipeline, "run_dir": str(args.out),
                               "render_threads": render_threads(volatile["workers"]),
                               "render_device": args.render_device, "device": args.device})
    return RunConfig(pipeline=config, **{**run, **volatile})


def _mismatch_message(exc: ResumeMismatch) -> str:
    """The differences in the words the user typed (--seed, not seed)."""
    flags = {(f"pipeline.{field}" if part == "pipeline" else field): "--" + dest.replace("_", "-")
             for dest, (part, field) in SETTINGS.items()}
    flags["learned_from"] = "the tests of the --learn-from runs"   # those runs changed since
    listed = "\n".join(f"  {_flag(d.setting, flags)}: {_shown(d.stored)} in the stored run, "
                       f"{_shown(d.now)} now" for d in exc.differences)
    return (f"{exc.run_dir} holds a run started with other settings:\n{listed}\n"
            "leave these options out to resume it as it was started (or give the stored values), "
            "or start a new run with another --out")


def _flag(setting: str, flags: dict) -> str:
    """--seed for "seed"; an entry of a dict-valued option by its key ("--min-visible luggage")."""
    if setting in flags:
        return flags[setting]
    head, _, key = setting.rpartition(".")
    return f"{flags[head]} {key}" if head in flags else setting


def _shown(value) -> str:
    if isinstance(value, list):
        return ",".join(map(str, value)) or "(none)"
    return "(default)" if value is None else repr(value) if isinstance(value, str) else str(value)


def _known(cls, values: dict) -> dict:
    """Only the fields this version knows (a run.json may come from an older or newer one)."""
    names = {f.name for f in fields(cls)}
    return {k: v for k, v in values.items() if k in names}


def cmd_run(args) -> int:
    from ..search import SUTErrorsStop, run_search

    config = config_from_args(args)
    try:
        summary = run_search(config, resume=args.resume)
    except SUTErrorsStop as exc:
        print(f"isu-validate run: stopped: {exc}", file=sys.stderr)
        return 1
    except ResumeMismatch as exc:
        print(f"isu-validate run: error: {_mismatch_message(exc)}", file=sys.stderr)
        return 2
    except RunError as exc:
        print(f"isu-validate run: error: {exc.on_command_line()}", file=sys.stderr)
        return 2
    except ConnectionError as exc:
        print(f"isu-validate run: error: {exc}", file=sys.stderr)
        return 2
    print(f"{summary.tests} tests ({summary.evaluated_now} evaluated now), {summary.failures} failing, "
          f"{summary.errors} with SUT/render errors; {summary.stopped_because}")
    if summary.last_sut_error:
        print(f"last SUT error: {summary.last_sut_error}")
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
