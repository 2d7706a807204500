"""Printable recreation sheets (one A4 page per sample) and ``PAIRS/index.html`` with all of them.

Everything that came from a file is escaped; the target render is linked (relative path), the
crops around what a feature shows are embedded, so a sheet prints from the pairs folder alone.
"""
from __future__ import annotations

import base64
import io
from dataclasses import dataclass, field
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from ..analysis.html import esc, fmt
from ..pairs import Sample
from .guide import AXES, Item, sketch_number
from .sketch import top_view

CROP_MARGIN = 0.6   # share of the box added on each side: the hand around the phone, the seat around the child
CROP_MIN_PX = 36
CROP_OUT_PX = 170

PRINT_CSS = """
@page{size:A4;margin:11mm}
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;color:#1d2330;margin:0;font-size:12.5px}
.sheet{box-sizing:border-box;width:188mm;min-height:272mm;margin:0 auto 18px;padding:6mm;background:#fff;
 page-break-after:always;break-after:page;overflow:hidden}
.sheet:last-child{page-break-after:auto;break-after:auto}
.sheet h1{font-size:19px;margin:0 0 2px}.sub{color:#555;margin:0 0 6px}
img.target{display:block;width:100%;max-height:92mm;object-fit:contain;background:#222;margin:4px 0}
table{border-collapse:collapse;width:100%;font-size:11px}
td,th{border-bottom:1px solid #ccd;padding:2px 4px;text-align:left;vertical-align:top}
td.box{width:12px;font-size:13px}th{background:#eef1f5}
.cols{display:flex;gap:8px;align-items:flex-start;margin-top:4px}.cols table{flex:1}
.side{width:58mm;flex:none}svg.sketch{width:58mm;display:block}
.crops figure{display:inline-block;margin:4px 4px 0 0;width:27mm}.crops img{width:27mm;border:1px solid #ccd}
figcaption{font-size:9px;color:#555}
.note{color:#555;font-size:11px}.overview{width:188mm;margin:0 auto 18px;padding:6mm;background:#fff}
@media screen{body{background:#e9ecf1;padding:12px}}
@media print{.overview{page-break-after:always;break-after:page}}
"""


@dataclass
class SheetInfo:
    position: int                   # 1-based place in the recreation order
    total: int
    source: str                     # run name and test id
    failed: bool
    changes: list[str] = field(default_factory=list)   # what changes from the previous sample
    minutes: float = 0.0


def crop_uri(sample: Sample, parts: tuple[str, ...]) -> str | None:
    """A JPEG data URI of the render around the named instances (from the render's label), or None."""
    visible = sample.render_label().get("visible", {})
    boxes = [visible[p]["bbox"] for p in parts if isinstance(visible.get(p), dict) and "bbox" in visible[p]]
    if not boxes:
        return None
    x0, y0 = min(b[0] for b in boxes), min(b[1] for b in boxes)
    x1, y1 = max(b[2] for b in boxes), max(b[3] for b in boxes)
    mx, my = max(CROP_MIN_PX, (x1 - x0) * CROP_MARGIN), max(CROP_MIN_PX, (y1 - y0) * CROP_MARGIN)
    try:
        with Image.open(sample.sim) as img:
            box = (max(0, int(x0 - mx)), max(0, int(y0 - my)), min(img.width, int(x1 + mx + 1)),
                   min(img.height, int(y1 + my + 1)))
            crop = img.convert("RGB").crop(box)
    except (OSError, UnidentifiedImageError):
        return None
    scale = CROP_OUT_PX / max(crop.size)
    crop = crop.resize((max(1, round(crop.width * scale)), max(1, round(crop.height * scale))), Image.LANCZOS)
    buf = io.BytesIO()
    crop.save(buf, format="JPEG", quality=88)
    return "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def sheet_html(sample: Sample, items: list[Item], cabin: dict, info: SheetInfo, image_href: str,
               camera_text: str, camera_xy: tuple[float, float] | None = None) -> str:
    """One sheet as an HTML fragment (``<section class="sheet">``)."""
    rows = []
    for item in items:
        where = item.placement.text if item.placement else ""
        number = sketch_number(items, item)   # the sketch numbers what it draws; the checklist shows the same
        mark = f" ({number})" if number else ""
        rows.append(f'<tr><td class="box">☐</td><td>{esc(item.title)}{esc(mark)}</td><td>{esc(item.text)}</td>'
                    f"<td>{esc(where)}</td></tr>")
    crops = []
    for item in items:
        if item.crop_parts and (uri := crop_uri(sample, item.crop_parts)):
            crops.append(f'<figure><img src="{esc(uri)}" alt="{esc(item.title)}"><figcaption>{esc(item.title)}: '
                         f"{esc(item.text)}</figcaption></figure>")
    changes = ", ".join(info.changes) if info.changes else "nothing but the capture"
    lead = ("first scene: set up everything below" if info.position == 1
            else f"change from the previous sheet: {changes}")
    sketch = top_view(cabin, items, camera_xy)
    return (
        f'<section class="sheet" id="{esc(sample.name)}"><h1>{esc(sample.name)} · recreation sheet '
        f"{info.position} of {info.total}</h1>"
        f'<p class="sub">{esc(info.source)} · {"failing" if info.failed else "passing"} in simulation · '
        f"{esc(lead)} (about {esc(fmt(info.minutes, 1))} min)</p>"
        f'<img class="target" src="{esc(image_href)}" alt="target render of {esc(sample.name)}">'
        '<div class="cols"><table><thead><tr><th></th><th>what</th><th>set it to</th><th>where (cabin frame)</th>'
        f"</tr></thead><tbody>{''.join(rows)}</tbody></table>"
        f'<div class="side">{sketch}<div class="crops">{"".join(crops)}</div></div></div>'
        f'<p class="note">Measure in the cabin frame: {esc(AXES)}. Camera: {esc(camera_text)}. '
        f"Capture: isu-validate capture shoot --source SPEC --pair {esc(sample.path)}</p></section>")


def page(title: str, body: str) -> str:
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{esc(title)}</title><style>{PRINT_CSS}</style></head><body>{body}</body></html>\n")


def overview_html(rows: list[dict], effort: dict, notes: list[str]) -> str:
    """The first page of index.html: the order, what changes when, and the effort against the run order."""
    head = "".join(f"<th>{esc(c)}</th>" for c in ("#", "sample", "from", "sim", "changes", "min"))
    body = "".join(
        f'<tr><td>{r["position"]}</td><td><a href="#{esc(r["sample"])}">{esc(r["sample"])}</a></td>'
        f'<td>{esc(r["source"])}</td><td>{"failing" if r["failed"] else "passing"}</td>'
        f'<td>{esc(", ".join(r["changes"]) or "-")}</td><td>{esc(fmt(r["minutes"], 1))}</td></tr>' for r in rows)
    saved = effort["run_order_minutes"] - effort["minutes"]
    summary = (f"Estimated effort in this order: {fmt(effort['minutes'], 1)} min; in the run's order "
               f"{fmt(effort['run_order_minutes'], 1)} min ({fmt(saved, 1)} min saved). Costs from "
               f"{effort['source']} ({effort['method']}).")
    extra = "".join(f'<p class="note">{esc(n)}</p>' for n in notes)
    return (f'<section class="overview"><h1>Recreation plan: {len(rows)} scenes</h1><p>{esc(summary)}</p>{extra}'
            f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
            '<p class="note">Each following page is one scene: set it up, tick the list, then capture it. '
            "Print this file (A4, one scene per page).</p></section>")


def relative(path: Path, start: Path) -> str:
    try:
        return str(path.relative_to(start))
    except ValueError:
        return str(path.resolve())
