"""The backbone features of a model's own training and held-out scenes, kept beside its heads.

The backbone is frozen, so a scene's features never change while the renderer and the space do
not: a model that keeps them (``train_features.npz``, ``held_out_features.npz``) can be retrained
with extra data without rendering its base set again, and evaluated on the same held-out scenes.
Each file holds the features as float32, the canonical scenes as JSON and what they were made with
(space hash, renderer version, preset, backbone, seed). float32, not float16: the shipped sets take
10.5 MB compressed (half the pooled activations are zero) and refit the shipped heads (the same
held-out answers; the weights to within the BLAS kernel's last digits, 2e-4 of the largest weight);
float16 would take 5.9 MB and move the weights by up to 1e-3 (the accuracies stay the same). Reusing
them with another renderer version or space is refused: the features would describe images the
renderer no longer makes.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError, InputNotFound

FILES = {"train": "train_features.npz", "held_out": "held_out_features.npz"}


@dataclass
class FeatureSet:
    features: np.ndarray     # (n, D) float32
    scenes: list[dict]       # the labels: canonical scenes (a feature left out is not learnt from)
    meta: dict               # space, space_hash, renderer, preset, backbone, input_size, seed, role


def save_feature_set(path: Path, features: np.ndarray, scenes: list[dict], meta: dict) -> None:
    if len(features) != len(scenes):
        raise ValueError(f"{len(features)} feature rows for {len(scenes)} scenes")
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(f, features=features.astype(np.float32), scenes=np.array(json.dumps(scenes)),
                            meta=np.array(json.dumps(meta)))


def load_feature_set(path: Path) -> FeatureSet:
    if not path.is_file():
        raise InputNotFound(f"no stored features {path}: the model in {path.parent} was trained before "
                            "features were kept; retrain it with `isu-validate reference train` (which keeps them)")
    with np.load(path, allow_pickle=False) as data:
        return FeatureSet(data["features"].astype(np.float32), json.loads(str(data["scenes"])),
                          json.loads(str(data["meta"])))


def save_bank(folder: Path, train: FeatureSet, held_out: FeatureSet) -> None:
    for role, part in (("train", train), ("held_out", held_out)):
        save_feature_set(folder / FILES[role], part.features, part.scenes, dict(part.meta, role=role))


def load_bank(folder: Path, space, renderer_version: str) -> tuple[FeatureSet, FeatureSet]:
    """The training and held-out features of the model in ``folder``, checked against the space and
    the renderer they will be used with."""
    train, held_out = (load_feature_set(folder / FILES[role]) for role in ("train", "held_out"))
    for part in (train, held_out):
        check_made_with(part.meta, f"the stored features in {folder}", space, renderer_version,
                        "the current renderer is", "render them again: `isu-validate reference train` without --extra")
    return train, held_out


def check_made_with(meta: dict, what: str, space, renderer_version: str | None, whose: str, fix: str) -> None:
    """Refuse data of another scene space or renderer version than ``whose``, naming both."""
    if meta.get("space_hash") != space.hash:
        raise InputError(f"{what} belong to scene space {meta.get('space')!r} (hash {meta.get('space_hash')}), "
                         f"not to {space.name!r} (hash {space.hash}); use data of the same space")
    if renderer_version is not None and meta.get("renderer") != renderer_version:
        raise InputError(f"{what} were rendered with renderer {meta.get('renderer')!r}, {whose} "
                         f"{renderer_version!r}: the features would describe other images; {fix}")
