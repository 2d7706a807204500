"""A style set: the real photos whose shared look style transfer aims at.

One photo (the paper used a single reconstructed scene) or many (every real frame of a pairs
directory: what one camera's pictures have in common, its colour, contrast and noise). Both methods
aim at the mean of the photos' Gram matrices, so one trained net or one optimisation target serves
the whole set, and one photo is the special case Gatys described.
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Iterable, Sequence

import torch

from isu_validate.errors import InputError
from isu_validate.image_files import expand_images

from .imageio import load_image, unreadable
from .losses import gram
from .vgg import VGG19, preprocess


def style_paths(items: Iterable[str | Path]) -> list[Path]:
    """Files and folders of style photos to a sorted list of readable image files (one-line errors)."""
    paths = expand_images(items, "style ")
    if not paths:
        raise InputError("give at least one style image (a real photo)")
    for path in paths:
        # decoded in full now: a truncated photo must fail before minutes of training, not after
        if reason := unreadable(path):
            raise InputError(f"cannot read style image {path} ({reason}); re-export it as PNG or leave it out")
    return sorted(set(paths))


def file_sha256(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def fingerprint(paths: Sequence[Path]) -> str:
    """The set's content hash: the same photos give the same key, whatever their names or order."""
    digest = hashlib.sha256()
    for h in sorted(file_sha256(p) for p in paths):
        digest.update(h.encode())
    return digest.hexdigest()


def mean_grams(vgg: VGG19, images: Sequence[torch.Tensor], layers: Sequence[str]) -> dict[str, torch.Tensor]:
    """The style target: per layer, the mean of the images' (1, C, C) Gram matrices."""
    if not images:
        raise InputError("a style set needs at least one image")
    with torch.no_grad():
        grams = [{k: gram(v) for k, v in vgg(preprocess(x.to(vgg.device)), layers).items()} for x in images]
    return {layer: torch.stack([g[layer] for g in grams]).mean(0) for layer in layers}


def load_style_grams(vgg: VGG19, paths: Sequence[Path], size: int, layers: Sequence[str]) -> dict[str, torch.Tensor]:
    """Mean Grams of the style photos, each scaled to ``size`` pixels on its longer side."""
    return mean_grams(vgg, [load_image(p, size) for p in paths], layers)
