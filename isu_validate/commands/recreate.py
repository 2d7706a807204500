"""``isu-validate recreate``: pick tests from runs for a lab to recreate; write the pairs and printable sheets.

    isu-validate recreate RUN... --select failing|passing|mixed --n N --seed S --out PAIRS
                          [--failing-share F] [--effort FILE] [--cabin RIG] [--sheet-preset PRESET|run]

Each sheet's picture is the scene rendered again for print (Blender, --sheet-preset, 640 px wide or more,
about 2 s a scene at standard) into PAIRS/<sample>/sheet.png; sim.png stays the run's frame.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path


def register(sub) -> None:
    p = sub.add_parser("recreate", help="pick tests to recreate in a real car; write pairs and recreation sheets",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", metavar="RUN", help="run directories (or folders of runs)")
    p.add_argument("--select", choices=("failing", "passing", "mixed"), default="failing",
                   help="which tests: failing, passing, or mixed (the runs' failing share; default failing)")
    p.add_argument("--n", type=int, default=10, help="how many tests (default 10)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random draw (default 0)")
    p.add_argument("--failing-share", type=float, help="mixed: share of failing tests instead of the runs' own")
    p.add_argument("--effort", default="default",
                   help="change costs in minutes, rigs/effort/NAME.toml or a file (default: default)")
    p.add_argument("--cabin", help="cabin rig for the measurements (default: the run's)")
    p.add_argument("--sheet-preset", default="standard",
                   help="render preset of the sheets' pictures (default standard), or 'run': the run's own "
                        "frames, no Blender (blurred when the run rendered small)")
    p.add_argument("--out", type=Path, required=True, help="new pairs directory")
    p.add_argument("--json", action="store_true", help="print the plan as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    import sys

    from ..recreate import plan_recreation
    if args.sheet_preset != "run":
        print(f"rendering each sheet's picture at the {args.sheet_preset} preset (Blender, about 2 s a scene at "
              "standard; --sheet-preset run skips it)", file=sys.stderr)
    plan = plan_recreation(args.runs, args.select, args.n, args.seed, args.out, args.failing_share, args.effort,
                           args.cabin, args.sheet_preset)
    if args.json:
        print(json.dumps({"out": str(plan.out), "samples": plan.samples, "minutes": plan.minutes,
                          "run_order_minutes": plan.run_order_minutes, "method": plan.method,
                          "notes": plan.notes}, indent=2))
        return 0
    failing = sum(s["failed"] for s in plan.samples)
    print(f"picked {len(plan.samples)} tests ({failing} failing, {len(plan.samples) - failing} passing) "
          f"into {plan.out}")
    for s in plan.samples:
        print(f"  {s['sample']}  {s['source']:40s} {'failing' if s['failed'] else 'passing'}  "
              f"{s['minutes']:5.1f} min  {', '.join(s['changes']) or '-'}")
    print(f"estimated effort: {plan.minutes:.1f} min in this order, {plan.run_order_minutes:.1f} min in the "
          f"run order ({plan.saving:.0%} less; {plan.method})")
    for note in plan.notes:
        print(f"note: {note}")
    print(f"sheets: {plan.out / 'index.html'} (print it: one A4 page per scene)")
    return 0
