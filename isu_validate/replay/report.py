"""``report.html`` of ``replay``: the paired counts, failure rates before and after per threshold, the
per-feature table, and galleries of the new and the fixed failures with both answers side by side
(everything the SUTs said is escaped by ``analysis.html``)."""
from __future__ import annotations

from pathlib import Path

from ..analysis.gallery import thumbnail
from ..analysis.html import esc, fmt, page, paragraph, section, stat, table, threshold_label
from ..atomic import write_text
from .compare import FIXED, NEW, PERSISTING, STILL_PASSING, Replayed

GALLERY = 60        # cards per gallery, largest change first
RAW_LIMIT = 1200    # characters of the new SUT's raw output per card
STYLE = "<style>tr.right td{background:#e6f4ea;color:#185c2b;font-weight:600}</style>"


def write_report(path: Path, summary: dict, items: list[Replayed], space) -> None:
    labels = {f.name: f.display_name for f in space.predicted}
    s = summary["settings"]
    sections = [_headline(summary), _rates(summary), _features(summary, labels),
                _gallery("New failures", "new", [i for i in items if i.status(summary["threshold"]) == NEW], labels,
                         "passed in the run, fail now"),
                _gallery("Fixed failures", "fixed", [i for i in items if i.status(summary["threshold"]) == FIXED],
                         labels, "failed in the run, pass now"),
                _gallery("Persisting failures", "persisting",
                         [i for i in items if i.status(summary["threshold"]) == PERSISTING], labels,
                         "failed in the run, fail now too"),
                _problems(summary)]
    version = s["sut_version"]["label"]
    subtitle = (f"run {s['run']} (SUT {s['run_sut']}{_options(s['run_sut_options'])}) replayed against {version}, "
                f"{s['repeats']} repeat(s); space {s['space']}; threshold {threshold_label(summary['threshold'])}")
    write_text(path, page(f"Regression replay: {version}", subtitle, [STYLE] + [x for x in sections if x]))


def _options(options: dict | None) -> str:
    return "".join(f", {k}={v}" for k, v in sorted((options or {}).items()))


def _pct(value) -> str:
    return "–" if value is None else f"{100 * value:.1f}%"


def _headline(s: dict) -> str:
    m = s["mcnemar"]
    cards = [stat("tests with a verdict in the run", s["n_tests"]), stat("replayed", s["n_replayed"]),
             stat("fixed", s[FIXED]), stat("new failures", s[NEW], "bad" if s[NEW] else ""),
             stat("persisting", s[PERSISTING]), stat("still passing", s[STILL_PASSING]),
             stat("McNemar exact p", fmt(m["p"]))]
    if s["sut_errors"] or s["not_replayed"]:
        cards += [stat("SUT errors (not counted)", s["sut_errors"], "warn"),
                  stat("not replayed", s["not_replayed"], "warn")]
    note = paragraph(f"At threshold {threshold_label(s['threshold'])} (a test fails when F_qa < threshold): "
                     f"{s['failures_before']} failures in the run, {s['failures_after']} now, among the "
                     f"{s['n_replayed']} tests replayed with a verdict. McNemar's exact test on the "
                     f"{m['discordant']} discordant pairs ({m['fixed']} fixed, {m['new']} new): p = {fmt(m['p'])}.")
    return section("Paired outcomes", f'<div class="cards">{"".join(cards)}</div>', note, anchor="counts")


def _rates(s: dict) -> str:
    rows = [{"threshold": threshold_label(r["threshold"]), "failures before": r["failures_before"],
             "failures after": r["failures_after"], "rate before": _pct(r["rate_before"]),
             "rate after": _pct(r["rate_after"])} for r in s["rates"]]
    return section("Failure rates before and after", table(list(rows[0]) if rows else [], rows),
                   paragraph("Over the tests replayed with a verdict; F_qa is judged as the run judged it."),
                   anchor="rates")


def _features(s: dict, labels: dict) -> str:
    rows = [{"feature": labels.get(k, k), "judged both times": f["judged"], "right before": f["right_before"],
             "right after": f["right_after"], "became right": f["became_right"], "became wrong": f["became_wrong"]}
            for k, f in sorted(s["per_feature"].items(), key=lambda kv: (-kv[1]["became_wrong"], kv[0]))]
    classes = ["wrong" if f["became wrong"] > f["became right"] else
               "right" if f["became right"] > f["became wrong"] else "" for f in rows]
    return section("Per feature", table(list(rows[0]) if rows else [], rows, classes),
                   paragraph("Occluded features are left out, as the run left them out."), anchor="features")


def _gallery(title: str, anchor: str, items: list[Replayed], labels: dict, what: str) -> str:
    items = sorted(items, key=lambda i: (-abs(i.after.f_qa - i.before.f_qa), i.record.test_id))
    shown = items[:GALLERY]
    head = paragraph(f"{len(items)} tests {what}; showing {len(shown)}, largest change first. Rows that became "
                     "wrong are red, rows that became right green.")
    cards = "".join(_card(i, labels) for i in shown)
    return section(f"{title} ({len(items)})", head, f'<div class="gallery">{cards}</div>' if cards else "",
                   anchor=anchor)


def _card(item: Replayed, labels: dict) -> str:
    uri = thumbnail(item.image or None)
    image = (f'<img src="{esc(uri)}" alt="{esc(item.record.test_id)}" loading="eager">' if uri
             else '<p class="note">(image missing)</p>')
    title = (f"<b>{esc(item.record.test_id)}</b> · F_qa {esc(fmt(item.before.f_qa))} → {esc(fmt(item.after.f_qa))}"
             + (" · rendered again" if item.rerendered else ""))
    rows, classes = [], []
    for key, feature in item.after.features.items():
        rows.append({"feature": labels.get(key, key), "truth": feature["truth"],
                     "run": _answer(item.before, key), "now": _answer(item.after, key)})
        classes.append("wrong" if key in item.wrong else "right" if key in item.right else "")
    raw = item.after.raw if len(item.after.raw) <= RAW_LIMIT else item.after.raw[:RAW_LIMIT] + " …"
    details = f"<details><summary>new SUT output</summary><pre>{esc(raw)}</pre></details>" if raw else ""
    return f'<div class="card">{image}<div>{title}</div>{table(["feature", "truth", "run", "now"], rows, classes)}' \
           f"{details}</div>"


def _answer(judged, key: str) -> str:
    feature = judged.features.get(key) or {}
    answer = feature.get("answer")
    shown = "(no answer)" if answer is None else str(answer)
    return f"{shown} (occluded)" if feature.get("status") == "occluded" else shown


def _problems(s: dict) -> str:
    if not s["problems"]:
        return ""
    items = "".join(f"<li>{esc(p)}</li>" for p in s["problems"])
    return section("Problems", f"<ul>{items}</ul>", anchor="problems")
