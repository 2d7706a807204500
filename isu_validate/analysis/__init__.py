"""Analysis of runs: RQ1 failure rates with statistics, RQ2 failure diversity, failure
analysis and regions, and the HTML reports (single run and ``isu-validate report``).
Submodules import their heavy dependencies (matplotlib, SciPy, scikit-learn, torch) on use."""
from __future__ import annotations

from pathlib import Path


def write_run_report(run_dir: Path) -> Path:
    """Write ``run_dir/report.html`` (the ``run`` command's single-run report); return its path."""
    from .run_report import write_run_report as write
    return write(Path(run_dir))


def build_report(run_paths, out_dir: Path, settings=None) -> Path:
    """Compare runs (``isu-validate report``): ``out_dir/report.html`` plus CSV/JSON tables."""
    from .multi_report import build_report as build
    return build(run_paths, Path(out_dir), settings)


__all__ = ["build_report", "write_run_report"]
