"""``isu-validate bench search``: the search's own cost per test (everything but render and SUT).

Runs the real loop pieces (ask, diversity, durable archive commit, tell with the
records) against an instant benchmark SUT (``blind-spots``: answers computed from the
scene, judged by the real VQA judge, so a learning algorithm has per-feature verdicts
to learn from), and reports the cost per test in windows ending at the archive sizes
asked for (default 1,000 and 10,000 tests).
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from isu_validate.search.algorithm_names import ALGORITHMS, algorithms_option

WINDOW = 200  # tests per timing window


def register_bench(sub) -> None:
    p = sub.add_parser("search", help="search overhead per test at growing archive sizes")
    p.add_argument("--sizes", default="1000,10000", help="archive sizes to report at (comma-separated)")
    p.add_argument("--algorithm", default=ALGORITHMS[0], type=algorithms_option,
                   help=f"one or more of {', '.join(ALGORITHMS)}, comma-separated (default {ALGORITHMS[0]})")
    p.add_argument("--pop-size", type=int, default=50)
    p.add_argument("--space", default="isu-paper")
    p.add_argument("--seed", type=int, default=1)
    p.set_defaults(func=cmd_bench_search)


class Window:
    """Seconds per part of the loop over the tests since the last row."""

    def __init__(self):
        self.start, self.cpu_start, self.tests = time.perf_counter(), time.process_time(), 0
        self.parts = {"search": 0.0, "commit": 0.0}

    def timed(self, part: str, started: float) -> None:
        self.parts[part] += time.perf_counter() - started

    def row(self, tests: int) -> dict:
        per_test = 1000 / max(1, self.tests)
        return {"tests": tests, "ms_per_test": per_test * (time.perf_counter() - self.start),
                "cpu_ms_per_test": per_test * (time.process_time() - self.cpu_start),
                **{f"{k}_ms_per_test": per_test * v for k, v in self.parts.items()}}


def measure(space_name: str, algorithm: str, pop_size: int, seed: int, sizes: list[int], folder: Path) -> list[dict]:
    import numpy as np

    from isu_validate.archive import Archive, TestRecord
    from isu_validate.bench.effectiveness.harness import InstantEvaluation
    from isu_validate.search.algorithms import make_algorithm
    from isu_validate.search.diversity import DiversityTracker
    from isu_validate.search.loop import _objectives
    from isu_validate.space import load_space
    from isu_validate.sut.planted import make_benchmark_sut

    space = load_space(space_name)
    evaluate = InstantEvaluation(space, make_benchmark_sut("blind-spots", space))
    search = make_algorithm(algorithm, space, pop_size, seed)
    diversity = DiversityTracker(space)
    archive = Archive(folder / "bench.sqlite")
    rows, n, window, generation = [], 0, Window(), 0
    try:
        while n < max(sizes):
            started = time.perf_counter()
            scenes = search.ask(max(sizes) - n)
            novelty = [diversity.add(scene) for scene in scenes]
            window.timed("search", started)
            records = []
            for index, (scene, f_div) in enumerate(zip(scenes, novelty)):
                canonical = space.canonical(scene)
                _, verdict = evaluate(canonical)
                record = TestRecord(test_id=f"g{generation:04d}-i{index:03d}", generation=generation, index=index,
                                    algorithm=algorithm, seed=seed, scene_key=space.key(scene), scene=scene,
                                    canonical=canonical, f_div=f_div, fitness=dict(verdict.fitness),
                                    primary=verdict.primary, failed=verdict.failed,
                                    details={"verdict": verdict.details})
                started = time.perf_counter()
                archive.add(record)
                window.timed("commit", started)
                records.append(record)
            started = time.perf_counter()
            search.tell(np.array([_objectives(r) for r in records]), records)
            window.timed("search", started)
            generation += 1
            n += len(scenes)
            window.tests += len(scenes)
            if window.tests >= WINDOW or n >= max(sizes):
                rows.append(window.row(n))
                window = Window()
    finally:
        archive.close()
    return [min(rows, key=lambda r: abs(r["tests"] - size)) | {"size": size} for size in sizes]


def cmd_bench_search(args) -> int:
    sizes = sorted(int(s) for s in args.sizes.split(","))
    for algorithm in args.algorithm:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            results = measure(args.space, algorithm, args.pop_size, args.seed, sizes, Path(tmp))
            total = time.perf_counter() - start
        print(f"search overhead ({algorithm}, pop {args.pop_size}, space {args.space}; "
              f"archive commits durable: SQLite WAL, synchronous=FULL)")
        print(f"{'archive size':>12}  {'ms/test':>8}  {'search':>7}  {'commit':>7}  {'CPU':>6}  "
              "overhead  goal (ms/test)")
        for r in results:
            overhead = r["search_ms_per_test"] + r["commit_ms_per_test"]
            verdict = "ok" if overhead < 5 else "over"
            print(f"{r['size']:>12}  {r['ms_per_test']:>8.2f}  {r['search_ms_per_test']:>7.2f}  "
                  f"{r['commit_ms_per_test']:>7.2f}  {r['cpu_ms_per_test']:>6.2f}  {overhead:>8.2f}  "
                  f"< 5 ms ({verdict})")
        print("  search: ask + diversity + tell; commit: the durable archive write; overhead: search + commit,\n"
              "  what the search adds to a test (the goal); ms/test: the whole loop, including the benchmark\n"
              "  SUT's in-memory answers and judging, which a real run replaces by a render and a SUT call;\n"
              "  CPU: this process, all parts")
        print(f"total {total:.1f} s for {max(sizes)} tests\n", flush=True)
    return 0
