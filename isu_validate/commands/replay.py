"""``isu-validate replay``: ask a new SUT (or a new version of one) about a run's stored images, judged as the
run judged them, and compare the outcomes test by test.

    isu-validate replay RUN --sut SPEC [--sut-option K=V ...] [--threshold T] [--repeats R] --out DIR

Writes DIR/summary.json, DIR/replay.csv and DIR/report.html; replies are cached in DIR/cache/sut, so
running the same command again (after an interruption, or to add a report) pays no SUT call twice.
A missing image is rendered again only when this installation's renderer is the run's; otherwise those
tests are named and left out, and the rest are replayed. Exit status: 0 replayed; 1 nothing could be
replayed, or the SUT failed --stop-after-sut-errors times in a row; 2 bad input (not a run, a SUT whose
model was trained for another scene space, a bad option).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..analysis.html import threshold_label
from ..config import DEFAULT_SUT_ERROR_LIMIT
from . import add_overwrite_option
from ..devices import add_device_argument
from .sut import parse_options


def register(sub) -> None:
    p = sub.add_parser("replay", help="ask a new SUT about a run's stored images; fixed and new failures",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run", type=Path, metavar="RUN", help="run directory (`isu-validate run --out`)")
    p.add_argument("--sut", required=True,
                   help="SUT spec: reference, openai:MODEL@URL, command:PROGRAM ARGS..., http:URL")
    p.add_argument("--sut-option", action="append", default=[], metavar="NAME=VALUE",
                   help="adapter option, repeatable (e.g. model_dir=runs/reference-training/model)")
    p.add_argument("--threshold", type=float,
                   help="count fixed/new failures at this F_qa threshold (default: the run's oracle threshold)")
    p.add_argument("--repeats", type=int, help="SUT queries per image, per-feature majority (default: the run's)")
    p.add_argument("--sut-timeout", type=float, help="seconds per SUT request (default: the run's)")
    add_device_argument(p)
    p.add_argument("--stop-after-sut-errors", type=int, default=DEFAULT_SUT_ERROR_LIMIT, metavar="N",
                   help=f"stop after N SUT errors in a row with no answer in between (default "
                        f"{DEFAULT_SUT_ERROR_LIMIT}; 0 never stops)")
    p.add_argument("--out", type=Path, required=True,
                   help="replay folder: new, or this same replay's (it goes on where it stopped)")
    add_overwrite_option(p, "a folder that holds another replay or another command's output")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..replay import ReplaySettings, replay_run

    args.interrupted = (f"interrupted; the replies so far are cached in {args.out / 'cache' / 'sut'}: run the same "
                        "command again to continue")
    settings = ReplaySettings(sut=args.sut, sut_options=parse_options(args.sut_option), threshold=args.threshold,
                              repeats=args.repeats, sut_timeout_s=args.sut_timeout,
                              stop_after_sut_errors=args.stop_after_sut_errors, device=args.device)
    result = replay_run(args.run, args.out, settings, overwrite=args.overwrite)
    print(_lines(result.summary, args.out))
    if result.exit_code:
        why = result.summary["stopped"] or "nothing could be replayed (see the problems above)"
        print(f"replay: {why}", file=sys.stderr)
    return result.exit_code


def _pct(value) -> str:
    return "-" if value is None else f"{100 * value:.1f}%"


def _lines(s: dict, out: Path) -> str:
    m = s["mcnemar"]
    rates = ", ".join(f"{threshold_label(r['threshold'])}: {_pct(r['rate_before'])} -> {_pct(r['rate_after'])}"
                      for r in s["rates"])
    lines = [f"replayed {s['n_replayed']} of {s['n_tests']} tests with a verdict in the run "
             f"against {s['settings']['sut_version']['label']} (the run's SUT: {s['settings']['run_sut']}"
             + "".join(f", {k}={v}" for k, v in sorted(s['settings']['run_sut_options'].items())) + ")",
             f"at threshold {threshold_label(s['threshold'])}: fixed {s['fixed']}, new {s['new']}, "
             f"persisting {s['persisting']}, still passing {s['still_passing']} "
             f"(failures {s['failures_before']} -> {s['failures_after']}); "
             f"McNemar exact p = {m['p']:.4g} ({m['fixed']} fixed vs {m['new']} new)",
             f"failure rates (run -> now): {rates}"]
    if s["sut_errors"] or s["not_replayed"]:
        lines.append(f"not counted: {s['sut_errors']} SUT error(s), {s['not_replayed']} not replayed "
                     "(listed in the report and replay.csv)")
    lines.append(f"report: {out / 'report.html'}  csv: {out / 'replay.csv'}  summary: {out / 'summary.json'}")
    return "\n".join(lines)
