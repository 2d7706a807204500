"""Read and write uncompressed scanline OpenEXR files (enough for Blender's multilayer render output).

The renderer writes its linear passes in it (``render/outputs.py``); the camera model reads them back
(``exposure apply``, ``exposure fit --sim``, ``exposure colour --sim X.exr``). A leaf: imports numpy only.

Why our own: neither OpenCV nor imageio read Blender's multilayer EXR, and the worker writes its passes
uncompressed (compression would cost more than the disk traffic it saves on a local temp file)."""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

_MAGIC = 20000630
_TYPES = {0: np.dtype("<u4"), 1: np.dtype("<f2"), 2: np.dtype("<f4")}


def _cstring(buf: bytes, pos: int) -> tuple[str, int]:
    end = buf.index(b"\0", pos)
    return buf[pos:end].decode(), end + 1


def _headers(buf: bytes) -> tuple[list[dict], int, bool]:
    """The part headers (one, or several for multi-part files: Blender 5 writes one part per pass)."""
    magic, version = struct.unpack_from("<ii", buf, 0)
    if magic != _MAGIC:
        raise ValueError("not an OpenEXR file")
    if version & 0x200:
        raise ValueError("tiled EXR is not supported (write scanline EXR)")
    multipart = bool(version & 0x1000)
    pos, headers = 8, []
    while True:
        attrs = {}
        while buf[pos] != 0:
            name, pos = _cstring(buf, pos)
            kind, pos = _cstring(buf, pos)
            (size,) = struct.unpack_from("<i", buf, pos)
            pos += 4
            attrs[name] = (kind, buf[pos:pos + size])
            pos += size
        pos += 1
        headers.append(attrs)
        if not multipart or buf[pos] == 0:
            return headers, pos + (1 if multipart else 0), multipart


def _channels(raw: bytes) -> list[tuple[str, int]]:
    out, pos = [], 0
    while raw[pos] != 0:
        name, pos = _cstring(raw, pos)
        (ptype,) = struct.unpack_from("<i", raw, pos)
        pos += 16  # pixel type, pLinear + reserved, x and y sampling
        out.append((name, ptype))
    return out


def read_exr(path: str | Path) -> dict[str, np.ndarray]:
    """Every channel of an uncompressed scanline EXR, as float32 (H, W) arrays keyed by channel name
    (prefixed with the part name, as in ``ViewLayer.Depth.V``, when a multi-part file names its parts)."""
    buf = Path(path).read_bytes()
    raw = np.frombuffer(buf, dtype=np.uint8)
    headers, pos, multipart = _headers(buf)
    out = {}
    for attrs in headers:
        if attrs["compression"][1][0] != 0:
            raise ValueError(f"{path}: compressed EXR; the reader handles uncompressed files only")
        xmin, ymin, xmax, ymax = struct.unpack("<iiii", attrs["dataWindow"][1])
        width, height = xmax - xmin + 1, ymax - ymin + 1
        channels = _channels(attrs["channels"][1])
        offsets = np.frombuffer(buf, dtype="<u8", count=height, offset=pos).astype(np.int64)
        pos += 8 * height
        row_dtype = np.dtype([(name, _TYPES[t], (width,)) for name, t in channels])
        skip = 12 if multipart else 8          # [part,] y, data size
        ys = np.array([struct.unpack_from("<i", buf, int(o) + skip - 8)[0] for o in offsets])
        rows = raw[offsets[:, None] + skip + np.arange(row_dtype.itemsize)].copy().view(row_dtype)[:, 0]
        order = np.argsort(ys)
        part = attrs["name"][1].decode() + "." if multipart and "name" in attrs else ""
        for name, _ in channels:
            key = name if name.startswith(part) else part + name
            out[key] = rows[name][order].astype(np.float32)
    return out


def write_exr(path: str | Path, channels: dict[str, np.ndarray]) -> None:
    """Write float32 (H, W) channels as an uncompressed scanline EXR (e.g. {"R":..., "G":..., "B":...})."""
    names = sorted(channels)
    height, width = channels[names[0]].shape
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1) for n in names) + b"\0"

    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data

    header = struct.pack("<ii", _MAGIC, 2) + b"".join([
        attr("channels", "chlist", chlist),
        attr("compression", "compression", b"\0"),
        attr("dataWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1)),
        attr("displayWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1)),
        attr("lineOrder", "lineOrder", b"\0"),
        attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0)),
        attr("screenWindowWidth", "float", struct.pack("<f", 1.0)),
    ]) + b"\0"
    row_bytes = 4 * width * len(names)
    start = len(header) + 8 * height
    offsets = np.arange(height, dtype="<u8") * (8 + row_bytes) + start
    data = np.stack([channels[n].astype("<f4") for n in names], axis=1)  # (H, C, W)
    with open(path, "wb") as fh:
        fh.write(header)
        fh.write(offsets.tobytes())
        for y in range(height):
            fh.write(struct.pack("<ii", y, row_bytes))
            fh.write(data[y].tobytes())
