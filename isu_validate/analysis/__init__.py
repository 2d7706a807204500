"""Analysis of runs: RQ1 failure rates with statistics, RQ2 failure diversity, failure
analysis and regions, and the HTML reports (single run and ``isu-validate report``).
Submodules import their heavy dependencies (matplotlib, SciPy, scikit-learn, torch) on use."""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError


def write_run_report(run_dir: Path) -> Path:
    """Write ``run_dir/report.html`` (the ``run`` command's single-run report); return its path."""
    from .run_report import write_run_report as write
    return write(Path(run_dir))


def build_report(run_paths, out_dir: Path, settings=None, overwrite: bool = False) -> Path:
    """Compare runs (``isu-validate report``): ``out_dir/report.html`` plus CSV/JSON tables."""
    from .multi_report import build_report as build
    return build(run_paths, Path(out_dir), settings, overwrite=overwrite)


def report(runs, out: str | os.PathLike, *, embedding: str = "inception", clusters: int | None = None,
           gallery: int | None = None, seed: int = 0, device: str = "auto", overwrite: bool = False) -> Path:
    """Compare runs as ``isu-validate report`` does: ``out/report.html``, ``out/report.json`` and one CSV
    per table; returns the HTML's path. ``runs``: run directories (a folder of runs stands for all of
    them); ``embedding``: ``inception``, ``scene`` (no images) or ``clip:PATH``; ``clusters`` (k of
    k-means, default 10) and ``gallery`` (failing scenes shown, default 60) as the command's flags; ``device``
    where the image embedding runs (``auto|cpu|cuda[:N]|mps``, named in report.json's ``embedding_detail``).
    ``out`` must be new or this same report's folder; another command's output (a run) needs ``overwrite=True``.

        report(["runs/surrogate-s1", "runs/rs-s1"], "report/", embedding="scene")
    """
    from .multi_report import DEFAULT_GALLERY, DEFAULT_K, ReportSettings

    k = DEFAULT_K if clusters is None else clusters
    shown = DEFAULT_GALLERY if gallery is None else gallery
    if k < 1:
        raise InputError(f"--clusters must be at least 1, got {k}")
    if shown < 0:
        raise InputError(f"--gallery must be 0 or more, got {shown}")
    runs = [runs] if isinstance(runs, (str, os.PathLike)) else list(runs)   # one run, not its characters
    return build_report(runs, out, ReportSettings(embedding=embedding, k=k, seed=seed, gallery=shown,
                                                     device=device), overwrite=overwrite)


__all__ = ["build_report", "report", "write_run_report"]
