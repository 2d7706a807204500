"""``recognise``: every frame of the sources through the photo-trained yardsticks; rates, crops, report.

Writes to OUT: ``summary.json`` (the contract, docs/ARCHITECTURE.md "Recognition folder"), ``frames.jsonl``
(one record per frame: what each model said about each feature), ``sheet-<kind>.png`` (crops with what was
said) and ``index.html``."""
from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

from ..archive.output_dir import claim_output
from ..atomic import write_json, write_text
from ..progress import Progress
from ..recognition.frames import KINDS, Frame
from ..recognition.objects import PLAUSIBLE
from ..recognition.read import Yardsticks, read_frame
from ..recognition.tally import expression_summary, face_sizes, object_summary, rows
from ..errors import InputError
from .sources import frames_of, real_set_frames

FORMAT = "isu-validate-recognise/1"
SUMMARY, FRAMES = "summary.json", "frames.jsonl"
SHEET_CROPS = 96     # crops per contact sheet: enough to see the pattern, small enough to open


@dataclass(frozen=True)
class RecogniseSettings:
    sources: tuple[str, ...]
    limit: int | None = None       # first N frames of each source (None: all)
    real: tuple[str, ...] = ()     # labelled real photo sets (realphotos layouts), read beside the renders
    labels: str | None = None      # their label map (boxes of the things, answers); None: faces only
    space: str = "isu-paper"       # the label map's space

    def as_dict(self) -> dict:
        out = {"sources": list(self.sources), "limit": self.limit}
        if self.real:   # only when given: earlier folders' settings stay comparable
            out.update(real=[str(Path(r).resolve()) for r in self.real], labels=self.labels, space=self.space)
        return out


def gather(settings: RecogniseSettings) -> tuple[list[dict], list[Frame]]:
    described, frames = [], []
    sources = [(raw, lambda raw=raw: frames_of(Path(raw))) for raw in settings.sources]
    if settings.real:
        from ..space import load_space
        space = load_space(settings.space)
        labels = Path(settings.labels) if settings.labels else None
        sources += [(raw, lambda raw=raw: ("real photos", real_set_frames(Path(raw), labels, space)))
                    for raw in settings.real]
    if not sources:
        raise InputError("give a SOURCE (run, dataset, pairs, frames) or --real SET to read")
    for i, (raw, read) in enumerate(sources):
        kind, found = read()
        found = found[: settings.limit] if settings.limit else found
        prefix = f"{i}:" if len(sources) > 1 else ""
        frames += [replace(f, name=prefix + f.name) for f in found]
        described.append({"path": str(Path(raw).resolve()), "kind": kind, "frames": len(found)})
    return described, frames


def recognise(settings: RecogniseSettings, out: Path, device, stream=sys.stderr, overwrite: bool = False) -> dict:
    """Measure and write OUT; returns the summary. ``device`` is a resolved ``devices.TorchDevice``. OUT must be
    new, empty, or this command's output of the same settings (redone); anything else needs ``overwrite``."""
    output = claim_output(out, "recognise", settings.as_dict(), overwrite=overwrite)
    sources, frames = gather(settings)
    started = time.perf_counter()
    models = Yardsticks.load(device.name)
    load_s, cpu = time.perf_counter() - started, time.process_time()
    # the marker first: an interrupted measurement (a corrupt frame, ^C) is this command's, so it may be redone
    output.mark()
    write_json(out / SUMMARY, {"format": FORMAT, "settings": settings.as_dict(), "complete": False}, indent=1)
    records, crops = _read_all(frames, models, out, stream)
    read_s = time.perf_counter() - started - load_s
    cpu_s = time.process_time() - cpu   # CPU-seconds too: on a shared machine wall time measures the neighbours
    summary = _summary(settings, sources, records, models, device, load_s, read_s, cpu_s)
    from .report import write_report, write_sheets
    summary["sheets"] = write_sheets(crops, out)
    write_json(out / SUMMARY, summary, indent=1)
    write_text(out / "index.html", write_report(summary))
    return summary


def _read_all(frames: list[Frame], models: Yardsticks, out: Path, stream):
    progress = Progress(len(frames), label="frames", stream=stream, verdicts=False)
    records, crops = [], {k: [] for k in KINDS}
    with open(out / FRAMES, "w") as f:
        for frame in frames:
            t = time.perf_counter()
            record, said = read_frame(frame, models)
            record["seconds"] = round(time.perf_counter() - t, 4)
            f.write(json.dumps(record) + "\n")
            records.append(record)
            room = SHEET_CROPS - len(crops[frame.kind])
            crops[frame.kind] += [(c, f"{frame.name} {s}") for c, s in said[:max(room, 0)]]
            progress.update()
    return records, crops


def _summary(settings, sources, records, models, device, load_s, read_s, cpu_s) -> dict:
    kinds = {k: sum(r["kind"] == k for r in records) for k in KINDS}
    return {
        "format": FORMAT, "settings": settings.as_dict(), "complete": True, "sources": sources,
        "device": device.describe(),
        "models": models.describe(), "plausible_classes": {k: list(v) for k, v in PLAUSIBLE.items()},
        "frames": {"total": len(records), **kinds, "stand_in_frames": kinds["stand-in"],
                   "real_frames": kinds["real"]},
        "presets": sorted({str(r["preset"]) for r in records}),
        "rows": rows(records), "expression": expression_summary(records),
        "objects": object_summary(records), "face_width_px": face_sizes(records),
        "timing": {"load_s": round(load_s, 2), "read_s": round(read_s, 2),
                   "per_frame_s": round(read_s / len(records), 4) if records else None,
                   "cpu_s": round(cpu_s, 2), "cpu_s_per_frame": round(cpu_s / len(records), 4) if records else None},
        "files": {"frames": FRAMES, "report": "index.html"},
    }
