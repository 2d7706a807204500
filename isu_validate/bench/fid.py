"""``isu-validate bench fid``: FID/KID accuracy, spread against n, and feature-extraction speed.

Three tables:
1. agreement of the fast trace route with the float64 eigenvalue reference, and what the
   pytorch-fid route (scipy.linalg.sqrtm of S_a S_b) returns on the same singular inputs;
2. n against the spread of FID and KID over random subsets of two fixed pools, with the
   pools' full-size values as the target, and the time per computation;
3. feature extraction throughput on 640x480 frames (decode excluded, resize included).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from isu_validate.devices import add_device_argument
from isu_validate.errors import InputError


def register_bench(sub) -> None:
    p = sub.add_parser("fid", help="FID/KID: accuracy against a float64 reference, n against spread, speed")
    p.add_argument("--a", help="image set A (DIR or PAIRS_DIR:ROLE); default: synthetic features")
    p.add_argument("--b", help="image set B")
    p.add_argument("--sizes", default="2,10,53,200,500", help="subset sizes n (default 2,10,53,200,500)")
    p.add_argument("--repeats", type=int, default=10, help="random subsets per n (default 10)")
    p.add_argument("--throughput-images", type=int, default=16, help="frames for the speed table; 0 skips")
    p.add_argument("--batch-size", type=int, default=8)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--seed", type=int, default=0)
    add_device_argument(p)
    p.add_argument("--device-check", type=int, default=0, metavar="N",
                   help="also extract N frames' features (--a/--b, else synthetic) on the CPU and on --device and "
                        "print how far FID and the features move (the tolerance of issue 34); 0 skips")
    p.set_defaults(func=run)


def synthetic_pools(n: int, dim: int = 2048, rank: int = 64, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Two low-rank-plus-noise Gaussians shaped like Inception features (non-negative mean, few strong directions)."""
    rng = np.random.default_rng(seed)
    basis = rng.normal(size=(rank, dim)) / np.sqrt(rank)
    mu = np.abs(rng.normal(0.4, 0.2, dim))

    def draw(shift: float, stretch: float) -> np.ndarray:
        z = rng.normal(size=(n, rank)) * stretch
        return mu + shift + z @ basis + 0.05 * rng.normal(size=(n, dim))
    return draw(0.0, 1.0), draw(0.01, 1.2)


def agreement_table(pool_a: np.ndarray, pool_b: np.ndarray, sizes: list[int]) -> None:
    from isu_validate.realism.fid import GramFID, fid_from_stats, stats
    print("1. trace route against the float64 eigenvalue reference (same features)")
    print(f"{'n':>6} {'FID (fast)':>14} {'FID (eig ref)':>14} {'rel diff':>10} {'fast s':>8} {'ref s':>8}  "
          "sqrtm (pytorch-fid)")
    for i, n in enumerate(sizes):
        a, b = pool_a[:n], pool_b[:n]
        t0 = time.perf_counter()
        fast = GramFID.from_features(a, b).fid()
        t1 = time.perf_counter()
        ref = fid_from_stats(*stats(a), *stats(b))
        t2 = time.perf_counter()
        note = _sqrtm_route(a, b) if i < 2 else "(skipped: 10+ s at d=2048)"
        rel = abs(fast - ref) / max(ref, 1e-300)
        print(f"{n:>6} {fast:>14.6f} {ref:>14.6f} {rel:>10.2e} {t1 - t0:>8.3f} {t2 - t1:>8.3f}  {note}")


def _sqrtm_route(a: np.ndarray, b: np.ndarray) -> str:
    import scipy.linalg

    from isu_validate.realism.fid import stats
    (ma, sa), (mb, sb) = stats(a), stats(b)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        raw = scipy.linalg.sqrtm(sa @ sb)  # what pytorch-fid does; it warns on singular input
    flag = " (scipy: singular)" if caught else ""
    naive = (ma - mb) @ (ma - mb) + np.trace(sa) + np.trace(sb) - 2 * np.trace(raw)
    if not np.isfinite(naive):
        return "NaN/inf" + flag
    return f"{np.real(naive):.4f}" + (f" imag {np.imag(naive):+.2e}" if np.iscomplexobj(naive) else "") + flag


def spread_table(pool_a: np.ndarray, pool_b: np.ndarray, sizes: list[int], repeats: int, seed: int) -> None:
    from isu_validate.realism.fid import fid
    from isu_validate.realism.kid import kid
    full_fid = fid(pool_a, pool_b)
    full_kid = kid(pool_a, pool_b, subset_size=min(1000, len(pool_a), len(pool_b)), subsets=20, seed=seed).mean
    print(f"\n2. n against spread ({repeats} random subsets per n; pools of {len(pool_a)} and {len(pool_b)}: "
          f"FID {full_fid:.4f}, KID {full_kid:.5f})")
    print(f"{'n':>6} {'FID mean':>10} {'FID std':>9} {'KID mean':>10} {'KID std':>9} {'s per FID+KID':>14}")
    rng = np.random.default_rng(seed)
    for n in sizes:
        fids, kids = [], []
        start = time.perf_counter()
        for _ in range(repeats):
            a = pool_a[rng.choice(len(pool_a), n, replace=False)]
            b = pool_b[rng.choice(len(pool_b), n, replace=False)]
            fids.append(fid(a, b))
            kids.append(kid(a, b, subset_size=n, subsets=10, seed=seed).mean)
        per = (time.perf_counter() - start) / repeats
        print(f"{n:>6} {np.mean(fids):>10.4f} {np.std(fids):>9.4f} {np.mean(kids):>10.5f} {np.std(kids):>9.5f} "
              f"{per:>14.3f}")


def device_check_table(count: int, batch_size: int, seed: int, device: str, sets: tuple | None) -> None:
    """FID and features of the same frames on the CPU and on ``device``: relative FID change, worst feature."""
    from isu_validate.realism.features import FeatureExtractor
    from isu_validate.realism.fid import fid
    from isu_validate.realism.images import read_rgb
    from isu_validate.realism.sets import resolve_set
    if sets:
        frames = [[read_rgb(p) for p in resolve_set(s).paths[:count]] for s in sets]
    else:
        rng = np.random.default_rng(seed)
        frames = [[rng.uniform(lo, lo + 128, (480, 640, 3)).astype(np.float32) for _ in range(count)] for lo in (0, 96)]
    cpu, other = FeatureExtractor(batch_size=batch_size), FeatureExtractor(batch_size=batch_size, device=device)
    if other.device.is_cpu:
        print(f"\n4. device check skipped: {other.device.describe()}")
        return

    def feats(ex):
        return [np.concatenate([ex.features_of_arrays(f[i:i + batch_size]) for i in range(0, len(f), batch_size)])
                for f in frames]
    on_cpu, on_dev = feats(cpu), feats(other)
    fid_cpu, fid_dev = fid(*on_cpu), fid(*on_dev)
    worst = max(float(np.max(np.abs(a - b))) for a, b in zip(on_cpu, on_dev))
    scale = max(float(np.max(np.abs(a))) for a in on_cpu)
    print(f"\n4. cpu against {other.device.describe()}: {len(frames[0])} + {len(frames[1])} frames")
    change = abs(fid_dev - fid_cpu) / max(fid_cpu, 1e-12)
    print(f"   FID {fid_cpu:.6f} (cpu) / {fid_dev:.6f}: relative change {change:.2e}; "
          f"largest feature change {worst:.2e} (largest feature {scale:.3g})")


def throughput_table(count: int, batch_size: int, seed: int, device: str = "cpu") -> None:
    from isu_validate.realism.features import FeatureExtractor
    from isu_validate.realism.resize import resize_rgb
    rng = np.random.default_rng(seed)
    frames = [rng.uniform(0, 255, (480, 640, 3)).astype(np.float32) for _ in range(count)]
    ex = FeatureExtractor(batch_size=batch_size, device=device)
    for _ in range(3):  # TorchScript's profiling executor optimises the graph over the first calls
        ex.features_of_arrays(frames[:batch_size])
    t0 = time.perf_counter()
    for f in frames:
        resize_rgb(f, 299)
    t1 = time.perf_counter()
    rates = []
    for _ in range(3):  # median and best of 3: a shared machine's other jobs only slow a round down
        start = time.perf_counter()
        for i in range(0, count, batch_size):
            ex.features_of_arrays(frames[i:i + batch_size])
        rates.append(count / (time.perf_counter() - start))
    import torch
    print(f"\n3. feature extraction, 640x480 frames, batch {batch_size}, {torch.get_num_threads()} torch threads, "
          f"on {ex.device.describe()}")
    print(f"   resize only: {count / (t1 - t0):.1f} images/s; resize + Inception: "
          f"{np.median(rates):.2f} / {max(rates):.2f} images/s (median / best of 3 rounds)")


def _pools(args):
    if not args.a:
        big = max(_sizes(args)) * 2
        return synthetic_pools(max(big, 1000), seed=args.seed), "synthetic low-rank Gaussian features, d=2048"
    from isu_validate.realism.cache import default_cache_dir
    from isu_validate.realism.features import FeatureExtractor, stderr_progress
    from isu_validate.realism.sets import resolve_set
    if not args.b:
        raise InputError("bench fid needs both --a and --b (or neither, for synthetic features)")
    ex = FeatureExtractor(batch_size=args.batch_size, cache=default_cache_dir(), device=args.device)
    pools = tuple(ex.features(resolve_set(s).paths, stderr_progress(s)) for s in (args.a, args.b))
    return pools, f"Inception features of {args.a} and {args.b}"


def _sizes(args) -> list[int]:
    return [int(s) for s in args.sizes.split(",") if s.strip()]


def run(args) -> int:
    import torch
    from threadpoolctl import threadpool_limits
    if args.threads:
        torch.set_num_threads(args.threads)
    with threadpool_limits(limits=args.threads):  # None leaves BLAS as it is
        return _run(args)


def _run(args) -> int:
    (pool_a, pool_b), what = _pools(args)
    sizes = [n for n in _sizes(args) if 2 <= n <= min(len(pool_a), len(pool_b))]
    if not sizes:
        raise InputError(f"no subset size fits the pools ({len(pool_a)} and {len(pool_b)} images); lower --sizes")
    print(f"bench fid: {what}; seed {args.seed}")
    agreement_table(pool_a, pool_b, sizes)
    spread_table(pool_a, pool_b, sizes, args.repeats, args.seed)
    if args.throughput_images:
        throughput_table(args.throughput_images, args.batch_size, args.seed, args.device)
    if args.device_check:
        device_check_table(args.device_check, args.batch_size, args.seed, args.device,
                           (args.a, args.b) if args.a else None)
    return 0
