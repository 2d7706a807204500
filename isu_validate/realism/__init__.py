"""Realism metrics between image sets: FID and KID on Inception features, numerically sound.

The feature extractor (torch, TorchScript Inception) is imported on first use (PEP 562):
every CLI command imports this package through ``isu_validate.realism.images`` and must
not pay for torch.
"""
from .compare import MetricSettings, RealismResult, compare_features
from .fid import fid, fid_bootstrap, fid_from_stats, trace_sqrt_product
from .images import ImageError, read_rgb
from .kid import KIDResult, kid
from .sets import ImageSet, resolve_set

_LAZY = {"FeatureExtractor", "FeatureSettings"}

__all__ = ["FeatureExtractor", "FeatureSettings", "ImageError", "ImageSet", "KIDResult", "MetricSettings",
           "RealismResult", "compare_features", "fid", "fid_bootstrap", "fid_from_stats", "kid", "read_rgb",
           "resolve_set", "trace_sqrt_product"]


def __getattr__(name):
    if name in _LAZY:
        from . import features

        return getattr(features, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
