"""``build_dataset``: render a training dataset slot by slot, each committed as it finishes, and write its
files when it is complete. What ``isu-validate dataset`` and ``bench dataset`` call.

Everything a user can get wrong (settings, runs, the focus, style images and models, camera, preset, the
output folder) is checked before the first file is written. A kill loses at most the slots in flight: a
``resume`` reads the manifest, refuses other settings (naming each difference), and renders exactly the
slots an uninterrupted build would have, none twice.
"""
from __future__ import annotations

import re
import shutil
import sys
import time
from collections import Counter
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable

from ..archive.output_dir import claim_output, is_empty
from ..execution import make_executor, render_threads
from ..progress import Progress
from ..space import SceneSpace, load_space
from .card import costs, counts, licences, reproduce, versions
from .focus import load_focus_runs, runs_digest
from .folder import FORMAT, IMAGES_DIR, WORK_DIR, DatasetDir, DatasetError
from .images import IMAGES, ImageConfig, SlotJob
from .outputs import write_outputs
from .plan import Plan
from .settings import DatasetSettings, differences
from .styles import StyleSpec, plan_styles

_OUR_IMAGE = re.compile(r"^\d{6}(_style\d+)?\.png$")


@dataclass
class DatasetSummary:
    out: Path
    renders: int          # slots in the dataset (each one render)
    images: int           # renders and their style copies
    skipped: int          # slots whose frame could not show their scene (the next slots replaced them)
    made_now: int         # renders made by this call (a resume counts only its own)
    seconds: float        # wall time of this call's rendering
    short: int = 0        # renders fewer than asked (unusable frames in nearly every slot)

    @property
    def renders_per_s(self) -> float:
        return self.made_now / self.seconds if self.seconds > 0 else 0.0


def build_dataset(settings: DatasetSettings, out: str | Path, resume: bool = False,
                  log: Callable[[str], None] | None = None, progress_stream=None) -> DatasetSummary:
    """Render a dataset into ``out`` (or continue the one there with ``resume=True``); UserError, with
    nothing written, for settings, runs or a folder that cannot be used as asked.

        summary = build_dataset(DatasetSettings(n=200, preset="draft", seed=1), "datasets/uniform")
        summary = build_dataset(DatasetSettings(n=200, from_runs=("runs/s1",), focus="failing"), "datasets/near")
        print(summary.renders, summary.renders_per_s)   # then DIR/metadata.jsonl, annotations.json, vqa.jsonl
    """
    log = log or (lambda text: print(text, file=sys.stderr))
    settings = settings.check()
    folder = DatasetDir(Path(out).resolve())
    space = load_space(settings.space)
    runs = load_focus_runs(settings.from_runs, space) if settings.from_runs else []
    _check_rendering(settings)
    styles = plan_styles(settings.styles, settings.style_models, settings.style_size, settings.style_steps)
    settings = replace(settings, inputs=_inputs(runs, styles))
    output = claim_output(folder.path, "dataset", settings.identity(), resume=resume, overwrite=None)
    info = _resume_info(folder, settings) if resume else _new_info(folder, settings, space, styles)
    plan = Plan(space, settings, runs)
    info["focus"] = _focus_info(settings, plan, runs)
    config = ImageConfig(str(folder.path), settings.space, settings.preset, settings.camera, settings.extrinsics_from,
                         settings.cabin, render_threads(settings.workers), tuple(styles), settings.seed,
                         settings.renderer_factory, settings.render_device, settings.device, settings.variety())
    entries = folder.entries() if resume else {}
    start, made_now = time.monotonic(), 0
    if _usable(entries) < settings.n and len(entries) < plan.limit:   # else: a complete dataset, written again
        executor = make_executor(config, settings.workers, settings.cluster, task=IMAGES)   # checks the renderer
        try:
            output.mark()
            if not resume:
                folder.write_info(info)   # from here on the folder is this dataset
            made_now = _render_slots(folder, plan, settings.n, entries, executor, log, progress_stream)
        finally:
            executor.close()
    seconds = time.monotonic() - start
    return _finish(folder, space, settings, info, entries, made_now, seconds, log)


def _check_rendering(settings: DatasetSettings) -> None:
    """The preset, camera (a pose never registered is refused with the fix), cabin and prompt style."""
    from capture.camera import load_render_camera

    from ..render import get_preset, load_cabin
    from ..sut.prompt import prompt_style

    if isinstance(settings.preset, str):
        get_preset(settings.preset)
    load_render_camera(settings.camera, settings.extrinsics_from)
    load_cabin(settings.cabin)
    prompt_style(settings.prompt_style)


def _inputs(runs, styles: list[StyleSpec]) -> dict:
    return {"runs": runs_digest(runs) if runs else None, "styles": [s.to_dict() for s in styles]}


def _new_info(folder: DatasetDir, settings: DatasetSettings, space: SceneSpace, styles: list[StyleSpec]) -> dict:
    from ..render import get_preset, load_cabin

    if folder.is_dataset():
        raise DatasetError.naming(f"{folder.path} already holds a dataset; continue it with {{resume}}, or choose "
                                  "another folder for {out}")
    if not is_empty(folder.path):
        raise DatasetError(f"{folder.path} exists and is not an empty folder; choose a new folder for --out")
    preset = get_preset(settings.preset) if isinstance(settings.preset, str) else settings.preset
    environment = load_cabin(settings.cabin).get("lighting", {}).get("environment", "?")
    return {"format": FORMAT, "complete": False, "space": space.name, "space_hash": space.hash,
            "space_source": space.source, "settings": settings.to_dict(), "identity": settings.identity(),
            "preset": asdict(preset), "versions": versions(bool(styles)),
            "seeds": {"scenes": settings.seed, "style_noise": settings.seed, **_variety_seeds(settings)},
            "variety": settings.variety().describe() or None,
            "styles": [s.to_dict() for s in styles], "licences": licences(environment, [s.to_dict() for s in styles]),
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def _variety_seeds(settings: DatasetSettings) -> dict:
    variety = settings.variety()
    return {name: settings.seed for name, on in (("camera_jitter", variety.jitter.active),
                                                  ("sensor_effects", variety.effects.active),
                                                  ("camera_mix", bool(variety.cameras))) if on}


def _resume_info(folder: DatasetDir, settings: DatasetSettings) -> dict:
    if not folder.is_dataset():
        raise DatasetError.naming(f"no dataset to resume in {folder.path} (no dataset.json); start one without "
                                  "{resume}")
    info = folder.info()
    diffs = differences(info.get("identity", {}), settings.identity())
    if diffs:
        raise DatasetError.naming(f"{folder.path} was started with other settings; resume with the same ones (or "
                                  "choose another folder for {out}): " + "; ".join(diffs))
    info["settings"] = settings.to_dict()   # workers and cluster may change
    return info


def _focus_info(settings: DatasetSettings, plan: Plan, runs) -> dict | None:
    """The focus, with what defined a failing test: each run's SUT (and options) and oracle threshold."""
    if settings.focus is None:
        return None
    judged_by = [{"run": str(r.path.resolve()), "sut": r.sut, "sut_options": r.pipeline.get("sut_options") or {},
                  "threshold": r.oracle_threshold, "tests": len(r.valid),
                  "failing": sum(bool(t.failed) for t in r.valid)} for r in runs]
    return {"mode": settings.focus, "runs": list(settings.from_runs), "judged_by": judged_by,
            "regions": [r.to_dict() for r in plan.regions]}


def _usable(entries: dict[int, dict]) -> int:
    return sum(e["status"] == "ok" for e in entries.values())


def _render_slots(folder: DatasetDir, plan: Plan, n: int, entries: dict[int, dict], executor, log, stream) -> int:
    """Render the first slots until ``n`` are usable (or ``plan.limit`` slots were tried), committing each entry as
    it arrives (and adding it to ``entries``); the slots taken are always the lowest not yet done, so a resume
    renders what an uninterrupted build would have. Returns the usable frames made."""
    progress = Progress(n, label="images", stream=stream, verdicts=False)
    progress.done = progress.resumed = min(_usable(entries), n)
    made_now = 0
    while (need := n - _usable(entries)) > 0:
        todo = [s for s in range(plan.limit) if s not in entries][:need]
        if not todo:
            break
        jobs = [SlotJob(s, plan.slot(s).scene, plan.slot(s).region) for s in todo]
        for entry in executor.run(jobs):
            folder.commit(entry)
            entries[entry["slot"]] = entry
            if entry["status"] == "ok":
                made_now += 1
                progress.update()
            else:
                log(f"slot {entry['slot']}: skipped, {entry['reason']} (the next slot replaces it)")
    progress.close()
    return made_now


def _finish(folder: DatasetDir, space: SceneSpace, settings: DatasetSettings, info: dict, entries: dict[int, dict],
            made_now: int, seconds: float, log) -> DatasetSummary:
    ok = [entries[s] for s in sorted(entries) if entries[s]["status"] == "ok"][: settings.n]
    skipped = [{"slot": s, "reason": e["reason"]} for s, e in sorted(entries.items()) if e["status"] != "ok"]
    copies = sum(len(e["files"]) - 1 for e in ok)
    short = settings.n - len(ok)
    if info.get("focus"):
        got = Counter(e["region"] for e in ok)
        for region in info["focus"]["regions"]:
            region["scenes"] = got.get(region["region"], 0)
    info.update(complete=True, finished=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                counts={"images": len(ok) + copies, "renders": len(ok), "style_copies": copies,
                        "skipped": len(skipped), "short": short, **counts(space, ok)},
                skipped=skipped, costs=costs(ok, seconds, made_now) if made_now else info.get("costs"),
                image_size=sorted({f"{e['width']}x{e['height']}" for e in ok}),
                reproduce=reproduce(settings, str(folder.path)))
    _sweep(folder, ok)
    write_outputs(folder, space, ok, info, settings.prompt_style)
    if short:
        log(f"only {len(ok)} of {settings.n} images: {len(skipped)} frames could not show their scene and the "
            f"dataset gave up after {len(entries)} slots (see dataset.json: skipped)")
    return DatasetSummary(folder.path, len(ok), len(ok) + copies, len(skipped), made_now, seconds, short)


def _sweep(folder: DatasetDir, ok: list[dict]) -> None:
    """Remove the work folder and any image of ours no entry lists (a frame moved in just before a kill,
    whose slot a resume did not need)."""
    shutil.rmtree(folder.path / WORK_DIR, ignore_errors=True)
    listed = {f["file_name"] for e in ok for f in e["files"]}
    for path in (folder.path / IMAGES_DIR).glob("*.png"):
        if _OUR_IMAGE.match(path.name) and f"{IMAGES_DIR}/{path.name}" not in listed:
            path.unlink()
