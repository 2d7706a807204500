"""``isu-validate bench ...``: benchmarks that print speed against error.

Each area adds its own benchmark: a module in BENCH_MODULES defines
``register_bench(subparsers)`` adding e.g. ``bench search`` or ``bench render``.
"""
from __future__ import annotations

import importlib

BENCH_MODULES = [
    "isu_validate.render.bench",   # bench render
    "isu_validate.render.bench_faces",   # bench faces
    "capture.bench",          # bench calib
    "isu_validate.search.bench",
    "isu_validate.search.effectiveness.bench",  # bench effectiveness
    "isu_validate.evaluate.bench",
    "isu_validate.realism.bench",  # bench fid
    "style_transfer.bench",        # bench nst
    "capture.camera_model.bench",  # bench exposure
]


def register(sub) -> None:
    parser = sub.add_parser("bench", help="benchmarks: speed against error")
    bench_sub = parser.add_subparsers(dest="bench", metavar="BENCH")
    for name in BENCH_MODULES:
        importlib.import_module(name).register_bench(bench_sub)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)
