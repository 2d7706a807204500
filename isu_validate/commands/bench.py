"""``isu-validate bench ...``: benchmarks that print speed against error.

Each benchmark is a module of ``isu_validate.bench`` named after its command: it defines
``register_bench(subparsers)`` (options only; heavy imports wait until the benchmark runs).
Only the benchmark being run is imported.
"""
from __future__ import annotations

import importlib

from . import chosen

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
    "recognise": "render seconds per frame against photo-trained models' recognition rates, per preset",
}


def register(sub, argv: list[str] | None = None) -> None:
    parser = sub.add_parser("bench", help="benchmarks: speed against error")
    bench_sub = parser.add_subparsers(dest="bench", metavar="BENCH")
    after = argv[argv.index("bench") + 1:] if argv and "bench" in argv else None
    wanted = chosen(after, BENCHES) if after is not None else None
    for name, summary in BENCHES.items():
        if after is None or name == wanted:
            importlib.import_module(f"isu_validate.bench.{name}").register_bench(bench_sub)
        else:
            bench_sub.add_parser(name, help=summary, add_help=False)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)
