"""Does stylisation keep what the SUT must see? Structure similarity and answer flips.

The paper found generative translation (e.g. CycleGAN) changes scene content; style transfer
should change appearance only. Two measures per render/stylised pair:
* SSIM on luminance (structure and contrast, not colour);
* edge agreement: Pearson correlation of Sobel gradient magnitudes on luminance.
With a SUT, the share of answers that change between the render and its stylised version.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np
from PIL import Image
from scipy import ndimage
from skimage.metrics import structural_similarity

from isu_validate.errors import InputError


def luminance(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) in 0..1 to BT.601 luma in 0..1."""
    return rgb[..., :3] @ np.array([0.299, 0.587, 0.114])


def load_luma(path, size: tuple[int, int] | None = None) -> np.ndarray:
    """Luma of an image file, resized to ``size`` (width, height) when given."""
    with Image.open(path) as img:
        img = img.convert("RGB")
        if size and img.size != tuple(size):
            img = img.resize(tuple(size), Image.Resampling.LANCZOS)
        return luminance(np.asarray(img, dtype=np.float64) / 255.0)


def ssim_luma(a: np.ndarray, b: np.ndarray) -> float:
    if a.shape != b.shape:
        raise ValueError(f"SSIM needs equal sizes, got {a.shape} and {b.shape}")
    win = min(7, *(s if s % 2 else s - 1 for s in a.shape))
    if win < 3:
        raise InputError(f"images of {a.shape} pixels are too small for SSIM (3x3 at least)")
    return float(structural_similarity(a, b, data_range=1.0, win_size=win))


def edge_agreement(a: np.ndarray, b: np.ndarray) -> float:
    """Correlation of gradient magnitudes; 1 when both are flat (nothing to lose), 0 when one is."""
    ea, eb = (np.hypot(ndimage.sobel(x, 0), ndimage.sobel(x, 1)).ravel() for x in (a, b))
    sa, sb = ea.std(), eb.std()
    if sa < 1e-12 or sb < 1e-12:
        return 1.0 if sa < 1e-12 and sb < 1e-12 else 0.0
    return float(np.corrcoef(ea, eb)[0, 1])


@dataclass
class StructureScore:
    ssim_luma: float
    edge_agreement: float


def structure_score(render_path, stylised_path) -> StructureScore:
    """Compare at the render's size (the stylised image may have been made smaller)."""
    with Image.open(render_path) as img:
        size = img.size
    a, b = load_luma(render_path), load_luma(stylised_path, size)
    return StructureScore(ssim_luma(a, b), edge_agreement(a, b))


@dataclass
class FlipReport:
    compared: int = 0                 # answers compared (questions answered on both images)
    flipped: int = 0
    errors: int = 0                   # SUT errors on either image: neither flip nor agreement
    per_feature: dict[str, list[int]] = field(default_factory=dict)  # key: [compared, flipped]

    @property
    def flip_rate(self) -> float | None:
        return self.flipped / self.compared if self.compared else None


Answerer = Callable[[object, object], Mapping[str, str] | None]


def answer_flips(samples: Sequence[tuple[object, object, object]], ask: Answerer) -> FlipReport:
    """``samples``: (context, render, stylised); ``ask(context, image)`` gives answers or None on a SUT error."""
    report = FlipReport()
    for context, render, stylised in samples:
        before, after = ask(context, render), ask(context, stylised)
        if before is None or after is None:
            report.errors += 1
            continue
        for key in sorted(set(before) & set(after)):
            counts = report.per_feature.setdefault(key, [0, 0])
            changed = before[key] != after[key]
            counts[0] += 1
            counts[1] += int(changed)
            report.compared += 1
            report.flipped += int(changed)
    return report
