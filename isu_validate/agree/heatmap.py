"""The paper's agreement heatmap: features (rows) by samples (columns), each cell coloured by category."""
from __future__ import annotations

import numpy as np

from ..analysis.plots import plt, to_data_uri
from .compare import BOTH_CORRECT, BOTH_WRONG, NOT_COMPARED, NST_ONLY, REAL_ONLY, SIM_ONLY

ORDER = (BOTH_CORRECT, BOTH_WRONG, "render_only", REAL_ONLY, "not compared")
COLOURS = ("#2e7d32", "#f2a900", "#1565c0", "#c62828", "#bdbdbd")


def heatmap(rows: list[dict], column: str, labels: dict[str, str], title: str) -> str:
    """A PNG data URI; inactive features (not asked in that scene) stay white."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    columns = list(dict.fromkeys((r["sample"], r["frame"]) for r in rows))
    present = set(r["feature"] for r in rows)
    # the space's order (``labels`` follows it), as the paper's K1..K12; then anything else
    features = [f for f in labels if f in present] + sorted(present - set(labels))
    several = len(columns) > len({s for s, _ in columns})
    grid = np.full((len(features), len(columns)), np.nan)
    for r in rows:
        cat = r[column]
        if not cat:
            continue
        cat = "render_only" if cat in (SIM_ONLY, NST_ONLY) else "not compared" if cat in NOT_COMPARED else cat
        grid[features.index(r["feature"]), columns.index((r["sample"], r["frame"]))] = ORDER.index(cat)
    fig, ax = plt.subplots(figsize=(max(4.0, 1.6 + 0.28 * len(columns)), 1.2 + 0.3 * len(features)))
    ax.imshow(np.ma.masked_invalid(grid), cmap=ListedColormap(COLOURS), vmin=-0.5, vmax=len(ORDER) - 0.5,
              aspect="auto", interpolation="nearest")
    ax.set_yticks(range(len(features)), [labels.get(f, f) for f in features], fontsize=8)
    names = [f"{s}/{f.rsplit('.', 1)[0][-4:]}" if several else s for s, f in columns]
    ax.set_xticks(range(len(columns)), names, fontsize=7, rotation=90)
    ax.set_xticks(np.arange(-0.5, len(columns)), minor=True)
    ax.set_yticks(np.arange(-0.5, len(features)), minor=True)
    ax.grid(which="minor", color="#fff", linewidth=1)
    ax.tick_params(which="minor", length=0)
    ax.set_title(title, fontsize=10)
    render = "nst" if column == "nst_category" else "sim"
    names = {BOTH_CORRECT: "both correct", BOTH_WRONG: "both wrong", "render_only": f"correct only on {render}",
             REAL_ONLY: "correct only on real", "not compared": "not compared"}
    ax.legend(handles=[Patch(color=c, label=names[k]) for k, c in zip(ORDER, COLOURS)], fontsize=7,
              loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return to_data_uri(fig)
