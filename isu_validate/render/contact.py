"""A contact sheet: all frames of a folder tiled into one PNG, each captioned with its name."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np


def contact_sheet(images: Sequence[Path], out: Path, tile_width: int = 320, columns: int | None = None) -> Path:
    if not images:
        raise ValueError("no images for the contact sheet")
    columns = columns or min(len(images), max(1, round(math.sqrt(len(images) * 1.3))))
    first = cv2.imread(str(images[0]))
    tile_h = round(first.shape[0] * tile_width / first.shape[1])
    rows = math.ceil(len(images) / columns)
    sheet = np.full((rows * (tile_h + 18), columns * tile_width, 3), 24, np.uint8)
    for k, path in enumerate(images):
        img = cv2.imread(str(path))
        if img is None:
            continue
        r, c = divmod(k, columns)
        y, x = r * (tile_h + 18), c * tile_width
        sheet[y:y + tile_h, x:x + tile_width] = cv2.resize(img, (tile_width, tile_h), interpolation=cv2.INTER_AREA)
        cv2.putText(sheet, Path(path).stem, (x + 4, y + tile_h + 13), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                    (230, 230, 230), 1, cv2.LINE_AA)
    cv2.imwrite(str(out), sheet)
    return out
