"""Report sections shared by the single-run and the multi-run report.  Each returns a
``Part``: its HTML and the tables behind it (written as CSV/JSON by the caller)."""
from __future__ import annotations

from dataclasses import dataclass, field

from . import plots
from .failures import feature_errors, value_failure_rates
from .gallery import gallery, gallery_rows
from .html import figure, fmt, paragraph, section, table
from .regions import MAX_DEPTH, failure_regions
from .runs import Run

ERROR_TEXT_LIMIT = 300


@dataclass
class Part:
    html: str
    tables: dict[str, list[dict]] = field(default_factory=dict)


def failing(runs: list[Run]):
    return [(run, record) for run in runs for record in run.failures]


def feature_analysis(runs: list[Run], title: str = "Failure analysis per feature", suffix: str = "") -> Part:
    rows, pairs = feature_errors(runs)
    values = value_failure_rates(runs)
    parts = []
    if rows:
        parts.append(paragraph("How often each question was answered wrong (tests with a verdict), "
                               "and in which direction. 'occluded' counts the times the frame hid the "
                               "feature: those answers were not judged, and 'asked' and the rates leave "
                               "them out."))
        parts.append(table(["feature", "asked", "occluded", "wrong", "wrong_rate", "most_common_error"], rows))
        if any(r["wrong"] for r in rows):
            shown = [r for r in rows if r["wrong"]]
            chart = plots.horizontal_bars([r["feature"] for r in shown], [r["wrong_rate"] for r in shown],
                                          "share answered wrong", "Wrong answers per feature")
            parts.append(figure(chart, "wrong answers per feature"))
        parts.append("<h3>Wrong answers: truth answered as</h3>"
                     + table(["feature", "truth", "answer", "count"], pairs))
    else:
        parts.append(paragraph("No per-question answers (captioning, or no test with a verdict)."))
    top = sorted((v for v in values if v["tests"] >= 3), key=lambda v: -v["failure_rate"])[:12]
    parts.append("<h3>Feature values with the highest failure rate (at least 3 tests)</h3>"
                 + table(["feature", "value", "tests", "failing", "failure_rate"], top))
    parts.append("<details><summary>all feature values</summary>"
                 + table(["feature", "value", "tests", "failing", "failure_rate"], values) + "</details>")
    return Part(section(title, *parts, anchor="features" + suffix),
                {"feature_errors" + suffix: rows, "confusions" + suffix: pairs, "feature_values" + suffix: values})


def regions(runs: list[Run], title: str = "Failure regions", suffix: str = "") -> Part:
    tests = [(run, r) for run in runs for r in run.valid]
    if not tests:
        return Part(section(title, paragraph("No tests with a verdict."), anchor="regions" + suffix),
                    {"regions" + suffix: []})
    rules = failure_regions(runs[0].space, [r.canonical for _, r in tests], [r.failed for _, r in tests])
    explain = (f"Leaves of a decision tree (depth <= {MAX_DEPTH}) over the scene features where most tests fail; "
               "'failing of tests' counts the tests the rule covers.")
    if not rules:
        body = paragraph("No region: " + ("no failures." if not any(r.failed for _, r in tests)
                                          else "every test failed, or too few tests to split."))
    else:
        shown = [dict(r, **{"failing of tests": f"{r['failing']} of {r['tests']}"}) for r in rules]
        body = table(["rule", "failing of tests", "precision", "share_of_failures"], shown)
    return Part(section(title, paragraph(explain), body, anchor="regions" + suffix), {"regions" + suffix: rules})


def failure_gallery(runs: list[Run], limit: int, clusters: dict | None = None) -> Part:
    items = failing(runs)
    return Part(section("Failing scenes", gallery(items, limit, clusters), anchor="gallery"),
                {"failures": gallery_rows(items)})


def errors(runs: list[Run]) -> Part:
    """SUT and render errors: not failures, listed apart."""
    rows = [{"run": run.name, "test_id": r.test_id, "kind": "SUT" if r.sut_error else "render",
             "error": _clip(r.sut_error or r.render_error or "")}
            for run in runs for r in run.records if r.errored]
    note = ("Tests without a verdict: the SUT or the renderer failed. They are not counted as failures "
            f"and are left out of the failure rates. {len(rows)} in total.")
    shown = rows[:200]
    more = paragraph(f"(first 200 of {len(rows)}; all in sut_errors.csv)") if len(rows) > 200 else ""
    return Part(section("SUT and render errors", paragraph(note), table(["run", "test_id", "kind", "error"], shown),
                        more, anchor="errors"), {"sut_errors": rows})


def _clip(text: str) -> str:
    return text if len(text) <= ERROR_TEXT_LIMIT else text[:ERROR_TEXT_LIMIT] + " …"


def mean_std(mean: float, std: float, digits: int = 1) -> str:
    """'55.8 ± 1.2'; the mean alone when there is no std (one run); an en dash for no value."""
    if mean != mean:
        return fmt(mean)
    return f"{mean:.{digits}f}" + (f" ± {std:.{digits}f}" if std == std else "")
