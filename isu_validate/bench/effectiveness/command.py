"""``isu-validate bench effectiveness``: does the search find more failures than random search?

Default: every algorithm against benchmark SUTs with planted blind spots (no rendering),
at equal budgets over several seeds; prints per SUT the failure rate per threshold,
the ratio to the baseline, Wilcoxon p and A12, RQ2 coverage and entropy of the failure
clusters, and the search's own time per test.  ``--pipeline`` does the same through
the real pipeline (render + any ``--sut``), writing resumable run directories;
``--emulate RUN_DIR...`` against an emulation of the SUT of stored runs (``emulate.py``);
``--bound ALPHA`` adds the known-risk bound (``bound.py``): what knowing the SUT would reach;
``--prior-tests N`` lets the surrogate first learn from N earlier random tests of the SUT, as
``run --learn-from`` does.
"""
from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

from isu_validate.errors import InputError
from isu_validate.search.algorithm_names import ALGORITHMS, algorithm_option, algorithms_option
from isu_validate.sut.benchmark_names import BENCHMARK_SUTS

# the harness (numpy, pymoo, scikit-learn) is imported by the functions that run the bench, so that
# `bench effectiveness --help` and a mistyped option answer at once


def register_bench(sub) -> None:
    p = sub.add_parser("effectiveness", help="failure rates of each search algorithm against random search",
                       description=__doc__.split("\n\n")[1])
    p.add_argument("--suts", default=",".join(BENCHMARK_SUTS),
                   help=f"benchmark SUTs, comma-separated (default {','.join(BENCHMARK_SUTS)}; "
                        "random-spots-SEED draws other blind spots)")
    p.add_argument("--algorithms", default=",".join(ALGORITHMS), type=algorithms_option,
                   help=f"default {','.join(ALGORITHMS)}")
    p.add_argument("--baseline", default="rs", type=algorithm_option,
                   help="the algorithm the others are compared with (default rs)")
    p.add_argument("--seeds", type=int, default=10, help="runs per algorithm, seeds 1..N (default 10)")
    p.add_argument("--budget", type=int, default=150, help="tests per run (default 150)")
    p.add_argument("--pop-size", type=int, default=15, help="tests per generation (default 15)")
    p.add_argument("--space", default="isu-paper")
    p.add_argument("--clusters", type=int, default=10, help="k of the RQ2 failure clusters (default 10)")
    p.add_argument("--json", type=Path, help="also write the summaries as JSON here")
    p.add_argument("--emulate", nargs="+", type=Path, metavar="RUN_DIR",
                   help="instead of the benchmark SUTs: an EMULATION of the SUT of these stored VQA runs "
                        "(per-feature errors and occlusion learnt from them), to tune the search without calling it")
    p.add_argument("--bound", type=float, metavar="ALPHA",
                   help="also the known-risk bound: tests drawn from random scenes with weight P(fail)^ALPHA, P known "
                        "from other noise draws of the SUT (an upper reference, not a search; e.g. 2 or 4)")
    p.add_argument("--prior-tests", type=int, default=0, metavar="N",
                   help="the surrogate first learns from N earlier random tests of the same SUT (other seeds; not "
                        "in its budget), as `run --learn-from` does")
    p.add_argument("--diagnose", action="store_true",
                   help="instead: why nsga2 barely beats rs (variants with one cause removed, per-generation trace)")
    p.add_argument("--pop-sizes", default="10,20,30", help="population sizes nsga2 is also tried with (--diagnose)")
    real = p.add_argument_group("through the real pipeline (render + SUT), resumable")
    real.add_argument("--pipeline", action="store_true", help="run real runs instead of the in-memory benchmark")
    real.add_argument("--sut", default="reference",
                      help="SUT spec for --pipeline (default reference; bench:NAME renders but answers from the scene)")
    real.add_argument("--out", type=Path, help="folder of the run directories (--pipeline; rerun to resume)")
    real.add_argument("--preset", default="draft")
    real.add_argument("--camera", default="default")
    real.add_argument("--cabin", default="default")
    real.add_argument("--repeats", type=int, default=1)
    real.add_argument("--workers", type=int, default=1)
    p.set_defaults(func=cmd_bench_effectiveness)


def _names(text: str) -> list[str]:
    return [n.strip() for n in text.split(",") if n.strip()]


def _check(args) -> list[str]:
    algorithms = args.algorithms
    if args.seeds < 1 or args.budget < 1 or args.pop_size < 2:
        raise InputError("--seeds and --budget must be at least 1 and --pop-size at least 2")
    if args.emulate and (args.pipeline or args.diagnose):
        raise InputError("--emulate runs the in-memory benchmark; leave out --pipeline and --diagnose")
    if args.bound is not None and (args.pipeline or args.diagnose):
        raise InputError("--bound runs in memory against a benchmark or emulated SUT; "
                         "leave out --pipeline and --diagnose")
    if args.bound is not None and not (math.isfinite(args.bound) and args.bound >= 0):
        raise InputError(f"--bound takes an exponent >= 0 (e.g. 2 or 4), got {args.bound:g}")
    if args.prior_tests and (args.pipeline or args.diagnose or args.prior_tests < 0):
        raise InputError("--prior-tests takes a number of tests >= 0 and runs in memory; leave out --pipeline "
                         "and --diagnose (through the pipeline, use `run --learn-from`)")
    if args.pipeline and args.out is None:
        raise InputError("--pipeline writes run directories: give them a folder with --out (rerun it to resume)")
    return algorithms


def cmd_bench_effectiveness(args) -> int:
    from isu_validate.bench.effectiveness.diagnosis import diagnose
    from isu_validate.bench.effectiveness.emulate import EmulatedSUT
    from isu_validate.bench.effectiveness.harness import simulate
    from isu_validate.bench.effectiveness.summary import summarize
    from isu_validate.bench.effectiveness.table import format_summary
    from isu_validate.space import load_space
    from isu_validate.sut.planted import make_benchmark_sut

    algorithms = _check(args)
    space = load_space(args.space)
    seeds = list(range(1, args.seeds + 1))
    summaries = []
    if args.diagnose:
        for name in _names(args.suts):
            pops = [int(p) for p in _names(args.pop_sizes)]
            print("\n".join(diagnose(space, make_benchmark_sut(name, space), seeds, args.budget, args.pop_size, pops)))
            print(flush=True)
        return 0
    if args.pipeline:
        summaries.append(_pipeline(args, space, algorithms, seeds))
    else:
        suts = [EmulatedSUT.fit(space, args.emulate)] if args.emulate else \
            [make_benchmark_sut(name, space) for name in _names(args.suts)]
        for sut in suts:
            start = time.perf_counter()
            outcomes = [simulate(space, sut, algo, seed, args.budget, args.pop_size, make=_learner(algo, sut, args))
                        for seed in seeds for algo in algorithms]
            description = sut.description + (f"; the surrogate learnt first from {args.prior_tests} earlier random "
                                             "tests per run (not in its budget)" if args.prior_tests else "")
            summary = summarize(space, sut.name, description, outcomes, args.baseline, args.clusters)
            if args.bound is not None:
                summary = _with_bound(space, sut, summary, outcomes, seeds, args)
            summaries.append(summary)
            print(format_summary(summary))
            print(f"  ({time.perf_counter() - start:.1f} s)\n", flush=True)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps([s.to_dict() for s in summaries], indent=2, default=str))
    return 0


PRIOR_SEED_OFFSET = 1000   # the earlier tests' random-search seeds: apart from every run's own


def _learner(algo: str, sut, args):
    """For --prior-tests: a surrogate that first learns from earlier random tests; else None."""
    from isu_validate.bench.effectiveness.harness import simulate
    from isu_validate.search.surrogate_search import SurrogateSearch

    if algo != SurrogateSearch.name or not args.prior_tests:
        return None

    def make(space, pop_size, seed):
        search = SurrogateSearch(space, pop_size, seed)
        search.learn(simulate(space, sut, "rs", PRIOR_SEED_OFFSET + seed, args.prior_tests, pop_size).records)
        return search
    return make


def _with_bound(space, sut, summary, outcomes, seeds, args):
    """The summary again with the bound's runs, its risk taken at the goal's threshold (else the strictest)."""
    from isu_validate.bench.effectiveness.bound import KnownRiskSearch, risk_bank
    from isu_validate.bench.effectiveness.harness import simulate
    from isu_validate.bench.effectiveness.summary import summarize

    threshold = summary.goal.get("threshold", min(summary.thresholds))
    bank = risk_bank(space, sut)
    risk = bank.risk(threshold)
    runs = [simulate(space, sut, KnownRiskSearch.name, seed, args.budget, args.pop_size,
                     make=lambda sp, pop, sd: KnownRiskSearch(sp, pop, sd, bank, risk, args.bound)) for seed in seeds]
    description = (f"{summary.description}; bound: P(fail at {threshold:g})^{args.bound:g} "
                   f"over {len(bank.scenes)} random scenes, P from {len(bank.fitness)} other noise draws "
                   f"(mean {risk.mean():.3f}): a reference, not a search")
    return summarize(space, sut.name, description, outcomes + runs, args.baseline, args.clusters,
                     references=(KnownRiskSearch.name,))


def _pipeline(args, space, algorithms, seeds):
    from isu_validate.bench.effectiveness.pipeline_runs import PipelineSettings, run_all
    from isu_validate.bench.effectiveness.summary import summarize
    from isu_validate.bench.effectiveness.table import format_summary
    from isu_validate.execution import render_threads

    settings = PipelineSettings(out=args.out, sut=args.sut, space=args.space, algorithms=algorithms, seeds=seeds,
                                budget=args.budget, pop_size=args.pop_size, preset=args.preset, camera=args.camera,
                                cabin=args.cabin, repeats=args.repeats, workers=args.workers,
                                render_threads=render_threads(args.workers))
    outcomes = run_all(settings, log=lambda line: print(line, file=sys.stderr, flush=True))
    summary = summarize(space, args.sut, f"through the pipeline, preset {args.preset}, runs in {args.out}",
                        outcomes, args.baseline, args.clusters)
    print(format_summary(summary))
    print(f"  full report with image-based RQ2: isu-validate report {args.out} --out {args.out / 'report'}")
    return summary
