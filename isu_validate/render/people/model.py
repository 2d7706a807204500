"""The anny body model (NAVER's MakeHuman-based parametric human): where its cache lives, and one
lazily built model per process.

anny builds its model data once (about 75 s and 2 GB on two cores) and caches it (~824 MB) in
``ANNY_CACHE_DIR``; `make setup` runs that build (``python -m isu_validate.setup_data``), so a user's
first run only loads it (about 0.5-6 s, ~0.9 GB resident). Without ``ANNY_CACHE_DIR`` in the
environment the cache is ``<sys.prefix>/share/anny``: inside the virtual environment, written by setup
and read by every run of that environment. The model is loaded only on a miss of the posed-vertex
cache (``people.cache``), so runs that only meet bodies seen before never pay for it."""
from __future__ import annotations

import os
import sys
import threading
import warnings
from functools import lru_cache
from pathlib import Path

# the model configuration every body is evaluated with (part of every posed-vertex cache key)
FACIAL_ACTIONS = "all"
_lock = threading.Lock()


def anny_cache_dir() -> Path:
    """Where anny's built model data lives: $ANNY_CACHE_DIR, else <sys.prefix>/share/anny."""
    return Path(os.environ.get("ANNY_CACHE_DIR") or Path(sys.prefix) / "share" / "anny")


@lru_cache(maxsize=1)
def anny_version() -> str:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("anny")
    except PackageNotFoundError as exc:
        raise RuntimeError("the anny body model is not installed; run `make setup` "
                           "(or pip install anny==0.6.2 --no-deps roma trimesh)") from exc


def model_cached() -> bool:
    """True when anny's model data has been built into the cache (setup did its job)."""
    return any(anny_cache_dir().glob("v*/build_compact_model_data_*.safetensors"))


@lru_cache(maxsize=1)
def load_model():
    """The anny model (float32, all 52 facial actions, torch skinning), built once per process."""
    with _lock:
        import torch
        try:
            from anny.paths import set_anny_cache_path
            import anny
        except ImportError as exc:
            raise RuntimeError(f"the anny body model cannot be imported ({exc}); run `make setup`, or "
                               "pip install --no-deps anny==0.6.2 and pip install roma trimesh rtree") from exc
        set_anny_cache_path(anny_cache_dir())
        with warnings.catch_warnings():
            # without the optional NVIDIA Warp anny falls back to torch skinning (same vertices, to 2e-7 m)
            warnings.filterwarnings("ignore", message=".*Warp.*")
            model = anny.Anny(facial_actions=FACIAL_ACTIONS).to(dtype=torch.float32)
        model.eval()
        return model


def build_cache() -> Path:
    """Build anny's model cache (setup's job); returns the cache folder."""
    load_model()
    return anny_cache_dir()
