"""Evaluating one test: render the scene, ask the SUT, judge the answer.

A ``Pipeline`` is built once per process from a picklable ``PipelineConfig`` (so a
process pool or a Dask worker each builds its own renderer and SUT client) and turns
a ``Job`` into a ``TestRecord``.  Which renderer, SUT and judge are used is decided by
``config.factory`` (``module:function``); the default builds the real ones.
"""
from __future__ import annotations

import importlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .archive import RunDir, TestRecord
from .archive.run_dir import IMAGES_DIR, LABELS_DIR
from .protocols import RenderError
from .evaluate.occlusion import nothing_to_judge
from .space import SceneSpace, load_space
from .sut.runner import query_guarded
from .config import PipelineConfig   # defined in a light module (the CLI shows its defaults)
from .errors import InputError

DEFAULT_FACTORY = PipelineConfig.factory   # the real renderer, SUT and judge


@dataclass
class Job:
    test_id: str
    generation: int
    index: int
    algorithm: str
    seed: int
    scene: dict
    scene_key: str
    f_div: float


@dataclass
class Components:
    renderer: Any
    sut: Any
    judge: Any
    build_request: Any               # (space, scene, image, mode, prompt) -> SUTRequest
    extra: dict = field(default_factory=dict)


def build_components(config: PipelineConfig, space: SceneSpace) -> Components:
    """The real renderer (Blender), SUT adapter and judge."""
    from functools import partial

    from .evaluate import make_judge
    from .sut import build_request, open_sut

    run_dir = Path(config.run_dir)
    renderer = build_renderer(config, space)
    sut = open_sut(config.sut, space=space, repeats=config.repeats, cache_dir=run_dir / "cache" / "sut",
                   device=config.device,
                   timeout_s=config.sut_timeout_s, **config.sut_options)
    options = {"template": config.caption_template} if config.mode == "vc" else {}
    judge = make_judge(config.mode, space, threshold=config.threshold, **options)
    return Components(renderer, sut, judge, partial(build_request, style=config.prompt_style))


def build_renderer(config: PipelineConfig, space: SceneSpace):
    """The real renderer with a run's render settings (its render cache and Blender logs in ``config.run_dir``)."""
    from .render import open_renderer

    run_dir = Path(config.run_dir)
    return open_renderer(preset=config.preset, camera=config.camera, cabin=config.cabin,
                         channels=config.channels, cache_dir=run_dir / "cache" / "render",
                         log_dir=run_dir / "logs", space=space, threads=config.render_threads,
                         extrinsics_from=config.extrinsics_from, min_visible=config.min_visible,
                         device=config.render_device)


def open_run_renderer(config: PipelineConfig, space: SceneSpace):
    """The renderer a run's tests were rendered with (``replay`` re-renders a missing frame with it): the real
    one, or the one of the run's own pipeline factory (``--pipeline-factory``), whose SUT is closed unused."""
    if config.factory == DEFAULT_FACTORY:
        return build_renderer(config, space)
    parts = _load_factory(config.factory)(config, space)
    close = getattr(parts.sut, "close", None)
    if close:
        close()
    return parts.renderer


def check_render_settings(config: PipelineConfig, space: SceneSpace) -> None:
    """Refuse, before a run writes anything, a camera whose pose was never registered (with the fix)
    and visibility thresholds that name no feature or lie outside [0, 1]."""
    from capture.camera import load_render_camera
    from .render.visibility import min_visible_for, needed_parts

    load_render_camera(config.camera, config.extrinsics_from)
    needed_parts(space)
    min_visible_for(space, config.min_visible)


def _load_factory(path: str):
    module, _, name = path.partition(":")
    if not module or not name:
        raise InputError(f"pipeline factory must be 'module:function', got {path!r}")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise InputError(f"cannot load the pipeline factory {path!r}: {exc}") from None


class Pipeline:
    def __init__(self, config: PipelineConfig):
        """Builds every component, so a bad setting fails here; writes nothing (the run directory
        may not exist yet: a run checks its pipeline before it writes its first file)."""
        self.config = config
        self.space = load_space(config.space)
        self.run_dir = Path(config.run_dir)
        self.parts: Components = _load_factory(config.factory)(config, self.space)
        self._dirs_made = False

    def evaluate(self, job: Job) -> TestRecord:
        if not self._dirs_made:
            for sub in (IMAGES_DIR, LABELS_DIR):
                (self.run_dir / sub).mkdir(parents=True, exist_ok=True)
            self._dirs_made = True
        canonical = self.space.check(job.scene)
        record = TestRecord(test_id=job.test_id, generation=job.generation, index=job.index,
                            algorithm=job.algorithm, seed=job.seed, scene_key=job.scene_key,
                            scene=job.scene, canonical=canonical, f_div=job.f_div)
        self._write_label(job, canonical)
        image = self._render(record)
        if image is not None:
            self._write_label(job, canonical, record)   # with what the frame shows of each feature
            hidden = nothing_to_judge(self.space, canonical, record.occluded)
            if hidden:
                record.render_error = hidden   # no verdict, like an error: the SUT is not asked
            else:
                self._ask_and_judge(record, image)
        record.created = time.time()
        return record

    def _write_label(self, job: Job, canonical: dict, record: TestRecord | None = None) -> None:
        label = {"test_id": job.test_id, "space": self.space.name, "space_hash": self.space.hash,
                 "scene_key": job.scene_key, "scene": canonical,
                 "truth": {q.key: q.truth for q in self.space.questions(canonical)}}
        if record is not None:
            label.update(visibility=record.visibility, occluded=record.occluded)
        RunDir(self.run_dir).label_file(job.test_id).write_text(json.dumps(label, indent=2))

    def _render(self, record: TestRecord) -> Path | None:
        out = RunDir(self.run_dir).image_file(record.test_id)
        start = time.perf_counter()
        try:
            result = self.parts.renderer.render(record.canonical, out)
        except RenderError as exc:
            record.render_error = str(exc) or type(exc).__name__
            record.timings["render_s"] = time.perf_counter() - start
            if getattr(exc, "image", None):   # an unusable frame (black, saturated...): kept to look at
                record.image = _relative(exc.image, self.run_dir)
            return None
        record.timings.update({k: float(v) for k, v in result.timings.items()})
        record.details["visibility"] = dict(getattr(result, "visibility", {}) or {})
        record.details["occluded"] = list(getattr(result, "occluded", []) or [])
        record.timings["render_s"] = time.perf_counter() - start
        record.details["render_cached"] = bool(result.cached)
        record.details["channels"] = {k: _relative(v, self.run_dir) for k, v in result.channels.items()}
        record.image = _relative(result.image, self.run_dir)
        return Path(result.image)

    def _ask_and_judge(self, record: TestRecord, image: Path) -> None:
        request = self.parts.build_request(self.space, record.canonical, image, self.config.mode, self.config.prompt)
        start = time.perf_counter()
        response = query_guarded(self.parts.sut, request)  # an adapter bug is this test's SUT error
        record.timings["sut_s"] = time.perf_counter() - start
        record.sut_raw, record.answers, record.caption = response.raw, response.answers, response.caption
        record.sut_error = response.error
        record.details["problems"] = list(response.problems)
        record.details["sut"] = dict(response.extra)
        verdict = self.parts.judge.judge(record.canonical, request, response, occluded=record.occluded)
        record.fitness, record.primary, record.failed = dict(verdict.fitness), verdict.primary, verdict.failed
        record.details["verdict"] = verdict.details

    def close(self) -> None:
        for part in (self.parts.renderer, self.parts.sut):
            close = getattr(part, "close", None)
            if close:
                close()


def _relative(path, root: Path) -> str:
    path = Path(path)
    try:
        return str(path.resolve().relative_to(root.resolve()))
    except ValueError:
        return str(path)


# One pipeline per process and configuration: worker processes and Dask workers reuse it.
_PIPELINES: dict[str, Pipeline] = {}


def _key(config: PipelineConfig) -> str:
    return json.dumps(config.to_dict(), sort_keys=True)


def open_pipeline(config: PipelineConfig) -> Pipeline:
    """This process's pipeline for ``config``, built on first use."""
    key = _key(config)
    if key not in _PIPELINES:
        _PIPELINES[key] = Pipeline(config)
    return _PIPELINES[key]


def check_pipeline(config: PipelineConfig) -> None:
    """Build every component once and close them again: raises what a worker would raise."""
    Pipeline(config).close()


def evaluate_job(config: PipelineConfig, job: Job) -> TestRecord:
    return open_pipeline(config).evaluate(job)


def close_pipeline(config: PipelineConfig) -> None:
    """End this process's pipeline for ``config`` (its renderer's Blender process with it)."""
    pipeline = _PIPELINES.pop(_key(config), None)
    if pipeline is not None:
        pipeline.close()


def close_pipelines() -> None:
    while _PIPELINES:
        _PIPELINES.popitem()[1].close()
