"""Building the self-contained HTML report: every piece of text is escaped here, once;
images arrive as data URIs, so the file opens anywhere with nothing beside it."""
from __future__ import annotations

import html
import math
import re
from typing import Iterable, Sequence

STYLE = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:0;color:#1d2330;background:#f6f7f9}
header{background:#1d2f4f;color:#fff;padding:18px 28px}header h1{margin:0 0 4px;font-size:22px}
header p{margin:0;opacity:.85}main{padding:8px 28px 40px;max-width:1300px}
section{background:#fff;border-radius:8px;padding:14px 20px;margin:16px 0;box-shadow:0 1px 3px #0002}
h2{font-size:18px;margin:4px 0 10px}h3{font-size:15px;margin:14px 0 6px}
table{border-collapse:collapse;font-size:13px;margin:6px 0}
th,td{padding:4px 9px;border-bottom:1px solid #e3e6eb;text-align:left;vertical-align:top}
th{background:#eef1f5}td.num{text-align:right;font-variant-numeric:tabular-nums}
.cards{display:flex;flex-wrap:wrap;gap:12px}
.stat{background:#eef3fb;border-radius:6px;padding:10px 16px;min-width:120px}
.stat b{display:block;font-size:22px}.stat.bad b{color:#b3261e}.stat.warn b{color:#8a5a00}
figure{margin:8px 0;display:inline-block;vertical-align:top}
figure img{max-width:100%;border:1px solid #e3e6eb}figcaption{font-size:12px;color:#555;max-width:640px}
.note{font-size:13px;color:#555}.gallery{display:flex;flex-wrap:wrap;gap:12px}
.card{border:1px solid #dde1e7;border-radius:6px;padding:8px;width:330px;font-size:12px}.card img{width:100%}
.card table{font-size:11px;width:100%;table-layout:fixed}
.card td,.card th{padding:2px 4px;overflow-wrap:anywhere}.card th:first-child{width:46%}
tr.wrong td{background:#fde7e7;color:#8c1d18;font-weight:600}
pre{white-space:pre-wrap;word-break:break-word;font-size:11px;background:#f3f4f6;padding:6px;max-height:160px;overflow:auto}
.filter{margin:6px 0 10px}.hidden{display:none}
nav{margin-top:8px;font-size:13px}nav a{color:#cfe0ff;text-decoration:none}nav a:hover{text-decoration:underline}
"""

# Checks that every embedded image decoded (the browser test reads data-images) and
# filters the gallery; it must never log an error on a healthy report.
SCRIPT = """
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
  document.body.setAttribute('data-images', broken.length ? 'broken' : 'ok');
  document.body.setAttribute('data-image-count', String(imgs.length));
  broken.forEach(function (i) { console.error('image failed to load: ' + (i.alt || '?')); });
  var box = document.getElementById('gallery-filter');
  if (box) box.addEventListener('input', function () {
    var q = box.value.toLowerCase();
    document.querySelectorAll('.card').forEach(function (c) {
      c.classList.toggle('hidden', q !== '' && c.textContent.toLowerCase().indexOf(q) < 0);
    });
  });
});
"""


def esc(value) -> str:
    return html.escape(str(value), quote=True)


def fmt(value, digits: int = 3) -> str:
    """Numbers for people: NaN reads as an en dash, floats get `digits` significant places."""
    if value is None or value == "":
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        if abs(value) < 1e-3 and value != 0:
            return f"{value:.{digits}g}"
        return f"{value:,.{digits}f}".rstrip("0").rstrip(".")
    return str(value)


def percent(value) -> str:
    """A percentage as every report shows one: one decimal ("16.7"), an en dash for no value."""
    return fmt(value) if not isinstance(value, (int, float)) or value != value else f"{value:.1f}"


def plural(n: int, word: str) -> str:
    """ "1 run", "2 runs". """
    return f"{n} {word}" + ("" if n == 1 else "s")


def threshold_label(t: float) -> str:
    """1.0, 0.9, 0.65: at least one decimal, so a threshold never reads as a count."""
    return f"{t:.1f}" if round(t, 1) == t else f"{t:g}"


def table(columns: Sequence[str], rows: Iterable[dict], classes: Iterable[str] | None = None) -> str:
    """Rows as an escaped table; `classes` gives an optional CSS class per row."""
    rows = list(rows)
    classes = list(classes) if classes is not None else [""] * len(rows)
    if not rows:
        return '<p class="note">(none)</p>'
    head = "".join(f"<th>{esc(c)}</th>" for c in columns)
    body = []
    for row, cls in zip(rows, classes):
        cells = "".join(_cell(row.get(c, "")) for c in columns)
        body.append(f'<tr class="{esc(cls)}">{cells}</tr>' if cls else f"<tr>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _cell(value) -> str:
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    return f'<td class="num">{esc(fmt(value))}</td>' if numeric else f"<td>{esc(fmt(value))}</td>"


def figure(data_uri: str, alt: str, caption: str = "") -> str:
    cap = f"<figcaption>{esc(caption)}</figcaption>" if caption else ""
    return f'<figure><img src="{esc(data_uri)}" alt="{esc(alt)}">{cap}</figure>'


def stat(label: str, value, kind: str = "") -> str:
    return f'<div class="stat {esc(kind)}"><b>{esc(fmt(value))}</b>{esc(label)}</div>'


def paragraph(text: str, cls: str = "note") -> str:
    return f'<p class="{esc(cls)}">{esc(text)}</p>'


def section(title: str, *parts: str, anchor: str = "") -> str:
    ident = f' id="{esc(anchor)}"' if anchor else ""
    return f"<section{ident}><h2>{esc(title)}</h2>{''.join(parts)}</section>"


_SECTION_HEAD = re.compile(r'<section id="([^"]+)"><h2>([^<]*)</h2>')


def contents(sections: Sequence[str]) -> str:
    """Links to every section that has an anchor (titles are already escaped)."""
    links = [f'<a href="#{anchor}">{title}</a>' for s in sections for anchor, title in _SECTION_HEAD.findall(s)]
    return f'<nav>{" · ".join(links)}</nav>' if links else ""


def page(title: str, subtitle: str, sections: Iterable[str]) -> str:
    sections = list(sections)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{esc(title)}</title><style>{STYLE}</style></head><body>"
            f"<header><h1>{esc(title)}</h1><p>{esc(subtitle)}</p>{contents(sections)}</header>"
            f"<main>{''.join(sections)}</main><script>{SCRIPT}</script></body></html>\n")
