"""The settings of a run: ``PipelineConfig`` (how each test is evaluated) and ``RunConfig`` (how
the search runs over it), as ``run.json`` stores them.

Plain dataclasses and the defaults the command line shows in ``isu-validate run --help``, in a
module that imports nothing heavy (no pipeline, no search, no numpy). The pipeline (``pipeline``)
and the run loop (``search.loop``) use them and re-export their own.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

from .errors import InputError

DEFAULT_MIN_VISIBLE = 0.25     # a quarter of a thing seen: partly hidden is a fair test, hardly seen is not
DEFAULT_SUT_ERROR_LIMIT = 5   # SUT errors in a row, no answer between, that stop a run (--stop-after-sut-errors)

# How the work is spread, or when the run stops: these may change when a run is resumed.
VOLATILE = ("workers", "cluster", "budget_tests", "budget_s", "stop_after_sut_errors")


@dataclass(frozen=True)
class PipelineConfig:
    """How each test is evaluated: where the run lives, the scene space, the SUT and how it is asked,
    the render settings and the oracle threshold (the ``run`` options that decide what is measured).

        PipelineConfig(run_dir="runs/gpt", sut="openai:gpt-4o@https://api.openai.com/v1", preset="standard")
    """
    run_dir: str
    space: str = "isu-paper"
    sut: str = "reference"
    mode: str = "vqa"                 # "vqa" or "vc"
    threshold: float | None = None    # oracle threshold; None = the judge's default
    prompt: str | None = None         # None = generated from the space / default caption prompt
    prompt_style: str = "paper"       # VQA prompt wording: "paper" (Figure 2) or "compact" (sut.prompt)
    caption_template: str | None = None  # reference-caption template name or file; None = the space's
    repeats: int = 1
    preset: str = "draft"
    camera: str = "default"
    cabin: str = "default"
    channels: tuple[str, ...] = ()
    sut_timeout_s: float = 60.0
    sut_options: dict = field(default_factory=dict)  # adapter options (never secrets: keys come from env)
    render_threads: int = 0           # Cycles threads per renderer (0 = all cores; split them across workers)
    render_device: str = "auto"       # Cycles' compute device (devices.RENDER_DEVICES; render/gpu.py)
    device: str = "auto"              # where torch work runs: the reference ISU, caption embeddings (devices.py)
    extrinsics_from: str | None = None  # camera rig whose cabin pose replaces the camera's own
    min_visible: dict = field(default_factory=dict)  # visibility thresholds {feature or "*": share} over the space's
    factory: str = "isu_validate.pipeline:build_components"

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class RunConfig:
    """What a run searches with (algorithm, population, seed, budget) over its ``PipelineConfig``.

        RunConfig(PipelineConfig(run_dir="runs/s1", sut="reference"), algorithm="rs", budget_tests=40, seed=1)
    """
    pipeline: PipelineConfig
    algorithm: str = "surrogate"
    pop_size: int = 10
    seed: int = 1
    budget_tests: int | None = 40
    budget_s: float | None = None
    workers: int = 1
    cluster: str | None = None
    stop_after_sut_errors: int = DEFAULT_SUT_ERROR_LIMIT  # SUT errors in a row with no answer between; 0 = never stop
    learn_from: tuple[str, ...] = ()            # earlier runs of the same SUT the search learns from first

    def check(self) -> None:
        """The plain values; the components are checked by building them (``make_executor``)."""
        if self.budget_tests is not None and self.budget_tests < 1:
            raise InputError(f"--budget must be at least 1 test, got {self.budget_tests}")
        if self.budget_s is not None and not self.budget_s > 0:
            raise InputError(f"--budget-time must be a positive number of seconds, got {self.budget_s}")
        if self.workers < 1:
            raise InputError(f"--workers must be at least 1, got {self.workers}")
        if self.stop_after_sut_errors < 0:
            raise InputError(f"--stop-after-sut-errors must be 0 (never stop) or more, "
                             f"got {self.stop_after_sut_errors}")

    def identity(self) -> dict:
        """What must match for a resume to continue the same search."""
        data = asdict(self)
        for volatile in VOLATILE:
            data.pop(volatile)
        data["pipeline"].pop("run_dir")
        for how in ("render_threads", "render_device", "device"):   # how the work is done, not what it computes
            data["pipeline"].pop(how)
        if not data["learn_from"]:
            data.pop("learn_from")  # runs started before --learn-from existed resume unchanged
        return json.loads(json.dumps(data))  # as stored in run.json (tuples become lists)
