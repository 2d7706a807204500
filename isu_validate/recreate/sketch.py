"""A top view of the cabin (SVG) with where things go: front at the top, the driver's side on the left.

Text is laid out apart from the markers: each label (seat names, angles, "origin", "camera") takes the
first of a few places around its anchor that overlaps nothing drawn before it (marker discs, object
footprints, other labels), so a number never sits on a seat's name."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..analysis.html import esc
from .guide import Item

SCALE = 120.0   # SVG units per metre
PAD = 14.0
FONT = 10.0
CHAR_W = 0.6 * FONT   # average advance of a sans-serif character at FONT (text width estimate)
MARKER_R = 7.0


@dataclass(frozen=True)
class Box:
    """An axis-aligned box in SVG units: left, top, right, bottom."""
    x0: float
    y0: float
    x1: float
    y1: float

    def overlap(self, other: "Box") -> float:
        w = min(self.x1, other.x1) - max(self.x0, other.x0)
        h = min(self.y1, other.y1) - max(self.y0, other.y0)
        return w * h if w > 0 and h > 0 else 0.0


class Layout:
    """What is drawn so far, as boxes; labels are placed where they overlap it least (first best)."""

    def __init__(self, width: float, height: float):
        self.taken: list[Box] = []
        self.bounds = Box(0.0, 0.0, width, height)

    def take(self, box: Box) -> None:
        self.taken.append(box)

    def label(self, text: str, candidates: list[tuple[float, float, str]], **attrs: str) -> str:
        """Place ``text`` at the first candidate (x, y baseline, anchor start|end|middle) clear of what is
        drawn and inside the view, else at the one overlapping least; returns the SVG text element."""
        width = CHAR_W * len(text)

        def box(x: float, y: float, anchor: str) -> Box:
            left = x - {"start": 0.0, "middle": width / 2, "end": width}[anchor]
            return Box(left, y - 0.8 * FONT, left + width, y + 0.25 * FONT)

        def cost(c) -> float:
            b = box(*c)
            outside = 0.0 if (b.x0 >= self.bounds.x0 and b.x1 <= self.bounds.x1 and b.y0 >= self.bounds.y0
                              and b.y1 <= self.bounds.y1) else 1e6
            return outside + sum(b.overlap(t) for t in self.taken)

        x, y, anchor = min(candidates, key=cost)   # min keeps the first of equal costs: the preferred place
        self.take(box(x, y, anchor))
        extra = "".join(f' {k.replace("_", "-")}="{v}"' for k, v in attrs.items())
        return (f'<text x="{x:.1f}" y="{y:.1f}" font-size="{FONT:g}" text-anchor="{anchor}"{extra}>'
                f'{esc(text)}</text>')


def top_view(cabin: dict, items: list[Item], camera: tuple[float, float] | None = None) -> str:
    """The sketch, or "" when nothing in the scene has a measured point; ``camera``: its (x, y)."""
    placed = [i for i in items if i.placement and i.placement.point]
    if not placed:
        return ""
    shell = cabin["shell"]
    half, x_front, x_rear = float(shell["half_width"]), float(shell["x_front"]), float(shell["x_rear"])

    def uv(x: float, y: float) -> tuple[float, float]:
        return PAD + (half - y) * SCALE, PAD + (x_front - x) * SCALE

    width, height = 2 * half * SCALE + 2 * PAD, (x_front - x_rear) * SCALE + 2 * PAD
    layout = Layout(width, height)
    shapes = [f'<rect x="{PAD}" y="{PAD}" width="{2 * half * SCALE:.1f}" height="{(x_front - x_rear) * SCALE:.1f}" '
              'rx="18" fill="#f4f5f7" stroke="#555" stroke-width="2"/>']
    seats = []
    for name, seat in (cabin.get("seats") or {}).items():
        x, y, _ = seat["cushion"]
        u, v = uv(x + seat["depth"] / 2, y + seat["width"] / 2)
        w, d = seat["width"] * SCALE, seat["depth"] * SCALE
        shapes.append(f'<rect x="{u:.1f}" y="{v:.1f}" width="{w:.1f}" height="{d:.1f}" rx="6" fill="#dfe3ea" '
                      'stroke="#9aa3b1"/>')
        seats.append((name, Box(u, v, u + w, v + d)))
    wheel = cabin.get("steering_wheel")
    if wheel:
        u, v = uv(wheel["centre"][0], wheel["centre"][1])
        shapes.append(f'<line x1="{u - wheel["radius"] * SCALE:.1f}" y1="{v:.1f}" '
                      f'x2="{u + wheel["radius"] * SCALE:.1f}" '
                      f'y2="{v:.1f}" stroke="#555" stroke-width="5" stroke-linecap="round"/>')
    things = [_thing(item, n, uv, layout) for n, item in enumerate(placed, 1)]   # markers first: labels avoid them
    u0, v0 = uv(0.0, 0.0)
    layout.take(Box(u0 - 3, v0 - 3, u0 + 3, v0 + 3))
    marks = [f'<circle cx="{u0:.1f}" cy="{v0:.1f}" r="3" fill="#000"/>']
    if camera is not None:
        cu, cv = uv(*camera)
        layout.take(Box(cu - 6, cv - 4, cu + 6, cv + 4))
        marks.append(f'<rect x="{cu - 6:.1f}" y="{cv - 4:.1f}" width="12" height="8" fill="#c62828"/>')
    labels = [layout.label(text, candidates, fill=colour) for text, candidates, colour in _angle_labels(placed, uv)]
    for name, b in seats:   # inside the seat's corners, then just outside its front and rear edges
        labels.append(layout.label(name, [(b.x0 + 4, b.y0 + 12, "start"), (b.x1 - 4, b.y0 + 12, "end"),
                                          (b.x0 + 4, b.y1 - 4, "start"), (b.x1 - 4, b.y1 - 4, "end"),
                                          (b.x0 + 2, b.y0 - 3, "start"), (b.x0 + 2, b.y1 + 10, "start")],
                                   fill="#6b7380"))
    labels.append(layout.label("origin", [(u0 + 5, v0 - 4, "start"), (u0 - 5, v0 - 4, "end"),
                                          (u0 + 5, v0 + 12, "start"), (u0 - 5, v0 + 12, "end")]))
    if camera is not None:
        labels.append(layout.label("camera", [(cu + 8, cv + 3, "start"), (cu - 8, cv + 3, "end"),
                                              (cu, cv - 7, "middle"), (cu, cv + 14, "middle")], fill="#c62828"))
    labels.append(f'<text x="{width / 2:.1f}" y="{PAD - 3:.1f}" font-size="{FONT:g}" text-anchor="middle">front</text>')
    return (f'<svg class="sketch" viewBox="0 0 {width:.0f} {height:.0f}" xmlns="http://www.w3.org/2000/svg" '
            f'role="img" aria-label="top view of the cabin">{"".join(shapes + things + marks + labels)}</svg>')


def _thing(item: Item, n: int, uv, layout: Layout) -> str:
    """A placed thing: its footprint (turned), the direction it faces, and its numbered marker."""
    p = item.placement
    x, y, _ = p.point
    u, v = uv(x, y)
    out = []
    if p.footprint:
        length, width = p.footprint
        a = math.radians(p.angle_deg or 0.0)
        front, side = (math.cos(a), math.sin(a)), (-math.sin(a), math.cos(a))
        corners = [uv(x + sl * front[0] * length / 2 + sw * side[0] * width / 2,
                      y + sl * front[1] * length / 2 + sw * side[1] * width / 2)
                   for sl, sw in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
        points = " ".join(f"{cu:.1f},{cv:.1f}" for cu, cv in corners)
        out.append(f'<polygon points="{points}" fill="#f2c14e88" stroke="#b07d00" stroke-width="1.5"/>')
        if p.angle_deg is not None:
            tip = uv(x + front[0] * length * 0.7, y + front[1] * length * 0.7)
            out.append(f'<line x1="{u:.1f}" y1="{v:.1f}" x2="{tip[0]:.1f}" y2="{tip[1]:.1f}" stroke="#b07d00" '
                       f'stroke-width="2"/>')
            layout.take(Box(min(u, tip[0]), min(v, tip[1]), max(u, tip[0]), max(v, tip[1])))
    layout.take(Box(u - MARKER_R, v - MARKER_R, u + MARKER_R, v + MARKER_R))
    out.append(f'<circle cx="{u:.1f}" cy="{v:.1f}" r="{MARKER_R:g}" fill="#1d2f4f"/>'
               f'<text x="{u:.1f}" y="{v + 3.5:.1f}" font-size="{FONT:g}" fill="#fff" text-anchor="middle">{n}</text>')
    return "".join(out)


def _angle_labels(placed: list[Item], uv) -> list[tuple[str, list[tuple[float, float, str]], str]]:
    """The turn of each turned thing, written beside the tip of its direction line."""
    out = []
    for item in placed:
        p = item.placement
        if not p.footprint or p.angle_deg is None:
            continue
        x, y, _ = p.point
        a = math.radians(p.angle_deg)
        tu, tv = uv(x + math.cos(a) * p.footprint[0] * 0.7, y + math.sin(a) * p.footprint[0] * 0.7)
        out.append((f"{p.angle_deg:.0f}°", [(tu + 3, tv, "start"), (tu - 3, tv, "end"), (tu, tv - 4, "middle"),
                                             (tu, tv + 11, "middle")], "#000"))
    return out
