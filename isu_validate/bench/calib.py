"""``isu-validate bench calib``: calibration speed against error on synthetic boards with a known truth."""
from __future__ import annotations

import functools
import json
import time
from typing import TYPE_CHECKING

from capture.lens_models import MODELS as LENS_MODELS   # the names only: OpenCV waits until the bench runs

if TYPE_CHECKING:
    from capture.board import BoardSpec
    from capture.synthetic import TrueCamera


@functools.cache
def bench_board() -> BoardSpec:
    """A larger board than the usual print, close and well tilted: the data a careful technician collects.
    mrcal's reference run on synthetic data (40 frames, 0.3 px noise) used comparable coverage.
    Built when the bench runs: ``capture.board`` loads OpenCV."""
    from capture.board import BoardSpec
    return BoardSpec(14, 10, 0.030, 0.022, "DICT_5X5_100")


BENCH_DISTANCE_M = (0.2, 0.45)
BENCH_TILT_DEG = 60.0
GOAL = {"frames": 40, "noise_px": 0.3, "intrinsics_px": 0.5, "crossval_median_px": 0.1, "solve_s": 10.0}


def register_bench(sub) -> None:
    p = sub.add_parser("calib", help="calibration: solve time, intrinsics error, uncertainty, cross-validation")
    p.add_argument("--frames", type=int, nargs="+", default=[10, 20, 40])
    p.add_argument("--noise", type=float, nargs="+", default=[0.3, 1.0], help="corner noise, px per axis")
    p.add_argument("--model", default="opencv8", choices=LENS_MODELS)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run)


def truth_for(model: str) -> TrueCamera:
    from capture import synthetic
    if model == "fisheye":
        return synthetic.FISHEYE_180
    if model == "pinhole":
        return synthetic.TrueCamera("pinhole", synthetic.DEFAULT_CAMERA.intrinsics[:4], 640, 480)
    return synthetic.DEFAULT_CAMERA


def bench_case(model: str, frames: int, noise: float, seed: int) -> dict:
    import numpy as np

    from capture import synthetic
    from capture.calibrate import calibrate
    from capture.projection_diff import projection_diff
    board = bench_board()
    truth = truth_for(model)
    rng = np.random.default_rng(seed)
    distance = (0.12, 0.35) if model == "fisheye" else BENCH_DISTANCE_M
    poses = synthetic.random_poses(rng, frames, truth, board, distance_m=distance, max_tilt_deg=BENCH_TILT_DEG)
    dets = synthetic.observe(board, truth, poses, noise, rng)
    t0 = time.perf_counter()
    res = calibrate(dets, model, board=board)
    total = time.perf_counter() - t0
    err = np.abs(res.solution.intrinsics[:4] - np.asarray(truth.intrinsics[:4]))
    vs_truth = projection_diff(model, res.solution.intrinsics, truth.model, truth.intrinsics, truth.size,
                               distance_m=1.0).stats()
    vs_truth_inf = projection_diff(model, res.solution.intrinsics, truth.model, truth.intrinsics, truth.size).stats()
    q = res.camera.quality
    return {"model": model, "frames": frames, "noise_px": noise, "solve_s": res.timings["solve_s"], "total_s": total,
            "err_fx": err[0], "err_fy": err[1], "err_cx": err[2], "err_cy": err[3], "rms_px": q["rms_px"],
            "truth_diff_median_px": vs_truth["median"], "truth_diff_inf_median_px": vs_truth_inf["median"],
            "unc_centre_px": q["uncertainty_px"]["centre"],
            "unc_edge_px": q["uncertainty_px"]["edge"], "unc_corner_px": q["uncertainty_px"]["corner"],
            "cv_median_px": (q["cross_validation_diff_px"] or {}).get("median", float("nan")),
            "warnings": len(res.warnings)}


def format_table(rows: list[dict], cols: list[str]) -> str:
    """Right-aligned columns as wide as their full names (a truncated header named two columns alike)."""
    widths = [max(10, len(c)) for c in cols]
    lines = [" ".join(f"{c:>{w}}" for c, w in zip(cols, widths))]
    for r in rows:
        lines.append(" ".join(f"{r[c]:>{w}d}" if isinstance(r[c], int) else f"{r[c]:>{w}.3f}"
                              for c, w in zip(cols, widths)))
    return "\n".join(lines)


def run(args) -> int:
    rows = [bench_case(args.model, f, n, args.seed) for n in args.noise for f in args.frames]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    cols = ["frames", "noise_px", "solve_s", "total_s", "err_fx", "err_fy", "err_cx", "err_cy", "truth_diff_median_px",
            "truth_diff_inf_median_px",
            "unc_centre_px", "unc_edge_px", "unc_corner_px", "cv_median_px", "rms_px"]
    print(f"bench calib: model {args.model}, board {bench_board()}, seed {args.seed}; errors in px against the truth")
    print(format_table(rows, cols))
    goal = [r for r in rows if r["frames"] == GOAL["frames"] and r["noise_px"] == GOAL["noise_px"]]
    for r in goal:
        ok = (max(r["err_fx"], r["err_fy"], r["err_cx"], r["err_cy"]) <= GOAL["intrinsics_px"]
              and r["cv_median_px"] <= GOAL["crossval_median_px"] and r["solve_s"] < GOAL["solve_s"])
        print(f"goal (40 frames, 0.3 px: fx fy cx cy within 0.5 px, cross-validation median <= 0.1 px, "
              f"solve < 10 s): {'met' if ok else 'NOT met'}")
    return 0
