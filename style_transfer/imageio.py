"""Images as (1, 3, H, W) float tensors in 0..1, resized with anti-aliasing."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
from PIL import Image, UnidentifiedImageError

from isu_validate.atomic import atomic_path
from isu_validate.errors import InputError, InputNotFound


def load_image(path: str | Path, max_side: int | None = None) -> torch.Tensor:
    path = Path(path)
    try:
        with Image.open(path) as img:
            img = img.convert("RGB")
    except FileNotFoundError:
        raise InputNotFound(f"image {path} does not exist") from None
    except (UnidentifiedImageError, OSError) as exc:
        raise InputError(f"cannot read image {path}: {exc}; re-export it as PNG") from exc
    if max_side:
        img = fit(img, max_side)
    return to_tensor(img)


def unreadable(path: str | Path) -> str | None:
    """Why ``path`` cannot be used as an image (decoded in full: a truncated file fails too), or None."""
    try:
        with Image.open(path) as img:
            img.load()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def fit(img: Image.Image, max_side: int) -> Image.Image:
    """Scale so the longer side is ``max_side``; keeps aspect, never below 16 px (VGG pools 4x)."""
    scale = max_side / max(img.size)
    size = (max(16, round(img.width * scale)), max(16, round(img.height * scale)))
    return img if size == img.size else img.resize(size, Image.Resampling.LANCZOS)


def to_tensor(img: Image.Image) -> torch.Tensor:
    arr = np.asarray(img, dtype=np.float32) / 255.0
    return torch.from_numpy(arr).permute(2, 0, 1).unsqueeze(0).contiguous()


def to_pil(x: torch.Tensor) -> Image.Image:
    arr = (x.detach().squeeze(0).clamp(0, 1).permute(1, 2, 0).cpu().numpy() * 255.0).round().astype(np.uint8)
    return Image.fromarray(arr)


def save_image(x: torch.Tensor, path: str | Path, size: tuple[int, int] | None = None) -> Path:
    """Write a PNG, resized to ``size`` (width, height) when given, e.g. back to the render's size."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    img = to_pil(x)
    if size and img.size != tuple(size):
        img = img.resize(tuple(size), Image.Resampling.LANCZOS)
    # write then rename: an interrupt never leaves a half-written PNG that a resumed run would keep
    with atomic_path(path) as tmp:
        img.save(tmp, format="PNG", compress_level=1)  # fast: level 6 costs more than the network
    return path
