"""``report.html`` of ``transfer``: per feature the real sets beside the renders, the confusion matrices, KID,
and a gallery of the wrong answers on real photos (most confident first). Everything the SUT said and every
label of a set is escaped by ``analysis.html``."""
from __future__ import annotations

from pathlib import Path

from ..analysis.gallery import thumbnail
from ..analysis.html import esc, fmt, page, paragraph, section, table
from ..atomic import write_text
from .scores import positive_class

GALLERY = 24     # wrong answers shown per set and feature


def write_report(path: Path, summary: dict, answered: dict[str, list[dict]], space) -> None:
    sections = [_overview(summary), _realism(summary), _zero_shot(summary)]
    for feature in summary["features"]:
        sections.append(_feature(summary, feature, space))
        positive = positive_class(space.features[feature].options)
        for name, records in answered.items():
            sections.append(_gallery(name, feature, records, positive))
    s = summary["sut"]
    subtitle = (f"SUT {s['spec']} ({s['version']}); real sets: {', '.join(summary['sets'])}; renders: "
                f"{(summary['renders'] or {}).get('source', 'none')}")
    write_text(path, page("Sim-to-real transfer", subtitle, [x for x in sections if x]))


def _ci(ci) -> str:
    return f"{ci[0]:.2f}-{ci[1]:.2f}" if ci else "–"


def _row(where: str, sc: dict) -> dict:
    base = sc["majority_baseline"]
    return {"photos": where, "n": sc["n"], "unanswered": sc["unanswered"],
            "accuracy": fmt(sc["accuracy"]), "95% CI": _ci(sc["accuracy_ci95"]),
            "balanced accuracy": fmt(sc["balanced_accuracy"]), "BA 95% CI": _ci(sc["balanced_accuracy_ci95"]),
            "majority class (acc.)": f"{base['class']} ({base['accuracy']:.2f})", "AUC": fmt(sc["auc"]),
            "median P(positive)": fmt(sc["p_positive_median"]),
            "answers given": ", ".join(f"{k} {v}" for k, v in sc["said_counts"].items())}


def _overview(summary: dict) -> str:
    rows = []
    for name, s in summary["sets"].items():
        rows.append({"set": name, "layout": s["layout"], "photos read": s["photos"],
                     "with a mapped label": s["labelled_photos"], "no mapped label": s["unanswered_photos"],
                     "left out for conflicts": sum(s["conflicts"].values()),
                     "labels the map ignores": ", ".join(f"{k} ({v})" for k, v in s["unmapped_labels"].items()),
                     "label map": s["label_map"]})
    notes = [paragraph(f"{name}: {note}") for name, s in summary["sets"].items() for note in s["notes"]]
    return section("Real photo sets", table(list(rows[0]), rows), *notes, anchor="sets")


def _realism(summary: dict) -> str:
    if not summary.get("realism"):
        return section("Distance to the renders", paragraph("No render images were given (--renders): no KID/FID."),
                       anchor="realism")
    rows = [{"real set": name, "n real": r["n_real"], "n renders": r["n_renders"], "KID": f"{r['kid_mean']:.4f}",
             "KID std": f"{r['kid_std']:.4f}", "FID": f"{r['fid']:.1f}"} for name, r in summary["realism"].items()]
    warnings = sorted({w for r in summary["realism"].values() for w in r["warnings"]})
    return section("Distance to the renders (Inception features)", table(list(rows[0]), rows),
                   *[paragraph(w) for w in warnings], anchor="realism")


def _zero_shot(summary: dict) -> str:
    if not summary.get("zero_shot"):
        return ""
    rows = []
    for name, features in summary["zero_shot"].items():
        for feature, r in features.items():
            rows.append(_zero_shot_row(name, feature, f"{r['object']} (ImageNet classes)", r, r))
            seen = r.get("detector")
            if seen and "unavailable" not in seen:
                rows.append(_zero_shot_row(name, feature, f"{seen['class']} ({seen['name']})", seen, r))
    return section("Does the object read as itself? (zero-shot, no training)", table(list(rows[0]), rows),
                   paragraph("The largest summed ImageNet probability of the object's classes over 25 crops of each "
                             "frame, against its label: an AUC the real photos reach and the renders do not says the "
                             "rendered object does not look like the real one to a photo-trained model. Where a "
                             "second row names a detector, it is the built-in COCO detector's best score for the "
                             "class over the frame and its 2x2 tiles: on the real photos, what a detector alone does "
                             "with nothing learnt from renders."),
                   anchor="zero-shot")


def _zero_shot_row(name: str, feature: str, scorer: str, scores: dict, counts: dict) -> dict:
    return {"frames": name, "feature": feature, "scored as": scorer, "AUC": fmt(scores["auc"]),
            "with": counts["n_positive"], "without": counts["n_negative"],
            "median score with": fmt(scores["median_positive"]), "median score without": fmt(scores["median_negative"])}


def _feature(summary: dict, feature: str, space) -> str:
    rows = [_row(f"real: {name}", s["scores"][feature]) for name, s in summary["sets"].items()
            if feature in s["scores"]]
    renders = summary.get("renders")
    if renders and feature in renders["scores"]:
        rows.append(_row(f"renders: {renders['source']}", renders["scores"][feature]))
    matrices = [_confusion(title, sc[feature]) for title, sc in
                [(f"real: {n}", s["scores"]) for n, s in summary["sets"].items()]
                + ([("renders", renders["scores"])] if renders else []) if feature in sc]
    by_label = [_by_label(name, s["scores"][feature]) for name, s in summary["sets"].items() if feature in s["scores"]]
    question = space.features[feature].question
    return section(f"{feature}: {question}", table(list(rows[0]), rows) if rows else paragraph("(no photo)"),
                   *matrices, *by_label, anchor=f"f-{feature}")


def _by_label(name: str, sc: dict) -> str:
    """What the SUT said per label of the real set (class folder, box class): where its false answers come from."""
    if not sc.get("said_by_label"):
        return ""
    def counts(c):
        return ", ".join(f"{k} {v}" for k, v in c.items())
    rows = [{"label": label, "photos": e["n"], "true answers": counts(e["truth"]), "said": counts(e["said"]),
             "share said positive": fmt(e["said_positive"]),
             "AUC against the other side": fmt(e.get("auc_against_other_side"))}
            for label, e in sc["said_by_label"].items()]
    return f"<h3>real: {esc(name)}: answers per label of the set</h3>" + table(list(rows[0]), rows)


def _confusion(title: str, sc: dict) -> str:
    if not sc.get("confusion"):
        return ""
    labels = sc["confusion"]["labels"]
    rows = [{"truth \\ said": truth, **dict(zip(labels, counts, strict=True))}
            for truth, counts in sc["confusion"]["rows"].items()]
    return f"<h3>{esc(title)}: confusion matrix</h3>" + table(["truth \\ said", *labels], rows)


def _gallery(name: str, feature: str, records: list[dict], positive: str) -> str:
    wrong = [r for r in records if feature in r["truth"] and r["said"].get(feature) not in (None, r["truth"][feature])]
    if not wrong:
        return ""
    def confidence(r):   # the most confident wrong answers first
        p = (r.get("p") or {}).get(feature) or {}
        return -p.get(r["said"][feature], 0.0)
    cards = []
    for r in sorted(wrong, key=confidence)[:GALLERY]:
        uri = thumbnail(r["image"])
        p = (r.get("p") or {}).get(feature)
        said = f"{r['said'][feature]}" + (f" (P({positive}) {p.get(positive, 0):.2f})" if p else "")
        img = f'<img src="{esc(uri)}" alt="{esc(r["name"])}">' if uri else paragraph("(image unreadable)")
        cards.append(f'<div class="card">{img}<table><tr><th>photo</th><td>{esc(r["name"])}</td></tr>'
                     f'<tr><th>truth</th><td>{esc(r["truth"][feature])}</td></tr>'
                     f'<tr class="wrong"><th>said</th><td>{esc(said)}</td></tr></table></div>')
    return section(f"Wrong answers on {name}: {feature} ({len(wrong)}; {min(len(wrong), GALLERY)} shown)",
                   f'<div class="gallery">{"".join(cards)}</div>', anchor=f"g-{name}-{feature}")
