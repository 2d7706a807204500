"""Unoccluded footprints: the pixels a part would cover with nothing in front of it.

The Blender worker hands each part's evaluated triangles, in the render camera's OpenCV frame, to
``footprints``, which cuts them at the near plane, projects them into the pinhole image Blender renders
and fills them; the union of a part's triangles is its footprint, so the part's own back faces and folds do not
matter. The masks go back to the host packed as bits of uint16 planes (``pack``), which warps them
through the rig's lens exactly like the segmentation pass and counts pixels (``unpack_counts``).

Pure numpy (no bpy), so it is tested without Blender. A pixel is covered when its centre
(integer coordinates, OpenCV) lies inside a triangle, edges included."""
from __future__ import annotations

import numpy as np

NEAR_M = 0.02          # the render camera's clip_start: nothing nearer is drawn, by Blender either


def clip_near(triangles: np.ndarray, near: float = NEAR_M) -> np.ndarray:
    """Camera-frame triangles (T,3,3) cut at the plane z = near: wholly behind it they go, crossing
    it they become the one or two triangles of the part in front (Sutherland-Hodgman, one plane)."""
    triangles = np.asarray(triangles, float).reshape(-1, 3, 3)
    front = triangles[..., 2] >= near
    keep = triangles[front.all(axis=1)]
    crossing = triangles[front.any(axis=1) & ~front.all(axis=1)]
    pieces = []
    for tri in crossing:   # few: only triangles straddling the camera's near plane
        polygon = []
        for a, b in zip(tri, np.roll(tri, -1, axis=0)):
            if a[2] >= near:
                polygon.append(a)
            if (a[2] >= near) != (b[2] >= near):
                s = (near - a[2]) / (b[2] - a[2])
                polygon.append(a + s * (b - a))
        pieces += [np.array([polygon[0], polygon[i], polygon[i + 1]]) for i in range(1, len(polygon) - 1)]
    return np.concatenate([keep, np.array(pieces).reshape(-1, 3, 3)]) if pieces else keep


def project(triangles_cam: np.ndarray, f: float, cx: float, cy: float) -> np.ndarray:
    """Pixel coordinates (T,3,2) of camera-frame triangles in front of the near plane."""
    z = triangles_cam[..., 2:3]
    return np.concatenate([f * triangles_cam[..., 0:1] / z + cx, f * triangles_cam[..., 1:2] / z + cy], axis=-1)


def fill_parts(parts_px: list[np.ndarray], width: int, height: int) -> np.ndarray:
    """Boolean (parts, height, width) masks: the union of each part's triangles (T,3,2), in pixels.

    Scanlines, vectorised over every triangle of every part at once: a triangle crosses each pixel row
    it spans in one run of pixel centres; the runs are summed into per-row difference arrays whose
    running sum is positive inside the union. The work grows with the rows crossed, not the pixels
    covered."""
    sizes = [len(t) for t in parts_px]
    tri = np.concatenate([np.asarray(t, np.float64).reshape(-1, 3, 2) for t in parts_px]) if parts_px \
        else np.zeros((0, 3, 2))
    part = np.repeat(np.arange(len(sizes)), sizes)
    finite = np.isfinite(tri).all(axis=(1, 2))
    tri, part = tri[finite], part[finite]
    ys = tri[..., 1]
    y0 = np.maximum(np.ceil(ys.min(axis=1, initial=np.inf)), 0).astype(np.int64)
    y1 = np.minimum(np.floor(ys.max(axis=1, initial=-np.inf)), height - 1).astype(np.int64)
    rows = np.maximum(y1 - y0 + 1, 0)
    which = np.repeat(np.arange(len(tri)), rows)                      # one entry per (triangle, row)
    y = y0[which] + np.arange(len(which)) - np.repeat(np.cumsum(rows) - rows, rows)
    xmin, xmax = _row_spans(tri[which], y.astype(np.float64))
    left = np.maximum(np.ceil(xmin), 0).astype(np.int64)
    right = np.minimum(np.floor(xmax), width - 1).astype(np.int64)
    keep = left <= right
    stride, size = width + 1, len(sizes) * height * (width + 1)
    row_start = (part[which][keep] * height + y[keep]) * stride
    runs = (np.bincount(row_start + left[keep], minlength=size)
            - np.bincount(row_start + right[keep] + 1, minlength=size))
    return np.cumsum(runs.reshape(len(sizes), height, stride), axis=2)[..., :width] > 0


def _row_spans(tri: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The x extent of each triangle (N,3,2) on its row y (N,), edges included (NaN: not crossed)."""
    xmin = np.full(len(y), np.inf)
    xmax = np.full(len(y), -np.inf)
    for k in range(3):
        p, q = tri[:, k], tri[:, (k + 1) % 3]
        dy = q[:, 1] - p[:, 1]
        crossed = (y >= np.minimum(p[:, 1], q[:, 1])) & (y <= np.maximum(p[:, 1], q[:, 1]))
        flat = dy == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            x = p[:, 0] + (y - p[:, 1]) * (q[:, 0] - p[:, 0]) / dy
        lo = np.where(flat, np.minimum(p[:, 0], q[:, 0]), x)   # a horizontal edge on the row: all of it
        hi = np.where(flat, np.maximum(p[:, 0], q[:, 0]), x)
        xmin = np.where(crossed, np.minimum(xmin, lo), xmin)
        xmax = np.where(crossed, np.maximum(xmax, hi), xmax)
    return xmin, xmax


def footprints(parts_cam: list[np.ndarray], f: float, cx: float, cy: float, width: int, height: int) -> np.ndarray:
    """Masks (parts, H, W) that the parts' camera-frame triangles (T,3,3 each) cover in the pinhole image."""
    return fill_parts([project(clip_near(t), f, cx, cy) for t in parts_cam], width, height)


def orientation(vertices: np.ndarray, faces: np.ndarray, closed: bool | None = None) -> int:
    """+1 for a closed mesh whose triangles all wind outwards, -1 all inwards, 0 for an open or
    inconsistently wound one. Seen from outside, a closed mesh's silhouette is the union of its
    camera-facing triangles, so the others can be dropped (half the work); open meshes keep all.
    ``closed`` (from ``is_closed(faces)``) skips the edge check, which depends on the faces only."""
    if not len(faces) or not (is_closed(faces) if closed is None else closed):
        return 0
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    volume = np.einsum("ij,ij->", a, np.cross(b, c))   # six times the signed volume
    return int(np.sign(volume))


def is_closed(faces: np.ndarray) -> bool:
    """Whether triangles (F,3) form a closed, consistently wound surface: every directed edge once,
    and its reverse present exactly once too."""
    if not len(faces):
        return False
    directed = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1).reshape(-1, 2).astype(np.int64)
    n = int(directed.max()) + 1
    forward = directed[:, 0] * n + directed[:, 1]
    backward = directed[:, 1] * n + directed[:, 0]
    return len(np.unique(forward)) == len(forward) and np.array_equal(np.sort(forward), np.sort(backward))


def facing_camera(triangles_cam: np.ndarray, orient: int) -> np.ndarray:
    """Which camera-frame triangles (T,3,3) of a mesh with ``orientation`` ``orient`` face the camera
    (at the origin); edge-on ones count as facing."""
    a, b, c = triangles_cam[:, 0], triangles_cam[:, 1], triangles_cam[:, 2]
    return orient * np.einsum("ij,ij->i", np.cross(b - a, c - a), a) <= 0


def pack(masks) -> np.ndarray:
    """Masks as bits of uint16 planes (planes, H, W): bit k of plane k // 16 is mask k. Nearest-neighbour
    warping moves whole values, so the packed planes go through the lens warp like the seg pass."""
    height, width = masks[0].shape if len(masks) else (0, 0)
    planes = np.zeros((max(1, -(-len(masks) // 16)), height, width), np.uint16)
    for k, m in enumerate(masks):
        planes[k // 16] |= (m.astype(np.uint16) << np.uint16(k % 16))
    return planes


def unpack_counts(planes: np.ndarray, n: int) -> list[int]:
    """Pixel count of each of the ``n`` packed masks."""
    return [int(np.count_nonzero(planes[k // 16] & np.uint16(1 << (k % 16)))) for k in range(n)]
