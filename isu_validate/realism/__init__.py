"""Realism metrics between image sets: FID and KID on Inception features, numerically sound.

Names are imported on first use (PEP 562): importing the package, as every CLI command
does through ``isu_validate.realism.images``, must not load torch.
"""
from importlib import import_module

_EXPORTS = {
    "MetricSettings": "compare", "RealismResult": "compare", "compare_features": "compare",
    "FeatureExtractor": "features", "FeatureSettings": "features",
    "fid": "fid", "fid_bootstrap": "fid", "fid_from_stats": "fid", "trace_sqrt_product": "fid",
    "ImageError": "images", "read_rgb": "images",
    "KIDResult": "kid", "kid": "kid",
    "ImageSet": "sets", "resolve_set": "sets",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_EXPORTS[name]}", __name__), name)
