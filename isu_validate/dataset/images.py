"""Making one dataset slot, in whichever process runs it (this one, a local pool's, a Dask worker's):
render the scene with its seg channel, turn the instance ids into COCO annotations, move the frame into
``images/``, add its style copies, and return the slot's manifest entry (the caller commits it).

The executors of ``isu_validate/execution.py`` run it as the ``Task`` ``IMAGES``: each process keeps one
``ImageMaker`` (one warm Blender worker, VGG loaded once) per configuration.
"""
from __future__ import annotations

import importlib
import json
import os
import shutil
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..execution import Task
from ..protocols import RenderError
from .folder import DatasetDir, LOGS_DIR
from .styles import StyleSpec


@dataclass(frozen=True)
class ImageConfig:
    """What every process needs to make slots (picklable: it travels to pool and Dask workers)."""
    out: str                     # the dataset folder (absolute; on a cluster, a path every worker sees)
    space: str
    preset: Any                  # a preset name or a render.Preset
    camera: str = "default"
    extrinsics_from: str | None = None
    cabin: str = "default"
    threads: int = 0             # Blender's and torch's threads in this process (0: all cores)
    styles: tuple[StyleSpec, ...] = ()
    style_seed: int = 0
    renderer_factory: str = ""   # module:function(space) -> renderer; empty: Blender
    render_device: str = "auto"  # Cycles' compute device
    device: str = "auto"         # the style transfer's torch device
    variety: Any = None          # a render.variety.Variety: per-scene camera jitter and sensor effects


@dataclass(frozen=True)
class SlotJob:
    slot: int
    scene: dict
    region: str


class ImageMaker:
    def __init__(self, config: ImageConfig):
        """Builds the renderer (Blender starts on the first render) and the style transfers: a bad camera,
        preset or style model fails here."""
        from ..space import load_space

        self.config = config
        self.folder = DatasetDir(Path(config.out))
        self.space = load_space(config.space)
        self.renderer = _renderer(config, self.space)
        self.stylist = None
        if config.styles:
            from .styles import Stylist
            self.stylist = Stylist(config.styles, config.threads or os.cpu_count() or 1, config.device)

    def make(self, job: SlotJob) -> dict:
        """The slot's manifest entry: ``status`` "ok" with its files, or "skipped" with the reason."""
        start = (time.perf_counter(), time.process_time())
        entry = {"slot": job.slot, "region": job.region, "scene": self.space.canonical(job.scene)}
        work = self.folder.work_dir()
        work.mkdir(parents=True, exist_ok=True)
        frame = work / f"{job.slot:06d}.png"
        try:
            return self._make(job, entry, frame, start)
        finally:
            for leftover in work.glob(f"{job.slot:06d}.*"):
                leftover.unlink(missing_ok=True)

    def _make(self, job: SlotJob, entry: dict, frame: Path, start: tuple[float, float]) -> dict:
        import cv2

        from ..evaluate.occlusion import nothing_to_judge
        from .coco import instance_annotations

        try:
            result = self.renderer.render(job.scene, frame)
        except RenderError as exc:   # an unusable frame: the slot is skipped, the next one replaces it
            return {**entry, "status": "skipped", "reason": str(exc) or type(exc).__name__}
        hidden = nothing_to_judge(self.space, entry["scene"], result.occluded)
        if hidden:
            return {**entry, "status": "skipped", "reason": hidden}
        ids = cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED)
        render_s = time.perf_counter() - start[0]
        name = self.folder.image_name(job.slot)
        (self.folder.path / name).parent.mkdir(exist_ok=True)
        os.replace(frame, self.folder.path / name)   # the same file system: the frame appears whole
        files = [{"file_name": name, "variant": "render"}]
        style_s = []
        for k, spec in enumerate(self.config.styles):
            copy = self.folder.image_name(job.slot, k + 1)
            style_s.append(self.stylist.stylise(k, self.folder.path / name, self.folder.path / copy,
                                                self.config.style_seed))
            files.append({"file_name": copy, "variant": f"style{k + 1}", "style": spec.image,
                          "style_method": spec.method})
        return {**entry, "status": "ok", "files": files, "width": int(ids.shape[1]), "height": int(ids.shape[0]),
                "visibility": dict(result.visibility), "occluded": list(result.occluded),
                "annotations": instance_annotations(ids), "up": dict(result.up),
                **({"variety": result.variety} if result.variety else {}),
                "timings": {"render_s": round(render_s, 4), "style_s": [round(s, 3) for s in style_s],
                            # CPU seconds: Blender's worker, and this process (posing, outputs, masks, styles)
                            "worker_cpu_s": result.timings.get("worker_cpu_s"),
                            "host_cpu_s": round(time.process_time() - start[1], 4)}}

    def close(self) -> None:
        close = getattr(self.renderer, "close", None)
        if close:
            close()
        shutil.rmtree(self.folder.work_dir(), ignore_errors=True)


def _renderer(config: ImageConfig, space):
    from ..render.variety import vary

    renderer = _plain_renderer(config, space)
    if config.variety is None:
        return renderer
    try:
        return vary(renderer, config.variety)
    except InputError:
        renderer.close()
        raise


def _plain_renderer(config: ImageConfig, space):
    if config.renderer_factory:
        module, _, name = config.renderer_factory.partition(":")
        try:
            return getattr(importlib.import_module(module), name)(space)
        except (ImportError, AttributeError, ValueError) as exc:
            raise InputError(f"cannot load the renderer factory {config.renderer_factory!r}: {exc}") from None
    from ..render import get_preset, open_renderer

    preset = (get_preset(config.preset, threads=config.threads) if isinstance(config.preset, str)
              else replace(config.preset, threads=config.threads))
    return open_renderer(preset, config.camera, config.cabin, ("seg",), None, Path(config.out) / LOGS_DIR,
                         space=space, extrinsics_from=config.extrinsics_from, device=config.render_device)


# ---- the Task: one ImageMaker per process and configuration, as pipeline.py keeps one Pipeline
_MAKERS: dict[str, ImageMaker] = {}


def _key(config: ImageConfig) -> str:
    return json.dumps(repr(config))


def open_maker(config: ImageConfig) -> ImageMaker:
    if _key(config) not in _MAKERS:
        _MAKERS[_key(config)] = ImageMaker(config)
    return _MAKERS[_key(config)]


def check_maker(config: ImageConfig) -> None:
    ImageMaker(config).close()


def make_slot(config: ImageConfig, job: SlotJob) -> dict:
    return open_maker(config).make(job)


def close_maker(config: ImageConfig) -> None:
    maker = _MAKERS.pop(_key(config), None)
    if maker is not None:
        maker.close()


def close_makers() -> None:
    while _MAKERS:
        _MAKERS.popitem()[1].close()


IMAGES = Task(open_maker, check_maker, make_slot, close_maker, close_makers)
