"""Reading image files for the realism metrics: any size, grayscale, palette, RGBA or 16-bit.

Every image becomes float32 RGB on a 0..255 scale. Alpha is dropped (not composited), the
convention clean-fid and torch-fidelity use, so our numbers stay comparable with theirs.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from ..image_files import IMAGE_SUFFIXES  # one list of the image files every set reader accepts
from ..errors import InputError, InputNotFound, UserError

__all__ = ["ImageError", "list_images", "read_rgb"]


class ImageError(UserError, ValueError):
    """An image file that cannot be used; the message names the file and the fix."""


def read_rgb(path: str | Path) -> np.ndarray:
    """The image at ``path`` as an (H, W, 3) float32 array in 0..255."""
    path = Path(path)
    try:
        with Image.open(path) as img:
            img.load()  # decode now, so a truncated file fails here and not later
            return _to_rgb_float(img)
    except FileNotFoundError:
        raise
    except (UnidentifiedImageError, OSError, SyntaxError) as exc:
        raise ImageError(f"cannot read image {path}: {exc}; re-export it as PNG or remove it from the set") from exc


def _to_rgb_float(img: Image.Image) -> np.ndarray:
    if img.width < 1 or img.height < 1:
        raise ImageError("image has no pixels")
    if img.mode in ("I;16", "I;16B", "I;16L", "I", "F"):
        # high bit depth grayscale: scale to 0..255 by the format's range, not the image's
        arr = np.asarray(img, dtype=np.float32)
        # I;16 is 16-bit by format; plain I (32-bit) is ambiguous, so judge it by its values
        sixteen = img.mode.startswith("I;16") or (img.mode == "I" and arr.max(initial=0) > 255)
        top = 65535.0 if sixteen else 255.0
        grey = np.clip(arr * (255.0 / top), 0, 255)
        return np.repeat(grey[..., None], 3, axis=2)
    return np.asarray(img.convert("RGB"), dtype=np.float32)


def list_images(folder: str | Path) -> list[Path]:
    """The image files directly inside ``folder``, sorted by name, frames only."""
    return list_frames(folder)[0]


def list_frames(folder: str | Path) -> tuple[list[Path], list[Path]]:
    """(frames, left out): the render by-products among the images (a contact sheet, segmentation
    and depth images) are no samples of a domain and would bias FID/KID. A folder with no images of its
    own is read as a labelled real photo set (class folders such as State Farm's ``c0/ .. c9/``, YOLO,
    COCO or CSV: ``realphotos.layouts``), so that KID against it counts the photos ``transfer`` scores."""
    from ..render.outputs import by_product

    folder = Path(folder)
    if not folder.is_dir():
        raise InputNotFound(f"image folder {folder} does not exist")
    images = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    found = [p for p in images if not by_product(p)]
    if not found and not images:
        found = [p for p in _photo_set(folder) if not by_product(p)]
    if not found:
        raise ImageError(
            f"folder {folder} holds no images ({', '.join(IMAGE_SUFFIXES)}); point to a folder of images, "
            "a real photo set (class folders, YOLO, COCO or CSV), or a pairs directory as PAIRS_DIR:sim|real|nst")
    return found, [p for p in images if by_product(p)]


def _photo_set(folder: Path) -> list[Path]:
    """The photos of ``folder`` read as a real photo set, sorted by path; none where it is no such set. A set
    whose layout is recognised but cannot be read raises its own error (a broken data.yaml says so)."""
    from ..realphotos.layouts import detect_layout, read_photo_set

    try:
        layout = detect_layout(folder)
    except InputError:
        return []
    return sorted(photo.path for photo in read_photo_set(folder, layout).photos)
