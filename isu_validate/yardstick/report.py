"""The recognition report: contact sheets of the crops with what each model said, and index.html with the
rates of renders and real photographs side by side (every value escaped)."""
from __future__ import annotations

from pathlib import Path

from capture.sidecar import banner

from ..analysis.html import STYLE, esc
from ..recognition.frames import KINDS
from ..recognition.tally import MEASURES, SPLITS

TILE, CAPTION_H, COLUMNS = 128, 30, 8


def write_sheets(crops: dict[str, list], out: Path) -> dict[str, str]:
    """One PNG per kind of frame: crops enlarged to tiles, each captioned with what the models said."""
    import cv2
    import numpy as np

    written = {}
    for kind, items in crops.items():
        if not items:
            continue
        tiles = [_tile(cv2, np, crop, caption) for crop, caption in items]
        tiles += [np.zeros_like(tiles[0])] * (-len(tiles) % COLUMNS)
        grid = np.vstack([np.hstack(tiles[i:i + COLUMNS]) for i in range(0, len(tiles), COLUMNS)])
        name = f"sheet-{kind}.png"
        cv2.imwrite(str(out / name), grid)
        written[kind] = name
    return written


def _tile(cv2, np, crop, caption: str):
    tile = np.full((TILE + CAPTION_H, TILE, 3), 255, np.uint8)
    h, w = crop.shape[:2]
    scale = TILE / max(h, w, 1)
    small = cv2.resize(cv2.cvtColor(crop, cv2.COLOR_RGB2BGR), (max(1, int(w * scale)), max(1, int(h * scale))),
                       interpolation=cv2.INTER_NEAREST)
    tile[:small.shape[0], :small.shape[1]] = small
    for i, line in enumerate(_lines(caption)):
        cv2.putText(tile, line, (2, TILE + 11 + 10 * i), cv2.FONT_HERSHEY_PLAIN, 0.6, (0, 0, 0), 1, cv2.LINE_AA)
    return tile


def _lines(caption: str, width: int = 24) -> list[str]:
    return [caption[i:i + width] for i in range(0, min(len(caption), 2 * width), width)]


def write_report(summary: dict) -> str:
    frames = summary["frames"]
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>recognition</title><style>{STYLE}</style>"
             "</head><body><h1>How recognisable are the frames to models trained on photographs?</h1>",
             f"<p>{esc(frames['total'])} frames: {esc(frames['render'])} renders, {esc(frames['real'])} real "
             f"photographs, {esc(frames['stand-in'])} stand-ins; presets {esc(', '.join(summary['presets']))}; "
             f"device {esc(summary['device'])}; {esc(summary['timing']['per_frame_s'])} s per frame.</p>"]
    if frames["stand-in"] or frames["real"]:
        parts.append(f"<p><b>{esc(banner(frames['stand-in'], frames['real']))}</b></p>")
    parts.append(_models(summary))
    parts.append(_table(summary["rows"], "all", "Every frame"))
    for split in SPLITS:
        parts.append(_table(summary["rows"], split, f"By {split}"))
    parts.append(_expression(summary["expression"]))
    parts.append(_objects(summary.get("objects", {})))
    for kind, name in summary.get("sheets", {}).items():
        parts.append(f"<h2>Crops: {esc(kind)}</h2><img src='{esc(name)}' alt='{esc(kind)} crops'>")
    return "\n".join(parts) + "</body></html>\n"


def _models(summary: dict) -> str:
    items = "".join(f"<li>{esc(k)}: {esc(v)}</li>" for k, v in summary["models"].items())
    plausible = "".join(f"<li>{esc(k)}: {esc(', '.join(v))}</li>" for k, v in summary["plausible_classes"].items())
    return f"<h2>Yardsticks</h2><ul>{items}</ul><p>Plausible ImageNet classes:</p><ul>{plausible}</ul>"


def _table(rows: list[dict], split: str, title: str) -> str:
    """Measures down, kinds of frame across (renders beside real photographs), one value per line."""
    chosen = [r for r in rows if r["split"] == split]
    kinds = [k for k in KINDS if any(r["kind"] == k for r in chosen)]
    keys = sorted({(r["measure"], r["value"]) for r in chosen}, key=lambda k: (list(MEASURES).index(k[0]), k[1]))
    cell = {(r["measure"], r["value"], r["kind"]): r for r in chosen}
    head = "".join(f"<th>{esc(k)}</th>" for k in kinds)
    body = "".join(f"<tr><td>{esc(m)}</td><td>{esc(v)}</td>"
                   + "".join(f"<td>{_cell(cell.get((m, v, k)))}</td>" for k in kinds) + "</tr>" for m, v in keys)
    return f"<h2>{esc(title)}</h2><table><tr><th>measure</th><th>{esc(split)}</th>{head}</tr>{body}</table>"


def _cell(row: dict | None) -> str:
    if row is None:
        return ""
    if not row["n"]:
        return esc(f"n 0, {row['occluded']} occluded")
    lo, hi = row["ci95"]
    return esc(f"{row['rate']:.0%} ({row['hits']}/{row['n']}; 95% {lo:.0%}-{hi:.0%}); {row['occluded']} occluded")


def _expression(expression: dict) -> str:
    parts = ["<h2>Expression: what FER read</h2>"]
    for kind, e in expression.items():
        reads = "; ".join(f"{t}: " + ", ".join(f"{c} {n}" for c, n in top.items()) for t, top in e["top_read"].items())
        parts.append(f"<p>{esc(kind)}: {esc(reads)}; AUC of P(happy), HAPPY against SERIOUS: {esc(e['auc_happy'])}</p>")
    return "".join(parts)


def _objects(objects: dict) -> str:
    parts = ["<h2>Objects: what ImageNet read</h2>"]
    for kind, per in objects.items():
        for obj, o in per.items():
            top1 = ", ".join(f"{c} {n}" for c, n in o["top1"].items())
            hits = ", ".join(f"{c} {n}" for c, n in o["top5_hits_by_class"].items()) or "none"
            parts.append(f"<p>{esc(kind)} {esc(obj)} (n {esc(o['n'])}): top-1 {esc(top1)}; "
                         f"top-5 hits by class: {esc(hits)}</p>")
    return "".join(parts)
