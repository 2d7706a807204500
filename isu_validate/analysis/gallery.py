"""The failure gallery: each failing scene's image, its scene, and the truth against what
the SUT answered, wrong features highlighted (all SUT text is escaped by ``html``)."""
from __future__ import annotations

import base64
import io
import json

from PIL import Image, UnidentifiedImageError

from ..archive import TestRecord
from .failures import NO_ANSWER, wrong_answers
from .html import esc, fmt, table
from .runs import Run

THUMB_WIDTH = 320
RAW_LIMIT = 1500  # characters of the SUT's raw output shown per card


def thumbnail(path) -> str | None:
    """A small JPEG data URI of the image, or None when it cannot be read."""
    if path is None:
        return None
    try:
        with Image.open(path) as img:
            img = img.convert("RGB")
            if img.width > THUMB_WIDTH:
                img = img.resize((THUMB_WIDTH, max(1, round(img.height * THUMB_WIDTH / img.width))), Image.LANCZOS)
            buf = io.BytesIO()
            img.save(buf, format="JPEG", quality=85)
    except (OSError, UnidentifiedImageError):
        return None
    return "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def pick(items: list[tuple[Run, TestRecord]], limit: int) -> list[tuple[Run, TestRecord]]:
    """The failing tests to show, at most ``limit``: worst fitness first, and among equal
    fitness the runs take turns, so one run cannot fill the gallery."""
    def value(item):
        run, record = item
        v = run.metric(record)
        return v if v is not None else 2.0

    turn: dict[int, int] = {}
    keyed = []
    for item in sorted(items, key=lambda it: (value(it), it[1].test_id)):
        run_id = id(item[0])
        turn[run_id] = turn.get(run_id, -1) + 1
        keyed.append(((value(item), turn[run_id], item[0].name), item))
    return [item for _, item in sorted(keyed, key=lambda kv: kv[0])][:limit]


def card(run: Run, record: TestRecord, cluster: int | None = None) -> str:
    uri = thumbnail(run.image_path(record))
    image = (f'<img src="{esc(uri)}" alt="{esc(record.test_id)}" loading="eager">' if uri
             else '<p class="note">(image missing)</p>')
    title = (f"<b>{esc(record.test_id)}</b> · {esc(run.algorithm)} seed {esc(run.seed)} · {esc(run.name)}<br>"
             f"{esc(run.metric_key)} = {esc(fmt(run.metric(record)))}"
             + ("" if cluster is None else f" · cluster {esc(cluster)}"))
    body = _answers(run, record) + _scene(run, record) + _raw(record)
    return f'<div class="card">{image}<div>{title}</div>{body}</div>'


def _answers(run: Run, record: TestRecord) -> str:
    if record.answers is None:
        reference = (record.details.get("verdict") or {}).get("reference_caption")
        rows = [{"": "SUT caption", "text": record.caption or ""}]
        if reference:
            rows.append({"": "reference", "text": reference})
        return table(["", "text"], rows)
    wrong = wrong_answers(run, record)
    rows, classes = [], []
    for key, truth in run.truth(record).items():
        rows.append({"feature": key, "truth": truth, "SUT": str(record.answers.get(key, NO_ANSWER))})
        classes.append("wrong" if key in wrong else "")
    return table(["feature", "truth", "SUT"], rows, classes)


def _scene(run: Run, record: TestRecord) -> str:
    asked = set(run.truth(record))
    rest = ", ".join(f"{k} = {fmt(v)}" for k, v in record.canonical.items() if k not in asked)
    return f'<p class="note">scene: {esc(rest)}</p>' if rest else ""


def _raw(record: TestRecord) -> str:
    raw = record.sut_raw or ""
    if not raw:
        return ""
    shown = raw if len(raw) <= RAW_LIMIT else raw[:RAW_LIMIT] + " …"
    return f"<details><summary>SUT output</summary><pre>{esc(shown)}</pre></details>"


def gallery(items: list[tuple[Run, TestRecord]], limit: int, clusters: dict | None = None) -> str:
    """Cards of the worst failing tests; ``clusters`` maps (run name, test id) to the RQ2 cluster."""
    clusters = clusters or {}
    chosen = pick(items, limit)
    if not chosen:
        return '<p class="note">No failing tests.</p>'
    head = (f'<p class="note">Showing {len(chosen)} of {len(items)} failing tests, worst first; '
            'wrong answers highlighted.</p>'
            '<input id="gallery-filter" class="filter" type="search" placeholder="filter (feature, value, run)">')
    cards = "".join(card(r, t, clusters.get((r.name, t.test_id))) for r, t in chosen)
    return f'{head}<div class="gallery">{cards}</div>'


def gallery_rows(items: list[tuple[Run, TestRecord]]) -> list[dict]:
    """The failing tests as a table (CSV/JSON), with the wrong answers spelt out."""
    return [{"run": run.name, "test_id": rec.test_id, "algorithm": run.algorithm, "seed": run.seed,
             "metric": run.metric_key, "fitness": run.metric(rec), "image": rec.image or "",
             "wrong": json.dumps({k: {"truth": t, "answer": a} for k, (t, a) in wrong_answers(run, rec).items()}),
             "caption": rec.caption or ""} for run, rec in items]
