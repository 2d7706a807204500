"""Fréchet Inception Distance, stable in float64 for any n >= 2.

FID = |mu_a - mu_b|^2 + tr S_a + tr S_b - 2 tr sqrt(sqrt(S_a) S_b sqrt(S_a)).

Below 2048 samples the covariances are singular, and ``scipy.linalg.sqrtm(S_a S_b)``
(pytorch-fid, TTUR) returns complex or NaN values. We never form a non-symmetric matrix
square root. Two exact routes to the trace term:

* from statistics: the eigenvalues of the symmetric PSD matrix sqrt(S_a) S_b sqrt(S_a),
  clipped at 0 (they are >= 0 in exact arithmetic);
* from features (used when n is below the dimension, the usual case here): with
  A, B the centred features scaled by 1/sqrt(n-1), the nonzero eigenvalues of
  sqrt(S_a) S_b sqrt(S_a) are the squared singular values of A B^T (n_a x n_b), so the
  trace term is its nuclear norm. Exact, and it costs an n_a x n_b SVD, not d^3.

The feature route works on Gram matrices, so bootstrap resamples only index them. It is
also the more accurate one: it obtains the singular values sqrt(lambda) directly, while the
eigenvalue route must take square roots of eigenvalues known only to about dim * eps *
lambda_max, so each tiny eigenvalue can be off by sqrt of that (measured: 6e-7 relative at
n=500, d=2048; 1e-15 at n <= 53). The eigenvalue route serves inputs given only as (mu, S).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError


def _check_features(f: np.ndarray, name: str) -> np.ndarray:
    f = np.asarray(f, dtype=np.float64)
    if f.ndim != 2:
        raise ValueError(f"features of set {name} must be (n, d), got shape {f.shape}")
    if f.shape[0] < 2:
        raise InputError(f"FID needs at least 2 images in set {name}, got {f.shape[0]}: add images to the set")
    if not np.isfinite(f).all():
        raise InputError(f"features of set {name} contain NaN or inf; a corrupt cache or image is the likely cause")
    return f


def _sym(m: np.ndarray) -> np.ndarray:
    return (m + m.T) * 0.5


def _nonnegative(w: np.ndarray) -> np.ndarray:
    """Eigenvalues of a PSD matrix with round-off removed: those below the numerical-rank
    tolerance (max * dim * eps, as numpy's matrix_rank) are zero. Without this, the ~2000
    null eigenvalues of a singular covariance come out as +-1e-13 and their square roots
    (~3e-7 each) add up to a visible error in the trace term."""
    tol = max(float(np.abs(w).max(initial=0.0)), 0.0) * len(w) * np.finfo(np.float64).eps
    return np.where(w > tol, w, 0.0)


def psd_sqrt(s: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(_sym(s))
    return (v * np.sqrt(_nonnegative(w))) @ v.T


def trace_sqrt_product(s_a: np.ndarray, s_b: np.ndarray) -> float:
    """tr sqrt(sqrt(S_a) S_b sqrt(S_a)) from the eigenvalues of that symmetric PSD matrix."""
    r = psd_sqrt(s_a)
    eig = np.linalg.eigvalsh(_sym(r @ s_b @ r))
    return float(np.sqrt(_nonnegative(eig)).sum())


def fid_from_stats(mu_a, s_a, mu_b, s_b) -> float:
    mu_a, mu_b = np.asarray(mu_a, np.float64), np.asarray(mu_b, np.float64)
    s_a, s_b = np.asarray(s_a, np.float64), np.asarray(s_b, np.float64)
    diff = mu_a - mu_b
    value = diff @ diff + np.trace(s_a) + np.trace(s_b) - 2.0 * trace_sqrt_product(s_a, s_b)
    return max(0.0, float(value))  # round-off can dip below 0 for identical sets


def stats(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f = np.asarray(f, np.float64)
    return f.mean(axis=0), np.cov(f, rowvar=False)


@dataclass
class GramFID:
    """FID from Gram matrices of features centred on the pooled mean (cancellation-free)."""
    g_aa: np.ndarray
    g_bb: np.ndarray
    g_ab: np.ndarray

    @classmethod
    def from_features(cls, f_a: np.ndarray, f_b: np.ndarray) -> "GramFID":
        f_a, f_b = _check_features(f_a, "A"), _check_features(f_b, "B")
        centre = np.concatenate([f_a, f_b]).mean(axis=0)
        a, b = f_a - centre, f_b - centre
        return cls(a @ a.T, b @ b.T, a @ b.T)

    def fid(self, ia: np.ndarray | None = None, ib: np.ndarray | None = None) -> float:
        """FID of the sets (or of the resamples ``ia``, ``ib`` with repeats)."""
        ia = np.arange(len(self.g_aa)) if ia is None else ia
        ib = np.arange(len(self.g_bb)) if ib is None else ib
        aa, bb, ab = self.g_aa[np.ix_(ia, ia)], self.g_bb[np.ix_(ib, ib)], self.g_ab[np.ix_(ia, ib)]
        n_a, n_b = len(ia), len(ib)
        mean_term = aa.mean() + bb.mean() - 2.0 * ab.mean()
        tr_a = (np.trace(aa) - aa.sum() / n_a) / (n_a - 1)
        tr_b = (np.trace(bb) - bb.sum() / n_b) / (n_b - 1)
        cross = ab - ab.mean(axis=0, keepdims=True) - ab.mean(axis=1, keepdims=True) + ab.mean()
        nuclear = np.linalg.svd(cross, compute_uv=False).sum() / np.sqrt((n_a - 1) * (n_b - 1))
        return max(0.0, float(mean_term + tr_a + tr_b - 2.0 * nuclear))


def use_gram(n_a: int, n_b: int, dim: int) -> bool:
    """The feature route is cheaper while n_a * n_b * d stays below the d^3 eigen-decompositions."""
    return n_a * n_b * dim + min(n_a, n_b) ** 2 * max(n_a, n_b) < (n_a + n_b) * dim ** 2 + 4 * dim ** 3


def fid(f_a: np.ndarray, f_b: np.ndarray) -> float:
    f_a, f_b = _check_features(f_a, "A"), _check_features(f_b, "B")
    if f_a.shape[1] != f_b.shape[1]:
        raise ValueError(f"feature dimensions differ: {f_a.shape[1]} vs {f_b.shape[1]}")
    if use_gram(len(f_a), len(f_b), f_a.shape[1]):
        return GramFID.from_features(f_a, f_b).fid()
    return fid_from_stats(*stats(f_a), *stats(f_b))


def fid_bootstrap(f_a: np.ndarray, f_b: np.ndarray, resamples: int, seed: int,
                  level: float = 0.95) -> tuple[float, float]:
    """Percentile bootstrap interval: both sets resampled with replacement, seeded."""
    if resamples < 1:
        raise InputError("bootstrap needs at least 1 resample (use 0 to skip the interval)")
    f_a, f_b = _check_features(f_a, "A"), _check_features(f_b, "B")
    rng = np.random.default_rng(seed)
    gram = GramFID.from_features(f_a, f_b) if use_gram(len(f_a), len(f_b), f_a.shape[1]) else None
    values = []
    for _ in range(resamples):
        ia, ib = rng.integers(0, len(f_a), len(f_a)), rng.integers(0, len(f_b), len(f_b))
        values.append(gram.fid(ia, ib) if gram else fid_from_stats(*stats(f_a[ia]), *stats(f_b[ib])))
    tail = (1.0 - level) / 2.0 * 100.0
    low, high = np.percentile(values, [tail, 100.0 - tail])
    return float(low), float(high)
