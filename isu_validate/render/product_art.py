"""Printed and displayed surfaces of the things in the cabin, drawn in code (numpy), so every pixel is the
project's own and redistributable: a generic cola label (no brand, no trademark: a red band, a white
wave and the word COLA in a stroke type drawn here) and a phone's home screen (wallpaper, status bar
with the time, app icons, dock). Deterministic: the same image on every machine.

Images are float32 RGBA in [0, 1], row 0 at the top (the Blender worker flips them for ``Image.pixels``).
Small on purpose: Cycles does not mip-map, so a texture many texels to a pixel (a can 25 px across in a
frame) shimmers at 2 samples; these sizes keep a few texels a pixel in the frame and stay sharp enough in
a close-up.
Host-side and bpy-free, so they can be tested and looked at without Blender."""
from __future__ import annotations

import numpy as np

def _arc(cx, cy, rx, ry, a0, a1, n=14):
    return [(cx + rx * np.cos(np.radians(a)), cy + ry * np.sin(np.radians(a))) for a in np.linspace(a0, a1, n)]


# a stroke type for the few characters the label and the lock screen need: polylines in a unit cell
# (x right, y up), drawn with round pen ends, so letters have the curves of printed type
_STROKES = {
    "C": [_arc(0.55, 0.5, 0.45, 0.5, 50, 310)],
    "O": [_arc(0.5, 0.5, 0.45, 0.5, 0, 360, 24)],
    "L": [[(0.12, 1.0), (0.12, 0.0), (0.85, 0.0)]],
    "A": [[(0.0, 0.0), (0.5, 1.0), (1.0, 0.0)], [(0.22, 0.38), (0.78, 0.38)]],
    "0": [_arc(0.5, 0.5, 0.4, 0.5, 0, 360, 24)],
    "1": [[(0.3, 0.78), (0.55, 1.0), (0.55, 0.0)]],
    "2": [_arc(0.5, 0.72, 0.38, 0.28, 160, -20, 10) + [(0.1, 0.0), (0.9, 0.0)]],
    "3": [_arc(0.5, 0.75, 0.36, 0.25, 150, -90, 12), _arc(0.5, 0.27, 0.4, 0.27, 90, -150, 12)],
    "4": [[(0.7, 0.0), (0.7, 1.0), (0.08, 0.3), (0.95, 0.3)]],
    ":": [[(0.5, 0.22), (0.5, 0.22)], [(0.5, 0.72), (0.5, 0.72)]],
}
_WIDTH = {":": 0.5, "1": 0.75}

RED = (0.72, 0.03, 0.04)
WHITE = (0.95, 0.94, 0.92)


def cola_label(width: int = 256, height: int = 64) -> np.ndarray:
    """A label wrapped once round a bottle or can (u round it, v up): red, a white wave across it and
    COLA twice, on opposite sides."""
    img = np.empty((height, width, 4), np.float32)
    img[..., :3], img[..., 3] = RED, 1.0
    u = np.arange(width)[None, :] / width
    v = 1.0 - np.arange(height)[:, None] / height          # up the label
    wave = 0.28 + 0.09 * np.sin(2 * np.pi * (2 * u + 0.15))
    ribbon = (v > wave) & (v < wave + 0.07 + 0.03 * np.sin(2 * np.pi * (2 * u)))
    img[ribbon, :3] = WHITE
    for centre in (0.25, 0.75):
        _text(img, "COLA", (centre, 0.68), height * 0.42, WHITE, weight=0.22, slant=0.18)
    return img


def screen_lit(setting: str, at_ear: bool) -> bool:
    """Whether the held phone's screen glows: isu-diverse's ``phone_screen`` ON or OFF, or BY_USE: lit while
    read, dark at the ear (a phone position the cabin rig marks ``at_ear``: the proximity sensor turns it off
    in a call)."""
    return setting == "ON" or (setting == "BY_USE" and not at_ear)


def home_screen(width: int = 96, height: int = 200, seed: int = 3) -> np.ndarray:
    """A phone's lit home screen: a soft gradient wallpaper, a status bar, a 4x5 grid of app icons
    (rounded squares in assorted colours) and a dock of four."""
    rng = np.random.default_rng(seed)
    img = np.empty((height, width, 4), np.float32)
    y = np.linspace(0.0, 1.0, height)[:, None, None]
    top, bottom = np.array([0.16, 0.34, 0.62]), np.array([0.42, 0.20, 0.46])
    img[..., :3] = top * (1 - y) + bottom * y
    img[..., 3] = 1.0
    img[: height // 28, :, :3] *= 0.6                      # status bar
    _text(img, "10:24", (0.16, 1 - 0.5 / 28), height / 28 * 0.6, WHITE, weight=0.2)
    bar = height // 28
    img[bar // 4: bar - bar // 4, width - width // 8: width - width // 20, :3] = WHITE   # battery
    cols, rows, size = 4, 5, width // 6
    gap_x = (width - cols * size) / (cols + 1)
    for r in range(rows):
        for c in range(cols):
            x0 = int(gap_x + c * (size + gap_x))
            y0 = int(height * 0.10 + r * size * 1.55)
            _icon(img, x0, y0, size, rng)
    dock_y = int(height * 0.86)
    dock = img[dock_y - size // 4: dock_y + size + size // 4, :, :3]
    dock[:] = dock * 0.7 + 0.12                            # the dock's frosted band
    for c in range(cols):
        _icon(img, int(gap_x + c * (size + gap_x)), dock_y, size, rng)
    return img


def _icon(img: np.ndarray, x0: int, y0: int, size: int, rng) -> None:
    hue = rng.random()
    colour = np.clip(np.abs((hue * 6 + np.array([0, 4, 2])) % 6 - 3) - 1, 0, 1) * 0.85 + 0.1
    yy, xx = np.mgrid[0:size, 0:size]
    r = size * 0.25
    dx = np.maximum(np.maximum(r - xx, xx - (size - 1 - r)), 0)
    dy = np.maximum(np.maximum(r - yy, yy - (size - 1 - r)), 0)
    inside = dx ** 2 + dy ** 2 <= r ** 2
    patch = img[y0:y0 + size, x0:x0 + size, :3]
    patch[inside[:patch.shape[0], :patch.shape[1]]] = colour
    d = np.hypot(xx - (size - 1) / 2, yy - (size - 1) / 2) / size
    glyph = [d < 0.2, (d > 0.13) & (d < 0.24),                             # a white mark: dot, ring, bars
             (np.abs(xx - size / 2) < size * 0.25) & (np.abs(yy % (size / 4) - size / 8) < size * 0.05)
             & (yy > size * 0.2) & (yy < size * 0.8)][int(rng.integers(3))]
    patch[(glyph & inside)[:patch.shape[0], :patch.shape[1]]] = WHITE


def _text(img: np.ndarray, text: str, centre: tuple[float, float], cap_height: float, colour,
          weight: float = 0.16, slant: float = 0.0) -> None:
    """Stroke letters of ``cap_height`` px centred at (u, v) (fractions of the image), pen width
    ``weight`` of the height, leaning by ``slant`` (italic), anti-aliased."""
    h, w = img.shape[:2]
    advance = [cap_height * (_WIDTH.get(ch, 0.8) + 0.25) for ch in text]
    x = centre[0] * w - sum(advance) / 2
    base = (1 - centre[1]) * h + cap_height / 2                  # pixel row of the baseline
    pen = weight * cap_height / 2
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    ink = np.zeros((h, w), np.float32)
    for ch, step in zip(text, advance):
        for line in _STROKES[ch]:
            pts = [(x + cap_height * (px * _WIDTH.get(ch, 0.8) + slant * py), base - cap_height * py)
                   for px, py in line]
            for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
                ink = np.maximum(ink, np.clip(pen + 0.5 - _segment_distance(xx, yy, x0, y0, x1, y1), 0, 1))
        x += step
    img[..., :3] = img[..., :3] * (1 - ink[..., None]) + np.asarray(colour, np.float32) * ink[..., None]


def _segment_distance(xx, yy, x0, y0, x1, y1):
    dx, dy = x1 - x0, y1 - y0
    t = np.clip(((xx - x0) * dx + (yy - y0) * dy) / max(dx * dx + dy * dy, 1e-9), 0, 1)
    return np.hypot(xx - x0 - t * dx, yy - y0 - t * dy)


def navigation_screen(width: int = 260, height: int = 150, seed: int = 5) -> np.ndarray:
    """A car's centre display showing a map: pale blocks, grey streets, a blue route and a header bar."""
    rng = np.random.default_rng(seed)
    img = np.empty((height, width, 4), np.float32)
    img[..., :3], img[..., 3] = (0.86, 0.87, 0.84), 1.0
    for _ in range(9):                               # streets
        if rng.random() < 0.5:
            y = int(rng.integers(10, height))
            img[y:y + 4, :, :3] = 0.97
        else:
            x = int(rng.integers(0, width))
            img[:, x:x + 4, :3] = 0.97
    park = rng.integers(0, [width - 60, height - 40])
    img[park[1]:park[1] + 30, park[0]:park[0] + 50, :3] = (0.70, 0.84, 0.66)
    route_y = height // 2
    img[route_y:route_y + 5, width // 6:width * 5 // 6, :3] = (0.15, 0.45, 0.95)
    img[route_y - 40:route_y + 5, width * 5 // 6 - 5:width * 5 // 6, :3] = (0.15, 0.45, 0.95)
    img[:height // 8, :, :3] = (0.12, 0.13, 0.16)    # header bar
    return img


def instrument_dial(size: int = 128) -> np.ndarray:
    """One round gauge of an instrument cluster: a black face, white tick marks round 270 degrees,
    a red needle."""
    img = np.zeros((size, size, 4), np.float32)
    img[..., 3] = 1.0
    yy, xx = np.mgrid[0:size, 0:size]
    dx, dy = (xx - size / 2) / (size / 2), (size / 2 - yy) / (size / 2)
    r, angle = np.hypot(dx, dy), np.degrees(np.arctan2(dy, dx))
    img[..., :3] = 0.02
    sweep = ~((angle < -45) & (angle > -135))           # all but the bottom quarter
    ticks = sweep & (r > 0.78) & (r < 0.92) & (np.abs((angle + 360) % 22.5 - 11.25) > 9.5)
    img[ticks, :3] = 0.9
    needle_dir = np.radians(150)
    along = dx * np.cos(needle_dir) + dy * np.sin(needle_dir)
    across = np.abs(-dx * np.sin(needle_dir) + dy * np.cos(needle_dir))
    img[(along > 0) & (along < 0.8) & (across < 0.035), :3] = (0.9, 0.1, 0.05)
    img[r > 0.97, :3] = 0.35                               # chrome ring
    return img
