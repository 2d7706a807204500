"""``isu-validate bench search``: the search's own cost per test (everything but render and SUT).

Runs the real loop pieces (ask, diversity, durable archive commit, tell) with a
synthetic, instant fitness, and reports the cost per test in windows ending at the
archive sizes asked for (default 1,000 and 10,000 tests).
"""
from __future__ import annotations

import tempfile
import time
import zlib
from pathlib import Path

import numpy as np

from ..archive import Archive, TestRecord
from ..space import load_space
from .algorithms import ALGORITHMS, make_algorithm
from .diversity import DiversityTracker

WINDOW = 200  # tests per timing window


def register_bench(sub) -> None:
    p = sub.add_parser("search", help="search overhead per test at growing archive sizes")
    p.add_argument("--sizes", default="1000,10000", help="archive sizes to report at (comma-separated)")
    p.add_argument("--algorithm", choices=ALGORITHMS, default="nsga2")
    p.add_argument("--pop-size", type=int, default=50)
    p.add_argument("--space", default="isu-paper")
    p.add_argument("--seed", type=int, default=1)
    p.set_defaults(func=cmd_bench_search)


def synthetic_fitness(space, scene: dict) -> float:
    """A cheap stand-in for a SUT: deterministic, depends on several features."""
    canonical = space.canonical(scene)
    # crc32, not hash(): string hashes change per process, and the bench must repeat exactly
    return 1.0 - 0.1 * sum(zlib.crc32(f"{k}={v}".encode()) % 3 == 0 for k, v in canonical.items()) / max(1, len(canonical))


def measure(space_name: str, algorithm: str, pop_size: int, seed: int, sizes: list[int], folder: Path) -> list[dict]:
    space = load_space(space_name)
    search = make_algorithm(algorithm, space, pop_size, seed)
    diversity = DiversityTracker(space)
    archive = Archive(folder / "bench.sqlite")
    rows, n, window_start, window_n = [], 0, time.perf_counter(), 0
    generation = 0
    try:
        while n < max(sizes):
            scenes = search.ask(max(sizes) - n)
            F = []
            for index, scene in enumerate(scenes):
                f_div = diversity.add(scene)
                fitness = synthetic_fitness(space, scene)
                archive.add(TestRecord(test_id=f"g{generation:04d}-i{index:03d}", generation=generation, index=index,
                                       algorithm=algorithm, seed=seed, scene_key=space.key(scene), scene=scene,
                                       canonical=space.canonical(scene), f_div=f_div, fitness={"f_qa": fitness},
                                       primary=fitness, failed=fitness < 1.0))
                F.append([fitness, -f_div])
            search.tell(np.array(F))
            generation += 1
            n += len(scenes)
            window_n += len(scenes)
            if window_n >= WINDOW or n >= max(sizes):
                now = time.perf_counter()
                rows.append({"tests": n, "ms_per_test": 1000 * (now - window_start) / window_n})
                window_start, window_n = now, 0
    finally:
        archive.close()
    return [min(rows, key=lambda r: abs(r["tests"] - size)) | {"size": size} for size in sizes]


def cmd_bench_search(args) -> int:
    sizes = sorted(int(s) for s in args.sizes.split(","))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        results = measure(args.space, args.algorithm, args.pop_size, args.seed, sizes, Path(tmp))
        total = time.perf_counter() - start
    print(f"search overhead ({args.algorithm}, pop {args.pop_size}, space {args.space}; "
          f"archive commits durable: SQLite WAL, synchronous=FULL)")
    print(f"{'archive size':>12}  {'ms/test':>8}  goal")
    for r in results:
        verdict = "ok" if r["ms_per_test"] < 5 else "over"
        print(f"{r['size']:>12}  {r['ms_per_test']:>8.2f}  < 5 ms ({verdict})")
    print(f"total {total:.1f} s for {max(sizes)} tests")
    return 0
