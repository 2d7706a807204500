"""``isu-validate bench ...``: benchmarks that print speed against error.

Each benchmark is a module of ``isu_validate.bench`` named after its command: it defines
``register_bench(subparsers)`` (options only; heavy imports wait until the benchmark runs).
Only the benchmark being run is imported.
"""
from __future__ import annotations

import importlib

from . import add_overwrite_option, chosen

# bench NAME -> its one-line summary (the module is isu_validate.bench.NAME)
BENCHES = {
    "render": "render presets: seconds per frame against PSNR/SSIM to a reference",
    "faces": "driver's face: size in pixels and HAPPY/SERIOUS difference per preset",
    "calib": "calibration: solve time, intrinsics error, uncertainty, cross-validation",
    "search": "search overhead per test at growing archive sizes",
    "effectiveness": "failure rates of each search algorithm against random search",
    "evaluate": "judge cost per scene: parsing, VQA, caption metrics by torch threads",
    "fid": "FID/KID: accuracy against a float64 reference, n against spread, speed",
    "nst": "style transfer: Gatys steps against loss and time; fast-model throughput",
    "exposure": "imaging model: fit error against known cameras, apply time, chart detectors",
    "dataset": "dataset: images/s with masks, and COCO masks against a re-render",
    "augment": "the fix loop: focused vs uniform data, retrain the reference ISU, replay",
    "real": "real photographs: calibration, response, colour beside OpenCV and colour-science on the same photos",
    "recognise": "render seconds per frame against photo-trained models' recognition rates, per preset",
    "transfer": "recipes of training renders, judged on labelled real photos",
}


def register(sub, argv: list[str] | None = None) -> None:
    parser = sub.add_parser("bench", help="benchmarks: speed against error")
    bench_sub = parser.add_subparsers(dest="bench", metavar="BENCH")
    after = argv[argv.index("bench") + 1:] if argv and "bench" in argv else None
    wanted = chosen(after, BENCHES) if after is not None else None
    for name, summary in BENCHES.items():
        if after is None or name == wanted:
            importlib.import_module(f"isu_validate.bench.{name}").register_bench(bench_sub)
            _claims_its_out(bench_sub.choices[name], name)
        else:
            bench_sub.add_parser(name, help=summary, add_help=False)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


def _claims_its_out(parser, name: str) -> None:
    """A benchmark with ``--out`` refuses a folder that holds another command's output (``archive/output_dir.py``),
    as every command does; ``--overwrite`` says otherwise. Its own earlier output is the benchmark's business:
    ``bench augment`` and ``bench effectiveness --pipeline`` resume it and refuse other settings themselves, the
    others measure again into it."""
    run = parser.get_default("func")
    if run is None or "out" not in {a.dest for a in parser._actions}:
        return
    add_overwrite_option(parser, "another command's output")

    def claimed(args):
        if args.out is None:
            return run(args)
        from ..archive.output_dir import claim_output
        output = claim_output(args.out, f"bench {name}", {}, resume=True, overwrite=args.overwrite)
        try:
            return run(args)
        finally:   # marked once the benchmark made it: a refused option leaves no folder behind
            if output.path.is_dir():
                output.mark()

    parser.set_defaults(func=claimed)
