"""Which image each test is asked about: the run's own frame. A missing frame is rendered again only by
the renderer that made it (the same renderer version), with the run's render settings, into
``DIR/images`` (the run stays as it was); otherwise a new render would not be the frame the run judged,
so those tests are named and not replayed, and the rest are.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from ..archive import RunDir, TestRecord
from ..atomic import write_bytes
from ..protocols import RenderError
from .stored import StoredRun

LISTED = 12   # test ids named in one message; the rest are counted


@dataclass
class Frame:
    image: Path | None              # None: not replayed
    skipped: str | None = None      # why not
    rerendered: bool = False


def find_frames(stored: StoredRun, out: Path, log) -> dict[str, Frame]:
    """A frame for every test with a verdict, re-rendering the missing ones where that is faithful."""
    frames, missing = {}, []
    for record in stored.tests:
        path = stored.run.image_path(record)
        if path is not None:
            frames[record.test_id] = Frame(path)
        else:
            missing.append(record)
    if missing:
        frames.update(_missing(stored, missing, out, log))
    return frames


def _missing(stored: StoredRun, missing: list[TestRecord], out: Path, log) -> dict[str, Frame]:
    from ..render import RENDERER_VERSION

    frames: dict[str, Frame] = {}
    by_version: dict[str | None, list[str]] = {}
    same = []
    for record in missing:
        version = stored.renderer_version(record.test_id)
        if version == RENDERER_VERSION:
            same.append(record)
        else:
            by_version.setdefault(version, []).append(record.test_id)
    for version, ids in by_version.items():
        made = f"made them with the renderer {version}" if version else "does not record which renderer made them"
        reason = (f"image missing; the run {made}, this installation renders with {RENDERER_VERSION}: "
                  "a new render would not be the frame the run judged")
        log(f"{len(ids)} image(s) missing from {stored.path / 'images'} ({_listed(ids)}) and the run {made}, "
            f"this installation renders with {RENDERER_VERSION}: those tests are not replayed (a new render "
            "would not be the frame the run judged); restore the images to replay them")
        frames.update({i: Frame(None, reason) for i in ids})
    if same:
        frames.update(_rerender(stored, same, out, log))
    return frames


def _rerender(stored: StoredRun, records: list[TestRecord], out: Path, log) -> dict[str, Frame]:
    """Render the frames again into ``out/images`` (kept there: a second replay renders nothing twice)."""
    from ..pipeline import open_run_renderer

    frames, renderer, todo = {}, None, []
    for record in records:
        image = RunDir(out).image_file(record.test_id)
        if _readable(image):
            frames[record.test_id] = Frame(image, rerendered=True)
        else:
            todo.append(record)
    if not todo:
        return frames
    log(f"{len(todo)} image(s) missing from {stored.path / 'images'} ({_listed([r.test_id for r in todo])}): "
        f"rendering them again with the run's renderer and settings into {out / 'images'}")
    config = dataclasses.replace(stored.pipeline, run_dir=str(out))
    try:
        renderer = open_run_renderer(config, stored.space)
        for record in todo:
            frames[record.test_id] = _render_one(stored, renderer, record, out)
    finally:
        if renderer is not None:
            renderer.close()
    return frames


def _render_one(stored: StoredRun, renderer, record: TestRecord, out: Path) -> Frame:
    target = RunDir(out)
    target.image_file(record.test_id).parent.mkdir(parents=True, exist_ok=True)
    try:
        result = renderer.render(record.canonical, target.image_file(record.test_id))
    except RenderError as exc:
        return Frame(None, f"image missing and rendering it again failed: {exc or type(exc).__name__}")
    label = RunDir(stored.path).label_file(record.test_id)
    if label.is_file():   # the scene beside the frame, as in a run (label-reading SUTs find it there)
        write_bytes(target.label_file(record.test_id), label.read_bytes())
    return Frame(Path(result.image), rerendered=True)


def _readable(path: Path) -> bool:
    try:
        with Image.open(path) as img:
            img.load()
    except (OSError, UnidentifiedImageError, SyntaxError):
        return False
    return True


def _listed(ids: list[str]) -> str:
    shown = ", ".join(ids[:LISTED])
    return shown if len(ids) <= LISTED else f"{shown} and {len(ids) - LISTED} more"
