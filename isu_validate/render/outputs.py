"""From the worker's EXR to the files a user gets: sRGB PNG, instance/semantic segmentation with a
class map, depth, linear EXR; all warped through the rig's lens."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from ..exr import read_exr, write_exr
from ..srgb import srgb_encode
from .camera import PinholePlan, warp
from .footprint import unpack_counts
from .labels import INSTANCES, class_map, semantic_lut

CHANNELS = ("seg", "depth", "exr")
# What a frame x.png gets beside it (x.seg.png, ...), and the sheet `render --random` adds to a folder:
# files that are not frames, which image sets (FID/KID) must leave out.
BESIDE = {"seg": ".seg.png", "semantic": ".semantic.png", "classes": ".seg.json", "depth": ".depth.png",
          "exr": ".exr", "label": ".label.json"}
CONTACT_SHEET = "contact_sheet.png"


def parse_channels(channels) -> tuple[str, ...]:
    if isinstance(channels, str):
        channels = [c for c in channels.split(",") if c.strip()]
    channels = tuple(sorted({c.strip() for c in channels}))
    unknown = [c for c in channels if c not in CHANNELS]
    if unknown:
        from ..errors import InputError   # the user's --channels
        raise InputError(f"unknown render channel(s) {', '.join(unknown)}; channels: {', '.join(CHANNELS)}")
    return channels


def _pass(passes: dict, suffix: str) -> np.ndarray:
    for name, data in passes.items():
        if name.endswith(suffix):
            return data
    raise KeyError(f"render pass {suffix!r} missing from the worker's EXR (have {', '.join(passes)})")


def channel_paths(out: Path) -> dict[str, Path]:
    """Where each output goes, beside the image: images/x.png -> images/x.seg.png etc."""
    stem = out.with_suffix("")
    return {name: stem.with_name(stem.name + suffix) for name, suffix in BESIDE.items()}


def read_label(frame: Path) -> dict | None:
    """The render label written beside a frame (its scene, instance boxes, what it hid), or None where it has none."""
    path = channel_paths(Path(frame))["label"]
    return json.loads(path.read_text()) if path.is_file() else None


def by_product(path: str | Path) -> str | None:
    """What a render output that is not a frame is ("contact sheet", "seg channel"...), or None for a frame."""
    name = Path(path).name
    if name == CONTACT_SHEET:
        return "contact sheet"
    return next((f"{channel} channel" for channel, suffix in BESIDE.items() if name.endswith(suffix)), None)


def write_outputs(exr_path: Path, plan: PinholePlan, out: Path, channels: tuple[str, ...],
                  develop=srgb_encode) -> tuple[dict, dict]:
    """Write the image and requested channels; return (paths by channel, per-instance visibility).
    ``develop`` turns the warped linear RGB into the 8-bit image: sRGB, or the rig camera's imaging
    model (exposure, response, noise, colour; see ``renderer.BlenderRenderer._develop``)."""
    passes = read_exr(exr_path)
    rgb = np.dstack([_pass(passes, f"Combined.{c}") for c in "RGB"])
    rgb = warp(rgb, plan)
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), cv2.cvtColor(develop(rgb), cv2.COLOR_RGB2BGR)):
        raise OSError(f"could not write {out}")
    paths, where = {}, channel_paths(out)
    ids = warp(np.rint(_pass(passes, "Index.X")).astype(np.uint16), plan, nearest=True)
    visible = _visibility(ids)
    if "seg" in channels:
        cv2.imwrite(str(where["seg"]), ids)
        cv2.imwrite(str(where["semantic"]), semantic_lut()[np.minimum(ids, len(semantic_lut()) - 1)])
        where["classes"].write_text(json.dumps({**class_map(), "visible": visible}, indent=1))
        paths.update(seg=where["seg"], semantic=where["semantic"], classes=where["classes"])
    if "depth" in channels:
        z = warp(_pass(passes, "Depth.Z"), plan, nearest=True)
        mm = np.where(z < 65.0, np.rint(z * 1000.0), 0).astype(np.uint16)   # 0 = nothing within 65 m
        cv2.imwrite(str(where["depth"]), mm)
        paths["depth"] = where["depth"]
    if "exr" in channels:
        write_exr(where["exr"], {c: rgb[..., i] for i, c in enumerate("RGB")})
        paths["exr"] = where["exr"]
    return paths, visible


def _visibility(ids: np.ndarray) -> dict:
    """Pixel count and bounding box (x0, y0, x1, y1) of every visible instance."""
    out = {}
    counts = np.bincount(ids.ravel(), minlength=max(INSTANCES) + 1)
    for i, n in enumerate(counts):
        if n and i in INSTANCES:
            ys, xs = np.nonzero(ids == i)
            out[INSTANCES[i][0]] = {"id": i, "pixels": int(n),
                                    "bbox": [int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())]}
    return out


def footprint_pixels(path: Path, plan: PinholePlan, parts: list[str]) -> dict[str, int]:
    """Pixel count of each part's unoccluded footprint (the worker's packed masks), after the same
    lens warp as the segmentation."""
    planes = np.load(path)
    warped = np.stack([warp(plane, plan, nearest=True) for plane in planes])
    return dict(zip(parts, unpack_counts(warped, len(parts))))
