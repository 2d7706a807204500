"""The single-run report the ``run`` command writes at its end (``RUN/report.html``):
summary, failure rates at thresholds, tests over time, per-feature failure analysis,
failure regions, the failing scenes, and SUT errors apart from failures.  No image
embeddings here, so it takes seconds."""
from __future__ import annotations

from pathlib import Path

from ..atomic import write_text
from . import plots
from .html import figure, page, paragraph, percent, section, stat, table, threshold_label
from .rq1 import rate_key, run_rates
from .runs import Run, load_run
from .sections import errors, failure_gallery, feature_analysis, regions
from .thresholds import FAIL_RULES, fails_at

REPORT_FILE = "report.html"
GALLERY_LIMIT = 48


def write_run_report(run_dir: Path, gallery_limit: int = GALLERY_LIMIT) -> Path:
    run = load_run(run_dir)
    html = render_run_report(run, gallery_limit)
    return write_text(Path(run_dir) / REPORT_FILE, html)  # a reader never sees half a report


def render_run_report(run: Run, gallery_limit: int = GALLERY_LIMIT) -> str:
    parts = [summary(run), thresholds_section(run), timeline_section(run),
             feature_analysis([run]).html, regions([run]).html,
             failure_gallery([run], gallery_limit).html, errors([run]).html]
    subtitle = f"{run.algorithm} seed {run.seed} · SUT {run.sut} · {run.mode} · {run.path.resolve()}"
    return page(f"isu-validate run report: {run.name}", subtitle, parts)


def summary(run: Run) -> str:
    row = run_rates(run)
    threshold = run.oracle_threshold
    oracle = "failures (oracle" + ("" if threshold is None else f" at {threshold_label(threshold)}") + ")"
    rate = 100.0 * row["failures"] / row["with_verdict"] if row["with_verdict"] else float("nan")
    wall = max((run.elapsed(r) for r in run.records), default=0.0)
    cards = "".join([stat("tests", row["tests"]), stat("with a verdict", row["with_verdict"]),
                     stat(oracle, row["failures"], "bad" if row["failures"] else ""),
                     stat("failure rate (%)", percent(rate)),
                     stat("SUT errors", row["sut_errors"], "warn" if row["sut_errors"] else ""),
                     stat("render errors", row["render_errors"], "warn" if row["render_errors"] else ""),
                     stat("occluded features (not judged)", row["occluded"]),
                     stat("wall time (s)", wall)])
    config = {k: v for k, v in run.config.items() if k != "pipeline"}
    settings = [{"setting": k, "value": v} for k, v in {**config, **run.pipeline}.items()]
    note = "" if run.records else paragraph("This run has no evaluated tests yet.")
    return section("Summary", f'<div class="cards">{cards}</div>', note,
                   "<details><summary>configuration</summary>" + table(["setting", "value"], settings) + "</details>",
                   anchor="summary")


def thresholds_section(run: Run) -> str:
    row = run_rates(run)
    values = [run.metric(r) for r in run.valid]
    rows = [{"threshold": threshold_label(t), "failing": sum(fails_at(run.mode, v, t) for v in values),
             "failure rate (%)": percent(row[rate_key(t)])} for t in run.thresholds]
    text = (f"A test fails at threshold t when {run.metric_key} {FAIL_RULES.get(run.mode, '<')} t; rates over the "
            f"{len(values)} tests with a verdict (SUT and render errors are left out).")
    return section("Failure rates at thresholds", paragraph(text),
                   table(["threshold", "failing", "failure rate (%)"], rows), anchor="thresholds")


def timeline_section(run: Run) -> str:
    if not run.records:
        return section("Tests over time", paragraph("No tests."), anchor="timeline")
    records = run.records
    chart = plots.fitness_over_tests([run.metric(r) for r in records], [r.failed and not r.errored for r in records],
                                     [r.errored for r in records], run.metric_key, run.oracle_threshold)
    return section("Tests over time", figure(chart, "fitness of each test over time",
                                             "Fitness per test in evaluation order; purple: cumulative failures."),
                   anchor="timeline")
