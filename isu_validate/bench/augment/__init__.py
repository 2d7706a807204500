"""``isu-validate bench augment``: the test-and-fix loop on the reference ISU, measured end to end.

A random-search run finds the shipped reference ISU's failures (at the oracle threshold 0.9); datasets
of N renders are made uniformly and focused near those failures (``isu-validate dataset``), and for the
style row the focused renders get copies styled towards a frame that stands for reality (``--style``;
by default a stand-in frame the bench renders, which is not a photograph); each retrains the reference
ISU on its stored base features plus the dataset (``reference train --extra``); an independent
random-search run (seed + 1) is replayed on every model (``replay``). Rows: none, uniform N, focused N,
focused N with style transfer; columns: failure rate at 0.8, 0.9, 1.0 on the replayed run with the cut
against none, McNemar's p, worst and mean held-out accuracy change, renders, minutes. Features the
focused retrain did not fix are named and the table is shown without them as well.

Every stage is committed in ``OUT/stages.json``: run the same command again after a kill and finished
stages are kept (``OUT/search``, ``replay-run``, ``datasets/``, ``models/``, ``replays/`` resume inside).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path


def register_bench(sub) -> None:
    from .loop import ROWS

    p = sub.add_parser("augment", help="the fix loop: focused vs uniform data, retrain the reference ISU, replay")
    p.add_argument("--n", type=int, default=120, help="images per dataset (default 120)")
    p.add_argument("--budget", type=int, default=150, help="tests per random-search run (default 150)")
    p.add_argument("--seed", type=int, default=0, help="finding run and datasets (the replayed run: seed + 1)")
    p.add_argument("--preset", default="draft")
    p.add_argument("--pop-size", type=int, default=15, help="tests per generation of the runs (default 15)")
    p.add_argument("--style", type=Path, help="style image of the style row (default: a stand-in frame the bench "
                                              "renders: another rig, sky and sensor noise; not a photograph)")
    p.add_argument("--style-steps", type=int, default=150, help="fast style net training steps (default 150)")
    p.add_argument("--rows", default=",".join(ROWS), help=f"comma list (default {','.join(ROWS)})")
    p.add_argument("--out", type=Path, default=Path("runs/bench-augment"),
                   help="where every stage goes; run again to resume (default runs/bench-augment)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .loop import AugmentSettings, run_augment
    from .steps import PipelineSteps

    def log(text: str) -> None:
        print(f"bench augment: {text}", file=sys.stderr, flush=True)

    settings = AugmentSettings(args.out, n=args.n, budget=args.budget, seed=args.seed, preset=args.preset,
                               pop_size=args.pop_size, style=str(args.style) if args.style else None,
                               style_steps=args.style_steps,
                               rows=tuple(r.strip() for r in args.rows.split(",") if r.strip()))
    steps = PipelineSteps(args.preset, args.pop_size, settings.threshold, args.out, log)
    result = run_augment(settings, steps, log)
    text = report(result, settings)
    (args.out / "result.json").write_text(json.dumps(result, indent=1, default=str) + "\n")
    (args.out / "table.md").write_text(text + "\n")
    print(text)
    return 0


def report(result: dict, settings) -> str:
    from .table import format_goal, format_table

    search = result["search"]
    lines = [f"bench augment: N = {settings.n}, random-search runs of {settings.budget} tests (preset "
             f"{settings.preset}, oracle {settings.threshold}); the finding run failed {search['failures']} of "
             f"{search['tests']}; the replayed run is seed {settings.seed + 1}", "",
             format_table(result["rows"], settings.n), "", format_goal(result["goal"]),
             f"(the focused rows' renders and minutes include the finding run's {search['renders']} renders)"]
    lines += ["", "wrong answers on the replayed run per feature (model: count):"]
    errors = result["errors"]
    for feature in errors["none"]:
        counts = ", ".join(f"{row} {errors[row][feature]}" for row in errors)
        lines.append(f"  {feature}: {counts}")
    if result.get("not_fixed"):
        lines += ["", f"not fixed by the focused retrain: {', '.join(result['not_fixed'])}; without them:", "",
                  format_table(result["rows_without"], settings.n), "", format_goal(result["goal_without"])]
    elif "not_fixed" in result:
        lines += ["", "every feature the shipped model got wrong 3+ times was fixed at least in part by the "
                      "focused retrain"]
    return "\n".join(lines)
