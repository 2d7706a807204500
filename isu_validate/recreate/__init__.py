"""Recreation for lab technicians: pick tests from runs, order them by effort, write the pairs and sheets.

    plan = plan_recreation(["runs/nsga2-s1"], mode="mixed", n=12, seed=0, out="pairs/")

Rooms: ``select`` (which tests), ``effort`` (change costs and the order), ``guide`` (the checklist
in words and measurements), ``sketch`` (top view), ``sheet`` (printable HTML). The pairs layout
itself is ``isu_validate.pairs``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from ..analysis.runs import Run, load_run, name_uniquely
from ..archive import find_runs
from ..pairs import PairsDir, PairsError, Sample
from ..space import SceneSpace, SpaceError, load_space
from .effort import EffortModel, best_order, load_effort, path_cost
from .guide import checklist
from .select import Candidate, select
from .sheet import SheetInfo, overview_html, page, relative, sheet_html
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
             cabin: str | os.PathLike | None = None) -> RecreatePlan:
    """Pick ``n`` tests of ``runs`` (``mode``: failing, passing or mixed) for a lab to recreate, order them
    by the effort of changing one scene into the next, and write a new pairs directory ``out`` with a
    printable sheet per scene (``isu-validate recreate``).

        plan = plan_recreation(["runs/nsga2-s1"], "mixed", n=12, seed=0, out="pairs/")
        plan.samples, plan.minutes
    """
    pairs = PairsDir(out)
    if pairs.root.exists() and any(pairs.root.iterdir()):
        raise PairsError(f"{pairs.root} is not empty; recreate writes a new pairs directory (choose another --out, "
                         "so no captured frame is ever overwritten)")
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
    _write(pairs, space, model, cabin_rig, [chosen.chosen[i] for i in order], plan)
    return plan


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


def _write(pairs: PairsDir, space: SceneSpace, model: EffortModel, cabin: dict, ordered: list[Candidate],
           plan: RecreatePlan) -> None:
    width = max(2, len(str(len(ordered))))
    sheets, previous = [], None
    for k, cand in enumerate(ordered, 1):
        camera = _camera_file(cand.run)
        if camera is None:
            plan.notes.append(f"{cand.run.name}: the camera rig {cand.run.pipeline.get('camera')!r} is gone; "
                              "samples have no camera.toml")
        sample = pairs.new_sample(f"S{k:0{width}d}", cand.label_file, cand.image, camera, cand.render_label)
        scene = cand.record.canonical
        changed = model.changed(previous, scene)
        info = SheetInfo(k, len(ordered), f"{cand.run.name} test {cand.record.test_id}", cand.failed,
                         [g.note or g.name for g in changed] if previous is not None else [],
                         model.step(previous, scene))
        items = checklist(space, scene, cabin)
        camera_text, camera_xy = _camera(sample)
        sample.sheet.write_text(page(f"{sample.name} recreation sheet",
                                     sheet_html(sample, items, cabin, info, sample.sim.name, camera_text, camera_xy)))
        sheets.append(sheet_html(sample, items, cabin, info, relative(sample.sim, pairs.root), camera_text,
                                 camera_xy))
        plan.samples.append({"sample": sample.name, "position": k, "run": str(cand.run.path),
                             "test_id": cand.record.test_id, "failed": cand.failed,
                             "fitness": cand.record.primary, "source": info.source,
                             "changes": info.changes, "minutes": info.minutes})
        previous = scene
    effort = {"minutes": plan.minutes, "run_order_minutes": plan.run_order_minutes, "source": model.source,
              "method": plan.method, "per_scene": model.per_scene}
    pairs.write_manifest({"samples": plan.samples, "effort": effort, "notes": plan.notes,
                          "space": space.name, "space_hash": space.hash})
    pairs.index_file.write_text(page("Recreation sheets", overview_html(plan.samples, effort, plan.notes)
                                                + "".join(sheets)))


def _camera(sample: Sample) -> tuple[str, tuple[float, float] | None]:
    """Where the camera is, in words and on the sketch (from the sample's camera.toml)."""
    if not sample.camera.is_file():
        return "no camera file", None
    from capture.camera import load_camera
    try:
        rig = load_camera(sample.camera)
    except ValueError as exc:    # CameraFileError names the problem; a bad number in the file is a ValueError
        return f"camera.toml unreadable ({exc})", None
    x, y, z = rig.position
    return (f"{rig.name} ({rig.width}x{rig.height}) at x = {x:+.2f} m, y = {y:+.2f} m, z = {z:.2f} m, "
            "as in camera.toml"), (x, y)
