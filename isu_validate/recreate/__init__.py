"""Recreation for lab technicians: pick tests from runs, order them by effort, write the pairs and sheets.

    plan = plan_recreation(["runs/nsga2-s1"], mode="mixed", n=12, seed=0, out="pairs/")

Rooms: ``select`` (which tests), ``effort`` (change costs and the order), ``guide`` (the checklist
in words and measurements), ``body`` (a weight class in kilograms at the rendered height), ``light``
(what the light levels mean), ``aim`` (where the camera points), ``pictures`` (the scene rendered for
print, crops), ``sketch`` (top view), ``sheet`` (printable HTML). The pairs layout itself is
``isu_validate.pairs``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..analysis.runs import Run, load_run, name_uniquely
from ..archive import find_runs
from ..archive.output_dir import claim_output, is_empty
from ..pairs import PairsDir, PairsError, Sample
from ..protocols import RenderError
from ..space import SceneSpace, SpaceError, load_space
from .aim import camera_aim
from .effort import EffortModel, best_order, load_effort, path_cost
from .guide import checklist
from .light import light_rows
from .pictures import RUN_FRAME, SHEET_PRESET, Picture, Pictures, Setup, sheet_crops
from .select import Candidate, select
from .sheet import SheetContent, SheetInfo, overview_html, page, relative, sheet_html
from ..errors import InputError

__all__ = ["RecreatePlan", "recreate"]


@dataclass
class RecreatePlan:
    out: Path
    samples: list[dict]
    minutes: float
    run_order_minutes: float
    method: str
    notes: list[str] = field(default_factory=list)

    @property
    def saving(self) -> float:
        return 1.0 - self.minutes / self.run_order_minutes if self.run_order_minutes else 0.0


def plan_recreation(runs: list[str | os.PathLike], mode: str, n: int, seed: int, out: str | os.PathLike,
             failing_share: float | None = None, effort: str | os.PathLike = "default",
             cabin: str | os.PathLike | None = None, sheet_preset: str = SHEET_PRESET,
             open_renderer: Callable | None = None) -> RecreatePlan:
    """Pick ``n`` tests of ``runs`` (``mode``: failing, passing or mixed) for a lab to recreate, order them
    by the effort of changing one scene into the next, and write a new pairs directory ``out`` with a
    printable sheet per scene (``isu-validate recreate``). Each sheet's picture is the scene rendered
    again at ``sheet_preset`` (640 px wide or more; ``"run"``: the run's own frame, no Blender);
    ``open_renderer`` replaces ``isu_validate.render.open_renderer`` for that.

        plan = plan_recreation(["runs/nsga2-s1"], "mixed", n=12, seed=0, out="pairs/")
        plan.samples, plan.minutes
    """
    _check_preset(sheet_preset)
    pairs = PairsDir(out)
    # another command's output is named; any other content (an earlier recreate, captured frames) is "not empty"
    output = claim_output(pairs.root, "recreate", {"runs": [str(Path(r).resolve()) for r in runs], "mode": mode,
                                                   "n": n, "seed": seed}, resume=True, overwrite=None)
    if not is_empty(pairs.root):
        raise PairsError.naming(f"{pairs.root} is not empty; recreate writes a new pairs directory (choose another "
                                "folder for {out}, so no captured frame is ever overwritten)")
    loaded = name_uniquely([load_run(p) for p in find_runs(list(runs))])
    space = _space(loaded)
    chosen = select(loaded, mode, n, seed, failing_share)
    model = load_effort(effort, space)
    cabin_rig = _cabin(cabin or loaded[0].pipeline.get("cabin", "default"))
    scenes = [c.record.canonical for c in chosen.chosen]
    setup, cost = model.matrix(scenes)
    order = best_order(setup, cost)
    method = "exact (Held-Karp)" if len(scenes) <= 12 else "nearest neighbour + 2-opt/or-opt"
    plan = RecreatePlan(pairs.root, [], path_cost(setup, cost, order),
                        path_cost(setup, cost, list(range(len(scenes)))), method, list(chosen.notes))
    plan.notes += [f"effort file {model.source} names features this space does not have: {', '.join(model.unused)}"
                   ] if model.unused else []
    pictures = Pictures(sheet_preset, open_renderer)
    output.mark()
    try:
        _write(pairs, space, model, cabin_rig, [chosen.chosen[i] for i in order], plan, pictures)
    finally:
        pictures.close()
    return plan


def _check_preset(name: str) -> None:
    from ..render.presets import PRESETS
    if name != RUN_FRAME and name not in PRESETS:
        raise InputError(f"unknown --sheet-preset {name!r}; use a render preset ({', '.join(PRESETS)}) or "
                         f"{RUN_FRAME!r} (the run's own frames, no Blender)")


def _space(runs: list[Run]) -> SceneSpace:
    """The runs' common space; its words for people (labels, descriptions) from the space file when it
    is still the one the run used."""
    hashes = {r.info.get("space_hash") for r in runs}
    if len(hashes) > 1:
        raise InputError("the runs use different scene spaces; recreate tests of one space at a time")
    run = runs[0]
    try:
        named = load_space(run.info.get("space_source") or run.pipeline.get("space", "isu-paper"))
        if named.hash == run.space.hash:
            return named
    except (SpaceError, FileNotFoundError):
        pass
    return run.space


def _cabin(name_or_path) -> dict:
    from ..render.cabin import load_cabin
    return load_cabin(name_or_path)


def _camera_file(run: Run) -> Path | None:
    """The camera rig file the run rendered with (a shipped name or a path)."""
    from ..paths import resolve_rig
    try:
        return resolve_rig("cameras", run.pipeline.get("camera", "default"))
    except FileNotFoundError:
        return None


def _setup(run: Run, space: SceneSpace, notes: list[str]) -> Setup | None:
    """The run's camera (pose from --extrinsics-from applied), cabin and visibility thresholds."""
    from capture.camera import load_render_camera
    pipeline = run.pipeline
    try:
        camera = load_render_camera(pipeline.get("camera", "default"), pipeline.get("extrinsics_from"))
    except (ValueError, FileNotFoundError) as exc:   # CameraFileError is a ValueError
        notes.append(f"{run.name}: its camera cannot be read ({exc}); its sheets show the run's frames and no aim")
        return None
    return Setup(camera, pipeline.get("cabin", "default"), space, pipeline.get("min_visible") or {})


def _write(pairs: PairsDir, space: SceneSpace, model: EffortModel, cabin: dict, ordered: list[Candidate],
           plan: RecreatePlan, pictures: Pictures) -> None:
    width = max(2, len(str(len(ordered))))
    sheets, previous, setups = [], None, {}
    for k, cand in enumerate(ordered, 1):
        camera = _camera_file(cand.run)
        if camera is None:
            plan.notes.append(f"{cand.run.name}: the camera rig {cand.run.pipeline.get('camera')!r} is gone; "
                              "samples have no camera.toml")
        sample = pairs.new_sample(f"S{k:0{width}d}", cand.label_file, cand.image, camera, cand.render_label)
        scene = cand.record.canonical
        if cand.run.name not in setups:
            setups[cand.run.name] = _setup(cand.run, space, plan.notes)
        setup = setups[cand.run.name]
        changed = model.changed(previous, scene)
        info = SheetInfo(k, len(ordered), f"{cand.run.name} test {cand.record.test_id}", cand.failed,
                         [g.note or g.name for g in changed] if previous is not None else [],
                         model.step(previous, scene))
        picture = _picture(pictures, sample, scene, setup, plan.notes)
        content = sheet_content(sample, space, cabin, info, picture, setup)
        sample.sheet.write_text(page(f"{sample.name} recreation sheet",
                                     sheet_html(content, relative(picture.image, sample.path))))
        sheets.append(sheet_html(content, relative(picture.image, pairs.root)))
        plan.samples.append({"sample": sample.name, "position": k, "run": str(cand.run.path),
                             "test_id": cand.record.test_id, "failed": cand.failed,
                             "fitness": cand.record.primary, "source": info.source,
                             "changes": info.changes, "minutes": info.minutes})
        previous = scene
    effort = {"minutes": plan.minutes, "run_order_minutes": plan.run_order_minutes, "source": model.source,
              "method": plan.method, "per_scene": model.per_scene}
    pairs.write_manifest({"samples": plan.samples, "effort": effort, "notes": plan.notes,
                          "space": space.name, "space_hash": space.hash, "sheet_preset": pictures.preset})
    pairs.index_file.write_text(page("Recreation sheets", overview_html(plan.samples, effort, plan.notes)
                                                + "".join(sheets)))


def sheet_content(sample: Sample, space: SceneSpace, cabin: dict, info: SheetInfo, picture: Picture,
                  setup: Setup | None) -> SheetContent:
    """What one sample's sheet shows: its checklist (the features its render hid flagged), the camera's aim,
    the light levels, the picture and its crops."""
    scene = sample.scene()
    items = checklist(space, scene, cabin, _hidden(sample))
    return SheetContent(sample.name, sample.path, info, items, cabin, picture,
                        camera_aim(setup.camera) if setup else None, _camera_name(setup),
                        light_rows(space, scene, cabin), sheet_crops(items, picture))


def _picture(pictures: Pictures, sample: Sample, scene: dict, setup: Setup | None, notes: list[str]) -> Picture:
    """The sheet's picture; the run's frame when the render for the sheet fails (named in the notes)."""
    try:
        return pictures.picture(sample, scene, setup)
    except RenderError as exc:
        notes.append(f"{sample.name}: the sheet's picture could not be rendered ({exc}); it shows the run's frame")
        return pictures.picture(sample, scene, None)


def _hidden(sample: Sample) -> dict[str, float]:
    """Features the run's render hid (its label's ``occluded``), with their visible share."""
    label = sample.label()
    shares = label.get("visibility") or {}
    return {name: float(shares.get(name, 0.0)) for name in label.get("occluded") or ()}


def _camera_name(setup: Setup | None) -> str:
    if setup is None:
        return "no camera file"
    return f"{setup.camera.name} ({setup.camera.width}x{setup.camera.height}, camera.toml)"
