"""``exposure check``: how close renders and captures of the same scenes are in brightness and colour.

Pairs are matched by file stem (``SIM_DIR/x.png`` with ``REAL_DIR/x.png``), or come from a pairs
directory (``isu_validate.pairs``: each sample's ``sim.png`` with each of its ``real/`` frames). Per pair: the mean,
median and 5th/95th percentile of display luma (BT.709 weights on the 8-bit levels), their ratio, and
the CIE dE2000 between the two images' mean colours; pooled and per-pair luma histograms; an HTML page.
A render folder's by-products (contact sheet, channel images) are left out by the ``by_product`` test the
command hands in (the renderer's ``outputs.by_product``). Captures whose sidecar marks them stand-ins
(renders taken for photos) are counted, flagged per pair and, in a mixed set, summarised apart."""
from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path
from typing import Callable

import numpy as np

from isu_validate.atomic import write_text
from isu_validate.errors import InputError

from ..sidecar import banner, provenance
from .colour_align import read_rgb8
from .frames import IMAGE_SUFFIXES
from .metering import LUMA

BINS = 64


def _no_by_products(path: Path) -> str | None:
    return None


def pairs(sim_dir: str | Path, real_dir: str | Path,
          by_product: Callable[[Path], str | None] = _no_by_products) -> tuple[list[tuple[Path, Path]], list[str]]:
    """(sim, real) images matched by stem; ``by_product(path)`` names a sim file that is not a frame."""
    sim = {p.stem: p for p in sorted(Path(sim_dir).iterdir()) if p.suffix.lower() in IMAGE_SUFFIXES
           and not p.name.startswith(".") and not by_product(p)}   # no contact sheet or channel images
    real = {p.stem: p for p in sorted(Path(real_dir).iterdir()) if p.suffix.lower() in IMAGE_SUFFIXES
            and not p.name.startswith(".")}
    matched = [(sim[k], real[k]) for k in sorted(sim) if k in real]
    unmatched = ([str(sim[k]) for k in sorted(sim) if k not in real]
                 + [str(real[k]) for k in sorted(real) if k not in sim])
    if not matched:
        raise InputError(f"no image in {sim_dir} has a namesake in {real_dir}; pairs are matched by file name "
                         "(sim/x.png with real/x.png)")
    return matched, unmatched


def pairs_of_directory(root: str | Path) -> tuple[list[tuple[Path, Path]], list[str]]:
    """(sim.png, real frame) of every sample of a pairs directory; samples without frames are listed."""
    from isu_validate.pairs import PairsDir
    matched, unmatched = [], []
    for sample in PairsDir(root).samples():
        frames = sample.real_frames()
        if not sample.sim.is_file() or not frames:
            unmatched.append(str(sample.path))
        matched += [(sample.sim, frame) for frame in frames if sample.sim.is_file()]
    if not matched:
        raise InputError(f"no sample of {root} has both sim.png and captured frames in real/ (capture them with "
                         "`isu-validate capture shoot --pair DIR/<sample>`)")
    return matched, unmatched


def measure(image: np.ndarray) -> dict:
    luma = (image.astype(np.float64) / 255.0) @ LUMA
    return {"mean": float(luma.mean()), "median": float(np.median(luma)), "p5": float(np.percentile(luma, 5)),
            "p95": float(np.percentile(luma, 95)), "histogram": np.histogram(luma, BINS, (0, 1))[0].tolist(),
            "mean_colour": (image.reshape(-1, 3).mean(axis=0) / 255.0).tolist()}


def compare(sim_dir: str | Path, real_dir: str | Path | None = None,
            by_product: Callable[[Path], str | None] = _no_by_products) -> dict:
    """Per-pair and pooled brightness and colour; ``real_dir`` None: ``sim_dir`` is a pairs directory."""
    from .colour_fit import de2000
    matched, unmatched = (pairs(sim_dir, real_dir, by_product) if real_dir is not None
                          else pairs_of_directory(sim_dir))
    rows, stand_ins = [], provenance(real for _, real in matched).stand_in
    for sim_path, real_path in matched:
        s, r = measure(read_rgb8(sim_path)), measure(read_rgb8(real_path))
        name = sim_path.stem if real_dir is not None else f"{sim_path.parent.name}/{real_path.stem}"
        rows.append({"name": name, "sim": str(sim_path), "real": str(real_path), "stand_in": real_path in stand_ins,
                     "sim_luma": s, "real_luma": r,
                     "luma_ratio": r["mean"] / s["mean"] if s["mean"] > 0 else float("inf"),
                     "luma_difference": r["mean"] - s["mean"],
                     "de2000_mean_colour": float(de2000(np.array([s["mean_colour"]]),
                                                        np.array([r["mean_colour"]]))[0])})
    n_stand_in = sum(row["stand_in"] for row in rows)
    summary = {**_figures(rows), "unmatched": unmatched,
               "stand_in_frames": n_stand_in, "real_frames": len(rows) - n_stand_in}
    if 0 < n_stand_in < len(rows):   # a mixed set: the figures of each kind apart
        summary["by_provenance"] = {kind: _figures([row for row in rows if row["stand_in"] == flag])
                                    for kind, flag in (("real", False), ("stand_in", True))}
    return {"summary": summary, "pairs": rows}


def _figures(rows: list[dict]) -> dict:
    diffs = np.array([row["luma_difference"] for row in rows])
    des = np.array([row["de2000_mean_colour"] for row in rows])
    return {"pairs": len(rows), "mean_abs_luma_difference": float(np.abs(diffs).mean()),
            "mean_luma_difference": float(diffs.mean()), "mean_de2000_mean_colour": float(des.mean()),
            "max_de2000_mean_colour": float(des.max())}


def stand_in_banner(summary: dict) -> str:
    """The banner line, with the figures of each kind when the set is mixed; '' without stand-ins."""
    text = banner(summary["stand_in_frames"], summary["real_frames"])
    for kind, part in summary.get("by_provenance", {}).items():
        text += (f" {kind.replace('_', '-')} ({part['pairs']} pairs): mean |luma difference| "
                 f"{part['mean_abs_luma_difference']:.3f}, dE2000 of mean colours "
                 f"{part['mean_de2000_mean_colour']:.2f}.")
    return text


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    return base64.b64encode(buf.getvalue()).decode()


def plots(result: dict) -> list[tuple[str, str]]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows, edges = result["pairs"], np.linspace(0, 1, BINS + 1)
    out = []
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    for key, label in (("sim_luma", "renders"), ("real_luma", "captures")):
        pooled = np.sum([r[key]["histogram"] for r in rows], axis=0)
        ax[0].stairs(pooled / pooled.sum(), edges, label=label)
    ax[0].set_xlabel("luma")
    ax[0].set_title("brightness histogram, all pairs")
    ax[0].legend()
    s, r = [x["sim_luma"]["mean"] for x in rows], [x["real_luma"]["mean"] for x in rows]
    ax[1].plot(s, r, "o")
    ax[1].plot([0, 1], [0, 1], "k--", lw=1)
    ax[1].set_xlabel("render mean luma")
    ax[1].set_ylabel("capture mean luma")
    ax[1].set_title("per pair")
    fig.tight_layout()
    out.append(("Brightness", _png(fig)))
    plt.close(fig)
    n = min(len(rows), 12)
    cols = min(n, 4)
    n_rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(n_rows, cols, figsize=(3 * cols, 2.3 * n_rows), squeeze=False)
    for ax, row in zip(axes.ravel(), rows[:n]):
        for key, label in (("sim_luma", "render"), ("real_luma", "capture")):
            h = np.asarray(row[key]["histogram"], float)
            ax.stairs(h / max(h.sum(), 1), edges, label=label)
        ax.set_title(row["name"][:28], fontsize=8)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    out.append((f"Histograms per pair (first {n})", _png(fig)))
    plt.close(fig)
    return out


def write_html(result: dict, path: str | Path) -> Path:
    s = result["summary"]
    e = html.escape
    rows = "".join(
        f"<tr><td>{e(r['name'])}</td><td>{r['sim_luma']['mean']:.3f}</td><td>{r['real_luma']['mean']:.3f}</td>"
        f"<td>{r['luma_ratio']:.3f}</td><td>{r['de2000_mean_colour']:.2f}</td>"
        f"<td>{'stand-in' if r['stand_in'] else 'real'}</td></tr>" for r in result["pairs"])
    figures = "".join(f"<h2>{e(title)}</h2><img src='data:image/png;base64,{data}'>" for title, data in plots(result))
    unmatched = "".join(f"<li>{e(u)}</li>" for u in s["unmatched"])
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>exposure check</title>"
            "<style>body{font-family:sans-serif;margin:2em}td,th{padding:2px 10px;text-align:right}"
            "td:first-child{text-align:left}</style></head><body>"
            + _banner_html(s) +
            f"<h1>Renders against captures</h1><p>{s['pairs']} pairs; mean |luma difference| "
            f"{s['mean_abs_luma_difference']:.3f} (capture - render {s['mean_luma_difference']:+.3f}); "
            f"dE2000 of the mean colours: mean {s['mean_de2000_mean_colour']:.2f}, "
            f"max {s['max_de2000_mean_colour']:.2f}</p>{figures}"
            "<h2>Pairs</h2><table><tr><th>pair</th><th>render luma</th><th>capture luma</th><th>ratio</th>"
            f"<th>dE2000 mean colour</th><th>capture</th></tr>{rows}</table>"
            + (f"<h2>Unmatched files</h2><ul>{unmatched}</ul>" if unmatched else "") + "</body></html>")
    return write_text(path, page)


def _banner_html(summary: dict) -> str:
    text = stand_in_banner(summary)
    return (f"<div id='stand-in' style='border:3px solid #b3261e;background:#fdecea;padding:8px 14px'>"
            f"<h2>Stand-in frames: not a real-world result</h2><p><b>{html.escape(text)}</b></p></div>"
            if text else "")


def write_json(result: dict, path: str | Path) -> Path:
    return write_text(path, json.dumps(result, indent=1))
