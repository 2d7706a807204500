"""Printable recreation sheets (one A4 page per sample) and ``PAIRS/index.html`` with all of them.

A sheet holds what a technician needs to set the car up, on one page: the target picture; the camera's
place and aim with a small view marked where it points; the checklist (features the render hid are
flagged: set them, they are not judged) beside a top-view sketch; what the light levels mean; crops of
the small things; the cabin frame. Everything that came from a file is escaped; pictures are linked
(relative path), crops embedded, so a sheet prints from the pairs folder alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..analysis.html import esc, fmt
from .aim import CONVENTION, Aim, aim_lines
from .guide import AXES, Item, sketch_number
from .light import LightRow
from .pictures import Crop, Picture
from .sketch import top_view

# A4 is 210 x 297 mm; 10 mm margins leave 190 x 277 mm, and every block below has a fixed width or
# height so that the tallest scene (every feature active) stays on its page (tests print it and count)
PRINT_CSS = """
@page{size:A4;margin:10mm}
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;color:#1d2330;margin:0;font-size:9px;
 line-height:1.2;-webkit-print-color-adjust:exact;print-color-adjust:exact}
.sheet,.overview{box-sizing:border-box;width:190mm;margin:0 auto;background:#fff}
.sheet{break-after:page;page-break-after:always;break-inside:avoid}
.sheet:last-child{break-after:auto;page-break-after:auto}
.sheet h1{font-size:14px;margin:0}.sub{color:#555;margin:0 0 1.5mm;font-size:8px}
h2{font-size:10.5px;margin:0 0 1mm}
.top{display:flex;gap:3mm}
.target{margin:0;width:92mm;flex:none}.target img{display:block;width:92mm;height:69mm;object-fit:contain;
 background:#222}
figcaption{font-size:7.5px;color:#555}
.camera{flex:1;display:flex;flex-direction:column;gap:1mm}.sketchbox{width:40mm;flex:none}
.camera ul{margin:0;padding-left:3.5mm}.camera li{margin:0 0 .4mm}
.view{margin:0}.frame{position:relative;width:40mm;height:30mm}
.frame img{display:block;width:40mm;height:30mm;object-fit:fill}.frame svg{position:absolute;left:0;top:0;
 width:40mm;height:30mm}
table{border-collapse:collapse;width:100%}
td,th{border-bottom:1px solid #ccd;padding:.25mm .8mm;text-align:left;vertical-align:top}
th{background:#eef1f5}td.box{width:3mm;font-size:10px;padding:0 .5mm}
table.list{margin-top:1.5mm}table.list td:nth-child(2){width:34mm}table.list td:nth-child(4){width:62mm}
tr.hidden td{background:#fff4d6}.flag{display:block;color:#8a5a00;font-weight:600}
svg.sketch{width:40mm;display:block}
table.light{margin-top:1.5mm;font-size:8px;table-layout:fixed}table.light tr.chosen td{background:#e3f1e0;
 font-weight:600}
.crops{display:flex;flex-wrap:wrap;gap:1.5mm;margin-top:1.5mm}
.crops figure{margin:0;width:25mm}.crops img,.crops .none{display:block;width:25mm;height:21mm;object-fit:contain;
 background:#222;border:1px solid #ccd}
.crops .none{box-sizing:border-box;background:#f4f5f7;color:#8a5a00;font-size:7.5px;padding:1mm}
.crops figcaption{font-size:7px;line-height:1.15;max-height:3.45em;overflow:hidden}
.note{color:#555;font-size:7.5px;margin:1.5mm 0 0}
.overview{break-after:page;page-break-after:always}.overview td,.overview th{font-size:10px}
@media screen{body{background:#e9ecf1;padding:12px}.sheet,.overview{padding:6mm;margin-bottom:18px;
 width:202mm}}
"""


@dataclass
class SheetInfo:
    position: int                   # 1-based place in the recreation order
    total: int
    source: str                     # run name and test id
    failed: bool
    changes: list[str] = field(default_factory=list)   # what changes from the previous sample
    minutes: float = 0.0


@dataclass
class SheetContent:
    """Everything on one sheet but the picture's address (which differs between sheet.html and index.html)."""
    name: str
    pair: Path                      # the sample folder (the capture command names it)
    info: SheetInfo
    items: list[Item]
    cabin: dict
    picture: Picture
    aim: Aim | None
    camera_name: str
    lights: list[LightRow]
    crops: list[tuple[list[Item], Crop]]


def sheet_html(content: SheetContent, href: str) -> str:
    """One sheet as an HTML fragment (``<section class="sheet">``); ``href``: the picture's address."""
    info = content.info
    changes = ", ".join(info.changes) if info.changes else "nothing but the capture"
    lead = ("first scene: set up everything below" if info.position == 1
            else f"change from the previous sheet: {changes}")
    sketch = top_view(content.cabin, content.items, content.aim.position[:2] if content.aim else None)
    return (
        f'<section class="sheet" id="{esc(content.name)}"><h1>{esc(content.name)} · recreation sheet '
        f"{info.position} of {info.total}</h1>"
        f'<p class="sub">{esc(info.source)} · {"failing" if info.failed else "passing"} in simulation · '
        f"{esc(lead)} (about {esc(fmt(info.minutes, 1))} min)</p>"
        f'<div class="top">{_target(content, href)}<div class="sketchbox">{sketch}</div>{_camera(content, href)}'
        f"</div>{_checklist(content.items)}{_lights(content.lights)}{_crops(content.crops)}"
        f'<p class="note">Cabin frame: {esc(AXES)}. Camera angles: {esc(CONVENTION)}. Light: a lux meter at the '
        "driver's face checks the share of the brightest. "
        f"Capture: isu-validate capture shoot --source SPEC --pair {esc(content.pair)} "
        "(the alignment aid says which way to turn the camera)</p></section>")


def _target(content: SheetContent, href: str) -> str:
    how = ("rendered for this sheet" if content.picture.rendered
           else "the run's own frame, scaled up (recreate --sheet-preset run)")
    try:
        w, h = content.picture.size
        how += f", {w}x{h}"
    except OSError:
        pass
    return (f'<figure class="target"><img src="{esc(href)}" alt="target render of {esc(content.name)}">'
            f"<figcaption>Target: set the car up to look like this ({esc(how)}).</figcaption></figure>")


def _camera(content: SheetContent, href: str) -> str:
    if content.aim is None:
        return f'<div class="camera"><h2>Camera</h2><p>{esc(content.camera_name)}</p></div>'
    lines = "".join(f"<li>{esc(line)}</li>" for line in aim_lines(content.aim))
    return (f'<div class="camera"><h2>Camera: {esc(content.camera_name)}</h2><ul>{lines}</ul>'
            f'<figure class="view"><div class="frame"><img src="{esc(href)}" alt="what the camera should see">'
            f"{_crosshair(content.picture)}</div><figcaption>What the camera should see: the whole picture, "
            "the cross at its centre on the aim point.</figcaption></figure></div>")


def _crosshair(picture: Picture) -> str:
    camera = picture.camera
    if camera is None:
        return ""
    w, h, cx, cy = camera.width, camera.height, camera.cx, camera.cy
    arm, stroke = 0.08 * w, max(1.0, w / 160)
    lines = "".join(f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" stroke="{c}" '
                    f'stroke-width="{s:.1f}"/>'
                    for c, s in (("#000", 2.2 * stroke), ("#ffd600", stroke))
                    for x1, y1, x2, y2 in ((cx - arm, cy, cx + arm, cy), (cx, cy - arm, cx, cy + arm)))
    return f'<svg viewBox="0 0 {w} {h}" preserveAspectRatio="none" aria-hidden="true">{lines}</svg>'


def _checklist(items: list[Item]) -> str:
    rows = []
    for item in items:
        where = item.placement.text if item.placement else ""
        number = sketch_number(items, item)   # the sketch numbers what it draws; the checklist shows the same
        mark = f" ({number})" if number else ""
        flag = ""
        if item.hidden is not None:
            flag = (f'<span class="flag">hidden from the camera in the render ({item.hidden:.0%} visible): '
                    "set it, it is not judged</span>")
        rows.append(f'<tr{" class=hidden" if flag else ""}><td class="box">☐</td><td>{esc(item.title)}{esc(mark)}'
                    f"</td><td>{esc(item.text)}{flag}</td><td>{esc(where)}</td></tr>")
    return ('<table class="list"><thead><tr><th></th><th>what</th><th>set it to</th><th>where (cabin frame)</th>'
            f"</tr></thead><tbody>{''.join(rows)}</tbody></table>")


def _lights(rows: list[LightRow]) -> str:
    if not rows:
        return ""
    body = "".join(
        f'<tr{" class=chosen" if r.chosen else ""}><td>{esc(r.title)}</td><td>{esc(r.value)}'
        f'{" ◀ this scene" if r.chosen else ""}</td><td>{esc(r.rendered)}</td><td>{esc(r.relative)}</td>'
        f"<td>{esc(r.practical)}</td></tr>" for r in rows)
    widths = "".join(f'<col style="width:{w}">' for w in ("17mm", "20mm", "47mm", "20mm", "auto"))
    return (f'<table class="light"><colgroup>{widths}</colgroup><thead><tr><th>light</th><th>value</th>'
            "<th>the render used</th><th>of the brightest</th><th>in a lab or outdoors</th>"
            f"</tr></thead><tbody>{body}</tbody></table>")


def _crops(crops: list[tuple[list[Item], Crop]]) -> str:
    figures = []
    for items, c in crops:
        words = "; ".join(f"{i.title}: {i.text}" for i in items)
        share = next((i.hidden for i in items if i.hidden is not None), None)
        note = ("" if share is None else
                f"hidden in the render ({share:.0%} visible{', its place outlined' if c.outlined else ''}): ")
        image = (f'<img src="{esc(c.uri)}" alt="{esc(items[0].title)}">' if c.uri
                 else '<div class="none">nothing of it shows from the camera</div>')
        figures.append(f"<figure>{image}<figcaption>{esc(note)}{esc(words)}</figcaption></figure>")
    return f'<div class="crops">{"".join(figures)}</div>' if figures else ""


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
