"""The lens models' names and distortion lengths: the one list (``capture.lens`` projects through them).

Imports nothing heavy, so that a command line can offer the models as choices without loading OpenCV.
"""
from __future__ import annotations

from isu_validate.errors import InputError

N_DISTORTION = {"pinhole": 0, "opencv8": 8, "fisheye": 4}
MODELS = tuple(N_DISTORTION)


def check_model(model: str) -> str:
    if model not in N_DISTORTION:
        raise InputError(f"unknown lens model {model!r}; use one of {', '.join(MODELS)}")
    return model
