"""``report.html`` of ``agree``: the paper's heatmap (features by samples, coloured by category), the
per-feature table sorted by disagreement, and sim / real / nst side by side for the disagreeing samples
with the SUT's answers (escaped, like everything a SUT said). When any "real" frame is a stand-in render,
a banner at the top says how many, with the agreement on each kind apart."""
from __future__ import annotations

from pathlib import Path

from capture.sidecar import banner

from ..analysis.gallery import thumbnail
from ..analysis.html import esc, page, paragraph, section, stat, table
from ..atomic import write_text
from ..space import SceneSpace
from .compare import BOTH_CORRECT, BOTH_WRONG, NOT_COMPARED, NST_ONLY, REAL_ONLY, SIM_ONLY

NAMES = {BOTH_CORRECT: "both correct", BOTH_WRONG: "both wrong", SIM_ONLY: "correct only on sim",
         NST_ONLY: "correct only on nst", REAL_ONLY: "correct only on real", "not compared": "not compared"}
RAW_LIMIT = 1200


def write_report(path: Path, summary: dict, rows: list[dict], answered: list, space: SceneSpace) -> None:
    labels = {f.name: f.display_name for f in space.predicted}
    sections = [_stand_in(summary), _headline(summary), _heatmaps(rows, labels), _features(summary, labels),
                _disagreements(rows, answered, labels), _validity(summary), _realism(summary),
                _problems(summary), _method(summary)]
    subtitle = (f"SUT {summary['settings']['sut']}, {summary['settings']['repeats']} repeats (per-feature majority), "
                f"space {summary['settings']['space']}, pairs {summary['settings']['pairs']}")
    write_text(path, page("Sim/real agreement", subtitle, [s for s in sections if s]))


def _pct(value) -> str:
    return "–" if value is None else f"{100 * value:.1f}%"


def _stand_in(s: dict) -> str:
    """The banner: how many 'real' frames are stand-in renders, and (a mixed folder) the agreement on each."""
    text = banner(s["stand_in_frames"], s["real_frames"])
    if not text:
        return ""
    cards = ""
    if s["real_frames"]:
        by = s["by_provenance"]
        cards = '<div class="cards">' + "".join(
            stat(f"agreement on {name} ({by[kind]['frames']} frames, {by[kind]['compared']} features)",
                 _pct(by[kind]["agreement_rate"]), "warn" if kind == "stand_in" else "")
            for kind, name in (("real", "real captures"), ("stand_in", "stand-ins"))) + "</div>"
    return (f'<section id="stand-in" style="border:3px solid #b3261e;background:#fdecea">'
            f'<h2>Stand-in frames: not a real-world result</h2><p><b>{esc(text)}</b></p>{cards}</section>')


def _headline(s: dict) -> str:
    cards = [stat("agreement (sim vs real)", _pct(s["agreement_rate"])),
             stat("samples compared", s["n_samples"]), stat("features compared", s["n_features_compared"]),
             stat("both correct", s[BOTH_CORRECT]), stat("both wrong", s[BOTH_WRONG]),
             stat("correct only on sim", s[SIM_ONLY], "warn"), stat("correct only on real", s[REAL_ONLY], "warn")]
    if "agreement_rate_nst" in s:
        change = s["nst_change"]["change"]
        cards += [stat("agreement (nst vs real)", _pct(s["agreement_rate_nst"])),
                  stat("change with style transfer", "–" if change is None else f"{100 * change:+.1f} points")]
    if s.get("fid") is not None:
        cards += [stat("FID sim/real", s["fid"]), stat("KID sim/real", f"{s['kid_mean']:.4f} ± {s['kid_std']:.4f}")]
    if s.get("fid_nst") is not None:
        cards += [stat("FID nst/real", s["fid_nst"])]
    if s["validity"]["rate"] is not None:
        cards.append(stat("reconstruction validity", _pct(s["validity"]["rate"])))
    nc = s["not_compared"]
    note = (f"Not compared: {nc['occluded']} occluded, {nc['unanswered']} unanswered, {nc['sut_error']} with a SUT "
            f"error. {s['n_frames']} real frames, each compared on its own"
            + (f" ({s['stand_in_frames']} of them stand-in renders)." if s["stand_in_frames"] else "."))
    return section("Summary", f'<div class="cards">{"".join(cards)}</div>', paragraph(note), anchor="summary")


def _heatmaps(rows: list[dict], labels: dict) -> str:
    if not rows:
        return section("Heatmap", paragraph("Nothing was compared."), anchor="heatmap")
    from .heatmap import heatmap
    parts = [heatmap(rows, "category", labels, "SUT on sim vs real, per feature and sample")]
    if any(r["nst_category"] for r in rows):
        parts.append(heatmap(rows, "nst_category", labels, "SUT on nst (style transfer) vs real"))
    return section("Heatmap", *[f'<figure><img src="{esc(u)}" alt="agreement heatmap"></figure>' for u in parts],
                   paragraph("Columns are samples (sample/frame where a sample has several real frames); white: "
                             "the feature is not in that scene."), anchor="heatmap")


def _features(s: dict, labels: dict) -> str:
    nst = s.get("per_feature_nst", {})
    out = []
    for feature, c in s["per_feature"].items():
        n = nst.get(feature, {})
        out.append({"feature": labels.get(feature, feature), "compared": c["compared"],
                    "agreement": _pct(c["agreement_rate"]), "both correct": c[BOTH_CORRECT],
                    "both wrong": c[BOTH_WRONG], "only sim": c[SIM_ONLY], "only real": c[REAL_ONLY],
                    "not compared": sum(c[k] for k in NOT_COMPARED),
                    "agreement nst": _pct(n.get("agreement_rate")) if n else "–", "_sort": c["agreement_rate"]})
    out.sort(key=lambda r: (2.0 if r["_sort"] is None else r["_sort"], r["feature"]))
    cols = ["feature", "compared", "agreement", "both correct", "both wrong", "only sim", "only real",
            "not compared"] + (["agreement nst"] if nst else [])
    return section("Per feature, most disagreement first", table(cols, out), anchor="features")


def _disagreements(rows: list[dict], answered: list, labels: dict) -> str:
    by_sample = {a.sample.name: a for a in answered}
    disagreeing = sorted({r["sample"] for r in rows if r["category"] in (SIM_ONLY, REAL_ONLY)
                          or r["nst_category"] in (NST_ONLY, REAL_ONLY)})
    if not disagreeing:
        return section("Disagreeing samples", paragraph("No sample disagrees."), anchor="disagreements")
    cards = [_card(by_sample[name], [r for r in rows if r["sample"] == name], labels) for name in disagreeing]
    return section("Disagreeing samples", paragraph("Render, photo(s) and stylised render side by side; "
                                                   "rows where sim and real disagree are highlighted."),
                   f'<div class="gallery">{"".join(cards)}</div>', anchor="disagreements")


def _card(answers, rows: list[dict], labels: dict) -> str:
    sample = answers.sample
    frames = sorted({r["frame"] for r in rows})
    images = [("sim", sample.sim)] + [(f"real/{f}", sample.real_dir / f) for f in frames]
    if answers.nst is not None:
        images.append(("nst", sample.nst))
    thumbs = "".join(_thumb(name, path) for name, path in images)
    table_rows, classes = [], []
    for r in rows:
        table_rows.append({"frame": r["frame"], "feature": labels.get(r["feature"], r["feature"]), "truth": r["truth"],
                           "sim": r["sim"], "real": r["real"], "nst": r["nst"],
                           "category": NAMES.get(r["category"], r["category"])})
        classes.append("wrong" if r["category"] in (SIM_ONLY, REAL_ONLY) else "")
    cols = ["frame", "feature", "truth", "sim", "real"] + (["nst"] if answers.nst else []) + ["category"]
    raws = [("sim", answers.sim)] + [(f"real/{f}", answers.real.get(f)) for f in frames] + [("nst", answers.nst)]
    raw = "".join(f"<details><summary>SUT output on {esc(name)}</summary><pre>{esc(_cut(a.raw))}</pre></details>"
                  for name, a in raws if a is not None and a.raw)
    return (f'<div class="card" style="width:auto;max-width:1000px"><b>{esc(sample.name)}</b>'
            f'<div style="display:flex;gap:6px;flex-wrap:wrap">{thumbs}</div>'
            f"{table(cols, table_rows, classes)}{raw}</div>")


def _thumb(name: str, path: Path) -> str:
    uri = thumbnail(path)
    body = f'<img src="{esc(uri)}" alt="{esc(name)}" style="width:240px">' if uri else '<p class="note">(missing)</p>'
    return f'<figure style="margin:0">{body}<figcaption>{esc(name)}</figcaption></figure>'


def _cut(text: str) -> str:
    return text if len(text) <= RAW_LIMIT else text[:RAW_LIMIT] + " …"


def _validity(s: dict) -> str:
    v = s["validity"]
    rows = [{"verdict": k, "pairs": v[k]} for k in ("valid", "invalid", "tied", "unvoted")]
    text = (f"Annotators ({', '.join(v['annotators']) or 'none yet'}) said per pair whether the photo shows the "
            "same scenario as the render (isu-validate agree votes); the majority decides. Pairs voted invalid "
            f"are left out of the agreement unless --include-invalid: {', '.join(v['invalid_samples']) or 'none'}. "
            f"Tied pairs are kept and flagged: {', '.join(v['tied_samples']) or 'none'}.")
    return section("Reconstruction validity", paragraph(f"Validity rate: {_pct(v['rate'])}."), paragraph(text),
                   table(["verdict", "pairs"], rows), anchor="validity")


def _realism(s: dict) -> str:
    r = s["realism"]
    if "skipped" in r:
        return section("Domain gap (FID/KID)", paragraph(f"Not computed: {r['skipped']}"), anchor="realism")
    rows, notes = [], []
    apart = {f"{name} ({kind.replace('_', '-')} frames)": v for kind, gap in s.get("realism_by_provenance", {}).items()
             for name, v in gap.items() if name != "skipped"}
    for name, v in {**r, **apart}.items():
        n = v.get("n_sim", v.get("n_nst"))
        rows.append({"sets": name.replace("_", " "), "FID": v["fid"], "KID mean": v["kid_mean"],
                     "KID std": v["kid_std"], "n": f"{n} / {v['n_real']}",
                     "KID subset": v["settings"]["kid_subset_size"], "subsets": v["settings"]["kid_subsets"]})
        notes += [w for w in v["warnings"] if w not in notes]
    first = next(iter(r.values()))["settings"]
    setting = (f"Inception {first.get('model', '')}, resize {first.get('resize_filter')} to {first.get('input_size')}, "
               f"seed {first.get('seed')}; the same numbers as `isu-validate realism` on these sets.")
    return section("Domain gap (FID/KID)", table(["sets", "FID", "KID mean", "KID std", "n", "KID subset", "subsets"],
                                                  rows), paragraph(setting), *[paragraph(w) for w in notes],
                   anchor="realism")


def _problems(s: dict) -> str:
    if not s["problems"]:
        return ""
    items = "".join(f"<li>{esc(p)}</li>" for p in s["problems"])
    return section(f"Problems ({len(s['problems'])})", f'<ul class="note">{items}</ul>', anchor="problems")


def _method(s: dict) -> str:
    text = ("For each sample, real frame and predicted feature active in the scene, the SUT's answer on the render "
            "and on the photo is correct or not (equal to the truth, as the run's judge decides). Agreement = (both "
            "correct + both wrong) / compared, as in the paper; both wrong counts even when the wrong answers differ. "
            "Several real frames of one sample are each compared on their own. Occluded features (the render label), "
            "unanswered features and SUT errors are not compared and are counted apart. "
            f"The SUT was asked {s['settings']['repeats']} times per image; the per-feature majority is its answer. "
            "The nst change is measured on the rows compared both ways.")
    return section("How the numbers are made", paragraph(text), anchor="method")

