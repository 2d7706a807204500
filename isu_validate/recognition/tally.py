"""Rates per feature from the frames' records: n, hits, a Wilson 95% interval, split by kind of frame
(render, real, stand-in), preset and the scene's light; occluded features are counted apart."""
from __future__ import annotations

from collections import Counter, defaultdict

from .expression import LABELS
from .frames import KINDS, LIGHTS

Z95 = 1.959963984540054


def wilson(hits: int, n: int, z: float = Z95) -> tuple[float, float] | None:
    """Wilson score interval of a binomial rate (None for n = 0), through scipy's ``binomtest``."""
    if n <= 0:
        return None
    from scipy.stats import binomtest
    from scipy.stats import norm

    ci = binomtest(hits, n).proportion_ci(confidence_level=2 * norm.cdf(z) - 1, method="wilson")
    return max(0.0, float(ci.low)), min(1.0, float(ci.high))


def _is(feature: str, emotion: str | None = None):
    def applies(item) -> bool:
        return item["feature"] == feature and (emotion is None or item.get("emotion") == emotion)
    return applies


def _read_as(emotion: str):
    def hit(item) -> bool | None:
        e = item.get("expression")
        return None if e is None else (e["read"] == "happy") == (emotion == "HAPPY")
    return hit


# measure -> (the items it is about, hit(visible item): True/False, None when the item could not be read)
MEASURES = {
    "face found": (_is("face"), lambda it: it["found"]),
    "HAPPY read happy": (_is("face", "HAPPY"), _read_as("HAPPY")),
    "SERIOUS read not happy": (_is("face", "SERIOUS"), _read_as("SERIOUS")),
    # any face, its expression unlabelled (a real photograph): how often it reads happy, beside the renders'
    "any face read happy": (_is("face"), lambda it: it["expression"]["read"] == "happy" if it.get("expression")
                            else None),
    "phone top-1": (_is("phone"), lambda it: it["top1"]),
    "phone top-5": (_is("phone"), lambda it: it["top5"]),
    "bottle top-1": (_is("bottle"), lambda it: it["top1"]),
    "bottle top-5": (_is("bottle"), lambda it: it["top5"]),
    # the same things turned upright (where the render label says where their top points)
    "phone top-5 upright": (_is("phone"), lambda it: it["upright"]["top5"] if "upright" in it else None),
    "bottle top-5 upright": (_is("bottle"), lambda it: it["upright"]["top5"] if "upright" in it else None),
}
FEATURE = {m: m.split()[0] if m.split()[0] in ("phone", "bottle") else "face" for m in MEASURES}
SPLITS = ("preset", *LIGHTS, "light")


def _groups(record: dict) -> list[tuple[str, str]]:
    light = "/".join(f"{record[f]}" for f in LIGHTS)
    return [("all", "all"), ("preset", str(record["preset"])),
            *[(f, str(record[f])) for f in LIGHTS], ("light", light)]


def rows(records: list[dict]) -> list[dict]:
    """One row per (measure, kind, split, value) with frames in it."""
    counts = defaultdict(lambda: [0, 0, 0])   # hits, n, occluded
    for record in records:
        for item in record["items"]:
            for measure, (applies, hit) in MEASURES.items():
                if not applies(item):
                    continue
                h = None if item["status"] == "occluded" else hit(item)
                if h is None and item["status"] != "occluded":   # visible but not read this way: no row
                    continue
                for split, value in _groups(record):
                    c = counts[(measure, record["kind"], split, value)]
                    if item["status"] == "occluded":
                        c[2] += 1
                    elif h is not None:
                        c[0] += int(h)
                        c[1] += 1
    return [_row(key, *c) for key, c in sorted(counts.items(), key=_order)]


def _order(entry):
    (measure, kind, split, value), _ = entry
    return (list(MEASURES).index(measure), KINDS.index(kind) if kind in KINDS else 9,
            ("all", *SPLITS).index(split), value)


def _row(key, hits, n, occluded) -> dict:
    measure, kind, split, value = key
    ci = wilson(hits, n)
    return {"measure": measure, "feature": FEATURE[measure], "kind": kind, "split": split, "value": value,
            "n": n, "hits": hits, "rate": hits / n if n else None,
            "ci95": [round(ci[0], 4), round(ci[1], 4)] if ci else None, "occluded": occluded}


def expression_summary(records: list[dict]) -> dict:
    """Per kind: FER's top read per true expression, its mean distribution, and the AUC of P(happy)
    separating HAPPY from SERIOUS drivers (does it rank them even where the top class is wrong?)."""
    out = {}
    for kind in sorted({r["kind"] for r in records}, key=lambda k: KINDS.index(k) if k in KINDS else 9):
        reads = [i["expression"] for r in records if r["kind"] == kind for i in r["items"] if i.get("expression")]
        by_truth = defaultdict(list)
        for e in reads:
            by_truth[e["truth"]].append(e)
        out[kind] = {
            "top_read": {t: dict(Counter(e["read"] for e in es).most_common()) for t, es in by_truth.items()},
            "mean_probs": {t: {c: round(sum(e["probs"][c] for e in es) / len(es), 4) for c in LABELS}
                           for t, es in by_truth.items()},
            "auc_happy": auc([e["p_happy"] for e in by_truth.get("HAPPY", [])],
                             [e["p_happy"] for e in by_truth.get("SERIOUS", [])]),
        }
    return out


def auc(positives: list[float], negatives: list[float]) -> float | None:
    """P(a positive scores above a negative), ties half (Mann-Whitney); None without both."""
    if not positives or not negatives:
        return None
    import numpy as np

    # per positive: the negatives below it, and half of those equal (sorted once: n log n, not n x m)
    below = np.sort(np.asarray(negatives, dtype=float))
    p = np.asarray(positives, dtype=float)
    less, not_more = np.searchsorted(below, p, side="left"), np.searchsorted(below, p, side="right")
    wins = float((less + 0.5 * (not_more - less)).sum())
    return round(wins / (len(positives) * len(negatives)), 4)


def face_sizes(records: list[dict]) -> dict:
    """Median detected face width (px) per kind and preset, and of the rendered head's box."""
    sizes = defaultdict(lambda: {"detected": [], "head_box": []})
    for r in records:
        for i in r["items"]:
            if i["feature"] == "face" and i["status"] == "visible":
                s = sizes[f"{r['kind']}/{r['preset']}"]
                if i.get("width_px"):
                    s["detected"].append(i["width_px"])
                if i.get("truth_width_px"):
                    s["head_box"].append(i["truth_width_px"])
    return {k: {name: _median(v) for name, v in s.items()} for k, s in sizes.items()}


def _median(values):
    if not values:
        return None
    v = sorted(values)
    return float(v[len(v) // 2]) if len(v) % 2 else (v[len(v) // 2 - 1] + v[len(v) // 2]) / 2


def object_summary(records: list[dict]) -> dict:
    """Per kind and object: the top-1 classes read, and which plausible class made each top-5 hit (a rate
    carried by one loose class, "hand-held computer" say, reads differently from one of "cellular telephone")."""
    from .objects import PLAUSIBLE

    out = defaultdict(dict)
    for kind in sorted({r["kind"] for r in records}):
        for obj, plausible in PLAUSIBLE.items():
            items = [i for r in records if r["kind"] == kind for i in r["items"]
                     if i["feature"] == obj and i["status"] == "visible" and i.get("top")]
            if items:
                out[kind][obj] = {
                    "n": len(items),
                    "top1": dict(Counter(i["top"][0][0] for i in items).most_common(10)),
                    "top5_hits_by_class": dict(Counter(c for i in items for c, _ in i["top"] if c in plausible))}
                upright = [i["upright"] for i in items if "upright" in i]
                if upright:
                    out[kind][obj]["upright"] = {
                        "n": len(upright), "top1": dict(Counter(u["top"][0][0] for u in upright).most_common(10)),
                        "top5_hits_by_class": dict(Counter(c for u in upright for c, _ in u["top"] if c in plausible))}
    return dict(out)
