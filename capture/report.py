"""The HTML calibration report: the plots that tell a good calibration from a lucky one."""
from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np

from .calibrate import CalibrationResult


def _figure():
    import matplotlib
    matplotlib.use("Agg")  # no display on lab machines or CI
    import matplotlib.pyplot as plt
    return plt


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    _figure().close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _image_axes(plt, size, title):
    fig, ax = plt.subplots(figsize=(6.4, 4.8 * size[1] / size[0] + 0.4))
    ax.set_xlim(-0.5, size[0] - 0.5)
    ax.set_ylim(size[1] - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_title(title)
    return fig, ax


def coverage_plot(res: CalibrationResult) -> str:
    plt = _figure()
    sol = res.solution
    fig, ax = _image_axes(plt, sol.image_size, "where corners were observed (red: rejected outliers)")
    for d, m in zip(sol.detections, sol.inliers):
        ax.plot(d.pixels[m, 0], d.pixels[m, 1], ".", ms=2, color="tab:blue")
        ax.plot(d.pixels[~m, 0], d.pixels[~m, 1], "x", ms=6, color="tab:red")
    return _png(fig)


def map_plot(us, vs, values, size, title, label) -> str:
    plt = _figure()
    fig, ax = _image_axes(plt, size, title)
    finite = values[np.isfinite(values)]
    vmax = float(np.percentile(finite, 99)) if finite.size else 1.0
    mesh = ax.pcolormesh(us, vs, np.where(np.isfinite(values), values, np.nan), shading="nearest",
                         vmin=0, vmax=max(vmax, 1e-6), cmap="viridis")
    if finite.size and finite.max() > finite.min():
        cs = ax.contour(us, vs, values, levels=6, colors="white", linewidths=0.6)
        ax.clabel(cs, fontsize=7, fmt="%.2f")
    fig.colorbar(mesh, ax=ax, label=label)
    return _png(fig)


def board_residual_plot(res: CalibrationResult) -> str:
    """Mean residual per board corner: a systematic pattern means a bent board or a wrong model."""
    plt = _figure()
    sol = res.solution
    ids = np.concatenate([d.ids[m] for d, m in zip(sol.detections, sol.inliers)])
    pts = np.concatenate([d.board_points[m] for d, m in zip(sol.detections, sol.inliers)])
    err = np.concatenate([np.linalg.norm(r[m], axis=1) for r, m in zip(sol.residuals(), sol.inliers)])
    n = ids.max() + 1
    mean = np.bincount(ids, err, n) / np.maximum(np.bincount(ids, None, n), 1)
    xy = np.zeros((n, 2))
    xy[ids] = pts[:, :2]
    seen = np.bincount(ids, None, n) > 0
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    sc = ax.scatter(xy[seen, 0] * 1000, xy[seen, 1] * 1000, c=mean[seen], s=60, cmap="magma")
    ax.invert_yaxis()
    ax.set_aspect("equal")
    ax.set_xlabel("board x (mm)")
    ax.set_ylabel("board y (mm)")
    ax.set_title("mean residual by board position")
    fig.colorbar(sc, ax=ax, label="px")
    return _png(fig)


def frame_plot(res: CalibrationResult) -> str:
    plt = _figure()
    rms = res.camera.calibration["frame_rms_px"]
    fig, ax = plt.subplots(figsize=(6.4, 2.8))
    ax.bar(range(len(rms)), rms, color="tab:blue")
    ax.set_xlabel("frame")
    ax.set_ylabel("RMS residual (px)")
    ax.set_title("residual per frame")
    return _png(fig)


def _table(rows) -> str:
    return "<table>" + "".join(f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(str(v))}</td></tr>"
                               for k, v in rows) + "</table>"


def write_report(res: CalibrationResult, path: str | Path, title: str = "Camera calibration") -> Path:
    cam, sol = res.camera, res.solution
    q = cam.quality
    names = ["fx", "fy", "cx", "cy"] + [f"d{i}" for i in range(len(cam.intrinsics) - 4)]
    sd = (np.sqrt(np.diag(sol.intrinsics_covariance)) if sol.intrinsics_covariance is not None
          else np.full(len(names), np.inf))
    intr_rows = [(n, f"{v:.6g} \u00b1 {s:.2g}") for n, v, s in zip(names, cam.intrinsics, sd)]
    u = q["uncertainty_px"]
    cv = q.get("cross_validation_diff_px") or {}
    qual_rows = [("model", cam.model), ("image", f"{cam.width}x{cam.height}"), ("frames", q["frames"]),
                 ("corners (outliers)", f"{q['corners']} ({q['outliers']})"),
                 ("RMS residual", f"{q['rms_px']:.3f} px"), ("noise (per axis)", f"{q['noise_px']:.3f} px"),
                 (f"uncertainty at {u['distance_m']:g} m (centre / edge / corner)",
                  f"{u['centre']:.3f} / {u['edge']:.3f} / {u['corner']:.3f} px"),
                 ("cross-validation diff (median / p90 / max)",
                  " / ".join(f"{cv[k]:.3f}" for k in ("median", "p90", "max")) + " px" if cv else "not run")]
    plots = [("Corner coverage", coverage_plot(res)),
             ("Projection uncertainty", map_plot(res.uncertainty_map.us, res.uncertainty_map.vs,
                                                 res.uncertainty_map.stdev_px, sol.image_size,
                                                 f"projection uncertainty at {u['distance_m']:g} m",
                                                 "worst-direction stdev (px)"))]
    if res.crossval is not None:
        plots.append(("Cross-validation", map_plot(res.crossval.us, res.crossval.vs, res.crossval.diff_px,
                                                   sol.image_size, "projection difference, even vs odd frames",
                                                   "px")))
    plots += [("Residuals by board position", board_residual_plot(res)), ("Residuals by frame", frame_plot(res))]
    warn = ("<ul class='warn'>" + "".join(f"<li>{html.escape(w)}</li>" for w in res.warnings) + "</ul>"
            if res.warnings else "<p>No warnings.</p>")
    skipped = ("<h2>Skipped images</h2><ul>" + "".join(f"<li>{html.escape(p)}: {html.escape(why)}</li>"
                                                       for p, why in res.skipped) + "</ul>") if res.skipped else ""
    figs = "".join(f"<h2>{html.escape(t)}</h2><img alt='{html.escape(t)}' src='data:image/png;base64,{b}'>"
                   for t, b in plots)
    doc = f"""<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}
th,td{{border:1px solid #ccc;padding:3px 8px;text-align:left}}.warn li{{color:#a40}}img{{max-width:100%}}</style>
</head><body><h1>{html.escape(title)}: {html.escape(cam.name)}</h1>
<p>Board {html.escape(cam.calibration.get('board', ''))}; judged by projection uncertainty (propagated from the
observation noise) and by cross-validation, not by the RMS residual alone.</p>
<h2>Warnings</h2>{warn}<h2>Quality</h2>{_table(qual_rows)}<h2>Intrinsics (\u00b1 1 sigma)</h2>{_table(intr_rows)}
{figs}{skipped}</body></html>"""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(doc)
    return path
