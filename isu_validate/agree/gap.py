"""FID and KID between the pairs' renders, stylised renders and photos (``isu_validate.realism``).

A few dozen pairs is far below the 2048 images where FID stops being biased: the numbers are
reported with their small-n settings and warnings, exactly as ``isu-validate realism`` reports
them, and are comparable only between sets of the same sizes (sim vs real against nst vs real).
"""
from __future__ import annotations

from pathlib import Path

KID_SUBSETS = 100
BOOTSTRAP = 0   # the FID interval needs many resamples of few images; agree reports the point value and KID


def domain_gap(sim: list[Path], real: list[Path], nst: list[Path], threads: int = 2,
               cache_dir: Path | None = None, seed: int = 0, device: str = "auto") -> dict:
    """{"sim_vs_real": {...}, "nst_vs_real": {...}} with fid, kid_mean, kid_std, n, settings, warnings;
    {"skipped": reason} when a set has fewer than two images."""
    if min(len(sim), len(real)) < 2:
        return {"skipped": f"FID/KID need at least 2 images per set (sim {len(sim)}, real {len(real)})"}
    import torch
    from threadpoolctl import threadpool_limits

    from ..realism import FeatureExtractor, MetricSettings, compare_features
    from ..realism.cache import default_cache_dir

    before = torch.get_num_threads()
    torch.set_num_threads(max(1, threads))
    try:
        with threadpool_limits(limits=max(1, threads)):
            extractor = FeatureExtractor(None, "bicubic", 8, cache_dir or default_cache_dir(), device)
            metric = MetricSettings(BOOTSTRAP, 0.95, None, KID_SUBSETS, seed)
            feats = {name: extractor.features(paths) for name, paths in (("sim", sim), ("real", real), ("nst", nst))
                     if len(paths) >= 2}
            out = {}
            for a in ("sim", "nst"):
                if a in feats:
                    r = compare_features(feats[a], feats["real"], metric, extractor.report_settings())
                    out[f"{a}_vs_real"] = {"fid": r.fid, "kid_mean": r.kid_mean, "kid_std": r.kid_std,
                                           f"n_{a}": r.n_a, "n_real": r.n_b, "settings": r.settings,
                                           "warnings": r.warnings}
            return out
    finally:
        torch.set_num_threads(before)
