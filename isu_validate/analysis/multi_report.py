"""``isu-validate report``: RQ1 and RQ2 over any set of runs, compared within each SUT and
mode, as one self-contained HTML file plus CSV/JSON for every table."""
from __future__ import annotations

import sys
import time
from collections import defaultdict
from dataclasses import asdict, dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from ..archive import find_runs
from ..archive.output_dir import claim_output
from ..atomic import write_text
from . import plots
from .embeddings import Embedder, make_embedder
from .html import esc, figure, page, paragraph, plural, section, table, threshold_label
from .rq1 import comparisons, rate_key, rq1_table, run_rates
from .rq2 import Diversity, measure_diversity
from .runs import Run, load_run, name_uniquely
from .sections import Part, errors, failure_gallery, feature_analysis, mean_std, regions
from .tables import write_csv, write_json
from .thresholds import FAIL_RULES, FAILURE_THRESHOLDS, METRIC_KEYS
from .timeline import band_by_tests, band_by_time
from ..errors import InputError

DEFAULT_K = 10
DEFAULT_GALLERY = 60


@dataclass
class ReportSettings:
    embedding: str = "inception"
    k: int = DEFAULT_K
    seed: int = 0
    gallery: int = DEFAULT_GALLERY
    device: str = "auto"     # where the image embedding runs (devices.py)


def build_report(run_paths: list, out_dir: Path, settings: ReportSettings | None = None,
                 log=lambda msg: print(msg, file=sys.stderr), overwrite: bool = False) -> Path:
    settings = settings or ReportSettings()
    embedder = make_embedder(settings.embedding, device=settings.device)  # fail on a bad embedding before reading runs
    runs = name_uniquely([load_run(p) for p in find_runs(run_paths)])
    if not runs:
        raise InputError("no runs given; pass one or more run directories")
    log(f"report: {plural(len(runs), 'run')}, {plural(sum(len(r.records) for r in runs), 'test')}")
    out_dir = Path(out_dir)
    claim_output(out_dir, "report", {"runs": sorted(str(r.path.resolve()) for r in runs), **asdict(settings)},
                 overwrite=overwrite).mark()
    settings_groups = settings_of(runs)
    parts = [overview(runs), rq1_part(runs), timeline_part(runs)]
    for (sut, mode), members in settings_groups.items():
        suffix = "" if len(settings_groups) == 1 else f"_{_slug(sut)}_{mode}"
        title = "" if not suffix else f" · {sut} · {mode}"
        parts += [feature_analysis(members, "Failure analysis per feature" + title, suffix),
                  regions(members, "Failure regions" + title, suffix),
                  diversity_part(members, embedder, settings, suffix, title, log)]
    clusters = {(row["run"], row["test_id"]): row["cluster"]
                for part in parts for name, rows in part.tables.items() if name.startswith("clusters") for row in rows}
    parts += [failure_gallery(runs, settings.gallery, clusters), errors(runs)]
    tables = {name: rows for part in parts for name, rows in part.tables.items()}
    for name, rows in tables.items():
        write_csv(out_dir / f"{name}.csv", rows)
    meta = report_settings(runs, settings, embedder)
    write_json(out_dir / "report.json", {"settings": meta, "tables": tables})
    html = page("isu-validate report", f"{plural(len(runs), 'run')} · embedding {embedder.name} · k = {settings.k}",
                [settings_section(meta)] + [p.html for p in parts])
    return write_text(out_dir / "report.html", html)


def settings_of(runs: list[Run]) -> dict[tuple[str, str], list[Run]]:
    """Runs compared with each other: one SUT and mode (and so one scene space)."""
    groups: dict[tuple[str, str], list[Run]] = defaultdict(list)
    for run in runs:
        groups[run.group].append(run)
    for members in groups.values():
        check_one_space(members)
    return dict(sorted(groups.items()))


def check_one_space(runs: list[Run]) -> None:
    first = runs[0]
    for run in runs[1:]:
        if run.space.hash != first.space.hash:
            raise InputError(f"runs {first.path} and {run.path} (SUT {run.sut}, {run.mode}) searched different scene "
                             f"spaces ({first.space.name} {first.space.hash} vs {run.space.name} {run.space.hash}); "
                             "report runs of one space together, and the others in a separate report")


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() else "-" for c in text)[:40]


def report_settings(runs: list[Run], settings: ReportSettings, embedder: Embedder) -> dict:
    def ver(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return "unknown"
    return {"created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "runs": [str(r.path) for r in runs],
            "thresholds": FAILURE_THRESHOLDS, "metrics": METRIC_KEYS,
            "failure": {m: f"{METRIC_KEYS[m]} {FAIL_RULES[m]} threshold" for m in FAIL_RULES},
            "embedding": embedder.name, "embedding_detail": embedder.description,
            "clusters_requested": settings.k, "kmeans": "scikit-learn KMeans, n_init=10, L2-normalised embeddings",
            "seed": settings.seed, "gallery_limit": settings.gallery,
            "rank_sum": "two-sided Wilcoxon rank-sum; exact permutation distribution (ties included) up to "
                        "60 values, else normal approximation with tie and continuity correction",
            "versions": {n: ver(n) for n in ("isu-validate", "numpy", "scipy", "scikit-learn", "matplotlib", "torch")}}


def settings_section(meta: dict) -> str:
    rows = [{"setting": k, "value": _readable(v)} for k, v in meta.items() if k not in ("runs", "versions")]
    rows.append({"setting": "versions", "value": ", ".join(f"{k} {v}" for k, v in meta["versions"].items())})
    return section("Settings", "<details><summary>how these numbers were made</summary>"
                   + table(["setting", "value"], rows) + "</details>", anchor="settings")


def _readable(value) -> str:
    """A setting for people: {"vqa": [1.0, 0.9]} reads "vqa: 1.0, 0.9", not as a Python dict."""
    if isinstance(value, dict):
        return "; ".join(f"{k}: {_readable(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return ", ".join(_readable(v) for v in value)
    return str(value)


# ------------------------------------------------------------------ overview and RQ1
def overview(runs: list[Run]) -> Part:
    rows = [{**run_rates(r), "oracle_threshold": r.oracle_threshold} for r in runs]
    columns = ["run", "sut", "mode", "algorithm", "seed", "oracle_threshold", "tests", "with_verdict", "failures",
               "sut_errors", "render_errors", "occluded"]
    return Part(section("Runs", table(columns, rows), anchor="runs"), {"runs": rows})


def rq1_part(runs: list[Run]) -> Part:
    tables = rq1_table(runs)
    html = [paragraph("Failure rate (%) at each threshold: a VQA test fails when F_qa < t, a captioning test when "
                      "F_emb <= t (the runs' oracles). "
                      "Mean ± standard deviation over repeated runs; tests with SUT or render errors are counted "
                      "apart and left out of the rates. 'occluded' counts features the frames hid (not "
                      "judged, left out of each test's fitness).")]
    for mode, rows in tables.items():
        thresholds = FAILURE_THRESHOLDS[mode]
        shown = [{"SUT": r["sut"], "algorithm": r["algorithm"], "runs": r["runs"],
                  "tests": mean_std(r["tests mean"], r["tests std"]),
                  "SUT errors": mean_std(r["sut_errors mean"], r["sut_errors std"]),
                  "occluded": mean_std(r["occluded mean"], r["occluded std"]),
                  **{threshold_label(t): mean_std(r[f"{rate_key(t)} mean"], r[f"{rate_key(t)} std"])
                     for t in thresholds}}
                 for r in rows]
        html.append(f"<h3>{esc(mode.upper())}: failure rate (%) by threshold on {esc(METRIC_KEYS[mode])}</h3>")
        columns = (["SUT", "algorithm", "runs", "tests", "SUT errors", "occluded"]
                   + [threshold_label(t) for t in thresholds])
        html.append(table(columns, shown))
        for sut in sorted({r["sut"] for r in rows}):
            series = {r["algorithm"]: ([r[f"{rate_key(t)} mean"] for t in thresholds],
                                       [r[f"{rate_key(t)} std"] for t in thresholds]) for r in rows if r["sut"] == sut}
            html.append(figure(plots.rates_by_threshold(thresholds, series, METRIC_KEYS[mode]),
                               f"failure rate by threshold, {sut} {mode}", f"SUT {sut}, {mode}: mean ± std over runs."))
    stats = comparisons(runs)
    html.append("<h3>Between algorithms: Wilcoxon rank-sum test and Vargha-Delaney A12 on per-run failure rates</h3>")
    html.append(paragraph("A12 > 0.5: algorithm a tends to have the higher failure rate. Magnitude: negligible "
                          "< 0.56 <= small < 0.64 <= medium < 0.71 <= large (on max(A12, 1 - A12)); "
                          "'sample too small' where so few runs cannot show any difference at p < 0.05."))
    shown = [dict(r, threshold=threshold_label(r["threshold"])) for r in stats]
    html.append(table(["sut", "mode", "threshold", "a", "b", "runs_a", "runs_b", "median_a", "median_b", "U", "p",
                       "method", "A12", "magnitude", "note"], shown) if stats
                else paragraph("Only one algorithm per SUT and mode: nothing to compare."))
    flat = [dict(r, mode=mode) for mode, rows in tables.items() for r in rows]
    return Part(section("RQ1: how many failures", *html, anchor="rq1"), {"rq1": flat, "statistics": stats})


# ------------------------------------------------------------------ failures over time
def timeline_part(runs: list[Run]) -> Part:
    html, rows = [], []
    for (sut, mode), members in settings_of(runs).items():
        by_algo: dict[str, list[Run]] = defaultdict(list)
        for run in members:
            by_algo[run.algorithm].append(run)
        tests = {a: band_by_tests(rs) for a, rs in sorted(by_algo.items())}
        horizon = max((r.elapsed(r.records[-1]) for r in members if r.records), default=0.0)
        wall = {a: band_by_time(rs, horizon) for a, rs in sorted(by_algo.items())}
        html.append(figure(plots.bands(tests, "tests", f"{sut} · {mode}"), "cumulative failures against tests"))
        html.append(figure(plots.bands(wall, "wall time (s)", f"{sut} · {mode}"), "cumulative failures against time"))
        for axis, series in (("tests", tests), ("seconds", wall)):
            for algo, band in series.items():
                rows += [{"sut": sut, "mode": mode, "algorithm": algo, "axis": axis, "x": float(x), "mean": float(m),
                          "std": float(s), "runs": int(n)}
                         for x, m, s, n in zip(band.x, band.mean, band.std, band.runs)]
    note = paragraph("Cumulative failures (oracle verdicts), mean over each algorithm's runs with a ±1 standard "
                     "deviation band; against wall time a finished run keeps its final count.")
    return Part(section("Failures over time", note, *html, anchor="timeline"), {"timeline": rows})


# ------------------------------------------------------------------ RQ2 diversity
def diversity_part(runs: list[Run], embedder: Embedder, settings: ReportSettings, suffix: str, title: str,
                   log) -> Part:
    result = measure_diversity(runs, embedder, settings.k, settings.seed, log)
    k = result.clustering.k
    html = [paragraph(_diversity_note(result, embedder, settings)),
            table(["algorithm", "runs", "failures", "coverage", "entropy", "coverage per run", "entropy per run"],
                  [dict(r, **{f"{m} per run": mean_std(r[f"{m} per run mean"], r[f"{m} per run std"], 3)
                              for m in ("coverage", "entropy")}) for r in result.per_algorithm])]
    if k:
        html.append(figure(plots.cluster_map(result.vectors, result.clustering.labels,
                                             [r.algorithm for r, _ in result.items],
                                             "Failing tests: embedding, first two principal components"),
                           "failure clusters map", "Colour: cluster; marker: algorithm."))
        html.append(figure(plots.cluster_counts(result.counts, "Failures per cluster"), "failures per cluster"))
    if result.statistics:
        html.append("<h3>Per-run coverage and entropy between algorithms</h3>")
        html.append(table(["measure", "a", "b", "runs_a", "runs_b", "U", "p", "method", "A12", "magnitude", "note"],
                          result.statistics))
    if result.entropy_gaps:
        html.append("<h3>Entropy difference between algorithms over several clusterings</h3>")
        html.append(paragraph("Mean per-run entropy of a minus b, in k-means clusterings with seeds "
                              f"{settings.seed} to {settings.seed + result.entropy_gaps[0]['clusterings'] - 1}: "
                              "k-means on these embeddings has many near-equal optima, and a difference whose "
                              "sign changes between them is not a finding."))
        html.append(table(["a", "b", "clusterings", "mean", "min", "max", "sign stable"], result.entropy_gaps))
    return Part(section("RQ2: how diverse are the failures" + title, *html, anchor="rq2" + suffix),
                {"diversity" + suffix: result.per_algorithm, "diversity_runs" + suffix: result.per_run,
                 "diversity_statistics" + suffix: result.statistics, "clusters" + suffix: result.assignments(),
                 "entropy_gaps" + suffix: result.entropy_gaps})


def _diversity_note(result: Diversity, embedder: Embedder, settings: ReportSettings) -> str:
    notes = [f"Embedding: {embedder.description}. k-means with k = {result.clustering.k} (requested {settings.k}) "
             f"over the {len(result.items)} failing tests of these runs, seed {settings.seed}. Coverage: share of the "
             "k clusters with at least one of the algorithm's failures; entropy: Shannon entropy of its failures "
             "over the k clusters divided by log k (undefined without failures, 0 with one cluster)."]
    if result.clustering.note:
        notes.append(result.clustering.note + ".")
    if result.skipped:
        notes.append(f"{result.skipped} failing tests have no image file and were left out.")
    return " ".join(notes)
