"""Shooting a session: frames as PNG with a JSON sidecar each, plus ``session.json``.

Every frame is on disk (written atomically) before the next is requested, so a camera
that is unplugged mid-session leaves every frame taken so far, and ``session.json``
says what happened.  A session folder replays as ``--source replay:DIR``.
"""
from __future__ import annotations

import datetime as _dt
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import cv2

from isu_validate.atomic import atomic_path, write_text
from isu_validate.errors import InputError

from .sources import CaptureError, ExposureRequest, Frame, FrameSource


@dataclass
class Session:
    out: Path
    frames: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    error: str | None = None


def _atomic_write_png(path: Path, image) -> None:
    with atomic_path(path, keep_suffix=True) as tmp:   # cv2 picks the format by the suffix
        if not cv2.imwrite(str(tmp), image):
            raise OSError(f"could not write {path} (disk full or read-only?)")


def shoot(source: FrameSource, n_frames: int, out: str | Path, request: ExposureRequest | None = None,
          progress=None, first_index: int | None = None, annotate: Callable[[Path, Frame], dict] | None = None
          ) -> Session:
    """Take ``n_frames`` frames into ``out``; raises CaptureError (frames kept) when the camera fails.

    ``first_index``: add to the frames already in ``out``, numbering on from there (a pair's ``real/``),
    with this session's record in ``session_<first>.json``; otherwise ``out`` must hold no frames.
    ``annotate(path, frame)``: called once each frame is on disk; what it returns joins the sidecar."""
    request = ExposureRequest() if request is None else request   # automatic exposure
    if n_frames <= 0:
        raise InputError(f"--frames must be positive, got {n_frames}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if first_index is None and any(out.glob("frame_*.png")):
        raise InputError(f"{out} already holds frames from another session; choose a new --out folder")
    start = first_index or 0
    record_name = "session.json" if first_index is None else f"session_{start:04d}.json"
    session = Session(out)
    record = {"source": source.spec, "requested": {"frames": n_frames, "exposure_us": request.exposure_us,
                                                   "iso": request.iso, "auto_exposure": request.auto},
              "started": _dt.datetime.now(_dt.timezone.utc).isoformat(), "status": "running", "frames": [],
              "warnings": session.warnings}

    def save(status: str) -> None:
        record["status"] = status
        record["frames"] = [p.name for p in session.frames]
        record["error"] = session.error
        write_text(out / record_name, json.dumps(record, indent=2))

    save("running")
    try:
        with source:
            session.warnings += source.set_exposure(request)
            for i in range(n_frames):
                frame = source.read()
                path = out / f"frame_{start + i:04d}.png"
                _atomic_write_png(path, frame.image)
                meta = dict(frame.meta, frame=path.name, requested=record["requested"])
                if annotate:
                    meta.update(annotate(path, frame))
                write_text(path.with_suffix(".json"), json.dumps(meta, indent=2, default=str))
                session.frames.append(path)
                for w in meta.get("warnings", []):
                    if w not in session.warnings:
                        session.warnings.append(w)
                if progress:
                    progress(i + 1, n_frames, meta)
    except CaptureError as exc:
        session.error = str(exc)
        save("failed")
        kept = f"; the {len(session.frames)} frame(s) taken before are kept in {out}" if session.frames else ""
        raise type(exc)(f"{exc}{kept}") from None
    save("complete")
    return session
