"""Kernel Inception Distance: the unbiased MMD^2 with a cubic polynomial kernel.

k(x, y) = (x.y / d + 1)^3 (Bińkowski et al. 2018; torch-fidelity's defaults), averaged over
seeded random subsets drawn without replacement. Unbiased means a single estimate can be
slightly negative when the sets match; we report it as it is, with the subsets' spread.
Comparing a set with itself gives a small negative value, -2/m (mean k(x,x) - mean k(x,y)):
the estimator assumes independent samples, and a set is not independent of itself.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

DEFAULT_SUBSET_SIZE = 1000   # torch-fidelity's default, capped by the set sizes
DEFAULT_SUBSETS = 100


@dataclass
class KIDResult:
    mean: float
    std: float          # population std of the subset estimates (ddof=0, as torch-fidelity)
    subset_size: int
    subsets: int
    seed: int


def resolve_subset_size(requested: int | None, n_a: int, n_b: int) -> int:
    """``None`` means min(1000, n_a, n_b); an explicit size larger than a set is an error."""
    smaller = min(n_a, n_b)
    if smaller < 2:
        raise InputError(f"KID needs at least 2 images per set, got {n_a} and {n_b}: add images to the smaller set")
    if requested is None:
        return min(DEFAULT_SUBSET_SIZE, smaller)
    if requested < 2:
        raise InputError(f"KID subset size must be at least 2, got {requested}")
    if requested > smaller:
        raise InputError(f"KID subset size {requested} exceeds the smaller set ({smaller} images); "
                         f"pass a subset size of at most {smaller}, or add images")
    return requested


def _poly(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return (x @ y.T / x.shape[1] + 1.0) ** 3


def mmd2_unbiased(k_xx: np.ndarray, k_yy: np.ndarray, k_xy: np.ndarray) -> float:
    m = len(k_xx)
    off_x = (k_xx.sum() - np.trace(k_xx)) / (m * (m - 1))
    off_y = (k_yy.sum() - np.trace(k_yy)) / (m * (m - 1))
    return float(off_x + off_y - 2.0 * k_xy.mean())


def kid(f_a: np.ndarray, f_b: np.ndarray, subset_size: int | None = None,
        subsets: int = DEFAULT_SUBSETS, seed: int = 0) -> KIDResult:
    f_a, f_b = np.asarray(f_a, np.float64), np.asarray(f_b, np.float64)
    if not (np.isfinite(f_a).all() and np.isfinite(f_b).all()):
        raise InputError("features contain NaN or inf; a corrupt cache or image is the likely cause")
    m = resolve_subset_size(subset_size, len(f_a), len(f_b))
    if subsets < 1:
        raise InputError(f"KID needs at least 1 subset, got {subsets}")
    rng = np.random.default_rng(seed)
    # whole kernel matrices once when they are small; subsets then only index them
    full = len(f_a) + len(f_b) <= 6000
    if full:
        k_aa, k_bb, k_ab = _poly(f_a, f_a), _poly(f_b, f_b), _poly(f_a, f_b)
    values = []
    for _ in range(subsets):
        ia = rng.choice(len(f_a), m, replace=False)
        ib = rng.choice(len(f_b), m, replace=False)
        if full:
            values.append(mmd2_unbiased(k_aa[np.ix_(ia, ia)], k_bb[np.ix_(ib, ib)], k_ab[np.ix_(ia, ib)]))
        else:
            x, y = f_a[ia], f_b[ib]
            values.append(mmd2_unbiased(_poly(x, x), _poly(y, y), _poly(x, y)))
    return KIDResult(float(np.mean(values)), float(np.std(values)), m, subsets, seed)
