"""``isu-validate report RUN... --out DIR``: RQ1 and RQ2 over runs, with statistics."""
from __future__ import annotations

from pathlib import Path

from . import add_overwrite_option
from ..devices import add_device_argument


def register(sub) -> None:
    p = sub.add_parser("report", help="compare runs: failure rates, statistics, failure analysis and diversity",
                       description="Compare runs grouped by SUT, mode and algorithm: RQ1 failure rates at thresholds "
                                   "with the Wilcoxon rank-sum test and A12, failures over time, failure analysis "
                                   "and regions, RQ2 failure clusters (coverage, entropy), and a failure gallery. "
                                   "Writes report.html plus CSV/JSON for every table.")
    p.add_argument("runs", nargs="+", type=Path, metavar="RUN",
                   help="run directories (a folder of run directories stands for all of them)")
    p.add_argument("--out", type=Path, required=True, help="folder for report.html and the tables")
    p.add_argument("--embedding", default="inception",
                   help="image embedding for failure clusters: inception (FID InceptionV3, default), "
                        "clip:PATH (TorchScript CLIP image encoder you supply), or scene (scene encoding, no images)")
    p.add_argument("--clusters", type=int, default=None, metavar="K",
                   help="k for k-means (default 10; lowered when there are fewer distinct failures)")
    p.add_argument("--gallery", type=int, default=None, metavar="N", help="failing scenes shown (default 60)")
    p.add_argument("--seed", type=int, default=0, help="seed for k-means")
    add_overwrite_option(p, "a report of other runs or settings, or another command's output (a run)")
    add_device_argument(p)   # the image embedding's device
    p.set_defaults(func=cmd_report)


def cmd_report(args) -> int:
    from ..analysis import report

    path = report(args.runs, args.out, embedding=args.embedding, clusters=args.clusters, gallery=args.gallery,
                  seed=args.seed, device=args.device, overwrite=args.overwrite)
    print(f"report: {path}")
    for line in region_lines(path.parent / "report.json"):
        print(line)
    return 0


def region_lines(report_json: Path) -> list[str]:
    """The failure regions of every SUT and mode, as the report's "Failure regions" tables hold them (the
    rules `dataset --focus failing` draws near)."""
    import json

    tables = json.loads(report_json.read_text())["tables"]
    lines = []
    for name, rules in sorted(tables.items()):
        if not name.startswith("regions"):
            continue
        group = name[len("regions_"):].replace("_", " ") if name != "regions" else ""
        lines.append(f"failure regions{' of ' + group if group else ''} (decision-tree rules where most tests fail):"
                     + ("" if rules else " none"))
        lines += [f"  {r['rule']}: {r['failing']} of {r['tests']} tests failing, "
                  f"{100 * r['share_of_failures']:.1f}% of the failures" for r in rules]
    return lines
