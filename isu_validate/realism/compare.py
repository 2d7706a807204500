"""FID and KID between two feature sets, with every setting that shaped the numbers."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from . import fid as fid_mod
from .kid import DEFAULT_SUBSETS, kid

FID_UNBIASED_N = 2048  # below the feature dimension the covariance is singular and FID biased upwards


@dataclass(frozen=True)
class MetricSettings:
    bootstrap: int = 200          # FID percentile-bootstrap resamples; 0 skips the interval
    ci_level: float = 0.95
    kid_subset_size: int | None = None   # None: min(1000, n_a, n_b)
    kid_subsets: int = DEFAULT_SUBSETS
    seed: int = 0


@dataclass
class RealismResult:
    fid: float
    fid_ci: list[float] | None
    kid_mean: float
    kid_std: float
    n_a: int
    n_b: int
    settings: dict[str, Any] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


def small_n_warning(n_a: int, n_b: int) -> str | None:
    if min(n_a, n_b) >= FID_UNBIASED_N:
        return None
    return (f"n = {min(n_a, n_b)} is below {FID_UNBIASED_N}: FID is biased upwards at this size and "
            "only comparable between sets of the same sizes; KID is the fairer number")


def compare_features(f_a: np.ndarray, f_b: np.ndarray, settings: MetricSettings = MetricSettings(),
                     feature_settings: dict[str, Any] | None = None) -> RealismResult:
    value = fid_mod.fid(f_a, f_b)
    ci = None
    if settings.bootstrap:
        ci = list(fid_mod.fid_bootstrap(f_a, f_b, settings.bootstrap, settings.seed, settings.ci_level))
    k = kid(f_a, f_b, settings.kid_subset_size, settings.kid_subsets, settings.seed)
    report = {
        "fid_trace_term": "nuclear norm of centred A B^T" if fid_mod.use_gram(len(f_a), len(f_b), f_a.shape[1])
                          else "eigenvalues of sqrt(S_a) S_b sqrt(S_a)",
        "fid_precision": "float64",
        "fid_bootstrap": settings.bootstrap, "fid_ci_level": settings.ci_level,
        "kid_kernel": "(x.y/d + 1)^3", "kid_subset_size": k.subset_size, "kid_subsets": k.subsets,
        "kid_std": "population (ddof=0)", "seed": settings.seed,
        **(feature_settings or {}),
    }
    warns = [w for w in [small_n_warning(len(f_a), len(f_b))] if w]
    if ci and not ci[0] <= value <= ci[1]:
        warns.append("the FID point estimate lies outside its bootstrap interval: resampling repeats images, "
                     "which adds small-sample bias; read the interval as spread and compare KID instead")
    if k.subset_size == min(len(f_a), len(f_b)) and len(f_a) == len(f_b):
        warns.append("KID subsets are the whole sets, so its std is 0 and says nothing about spread")
    return RealismResult(value, ci, k.mean, k.std, len(f_a), len(f_b), report, warns)
