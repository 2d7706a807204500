"""A top view of the cabin (SVG) with where things go: front at the top, the driver's side on the left."""
from __future__ import annotations

import math

from ..analysis.html import esc
from .guide import Item

SCALE = 120.0   # SVG units per metre
PAD = 14.0


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
    parts = [f'<rect x="{PAD}" y="{PAD}" width="{2 * half * SCALE:.1f}" height="{(x_front - x_rear) * SCALE:.1f}" '
             'rx="18" fill="#f4f5f7" stroke="#555" stroke-width="2"/>']
    for name, seat in (cabin.get("seats") or {}).items():
        x, y, _ = seat["cushion"]
        u, v = uv(x + seat["depth"] / 2, y + seat["width"] / 2)
        parts.append(f'<rect x="{u:.1f}" y="{v:.1f}" width="{seat["width"] * SCALE:.1f}" '
                     f'height="{seat["depth"] * SCALE:.1f}" rx="6" fill="#dfe3ea" stroke="#9aa3b1"/>'
                     f'<text x="{u + 4:.1f}" y="{v + 12:.1f}" font-size="10" fill="#6b7380">{esc(name)}</text>')
    wheel = cabin.get("steering_wheel")
    if wheel:
        u, v = uv(wheel["centre"][0], wheel["centre"][1])
        parts.append(f'<line x1="{u - wheel["radius"] * SCALE:.1f}" y1="{v:.1f}" x2="{u + wheel["radius"] * SCALE:.1f}" '
                     f'y2="{v:.1f}" stroke="#555" stroke-width="5" stroke-linecap="round"/>')
    for n, item in enumerate(placed, 1):
        parts.append(_thing(item, n, uv))
    if camera is not None:
        cu, cv = uv(*camera)
        parts.append(f'<rect x="{cu - 6:.1f}" y="{cv - 4:.1f}" width="12" height="8" fill="#c62828"/>'
                     f'<text x="{cu + 8:.1f}" y="{cv + 3:.1f}" font-size="10" fill="#c62828">camera</text>')
    u0, v0 = uv(0.0, 0.0)
    parts.append(f'<circle cx="{u0:.1f}" cy="{v0:.1f}" r="3" fill="#000"/>'
                 f'<text x="{u0 + 5:.1f}" y="{v0 - 4:.1f}" font-size="10">origin</text>'
                 f'<text x="{width / 2:.1f}" y="{PAD - 3:.1f}" font-size="10" text-anchor="middle">front</text>')
    return (f'<svg class="sketch" viewBox="0 0 {width:.0f} {height:.0f}" xmlns="http://www.w3.org/2000/svg" '
            f'role="img" aria-label="top view of the cabin">{"".join(parts)}</svg>')


def _thing(item: Item, n: int, uv) -> str:
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
                       f'stroke-width="2"/><text x="{tip[0] + 3:.1f}" y="{tip[1]:.1f}" font-size="10">'
                       f'{p.angle_deg:.0f}°</text>')
    out.append(f'<circle cx="{u:.1f}" cy="{v:.1f}" r="7" fill="#1d2f4f"/>'
               f'<text x="{u:.1f}" y="{v + 3.5:.1f}" font-size="10" fill="#fff" text-anchor="middle">{n}</text>')
    return "".join(out)
