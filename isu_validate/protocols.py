"""The seams between stages: what the search's evaluation expects of a renderer, a SUT and a judge.

Real implementations live in ``isu_validate.render``, ``isu_validate.sut`` and
``isu_validate.evaluate``; tests may pass doubles that satisfy these protocols.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Protocol, Sequence

from .space import Question


class RenderError(RuntimeError):
    """A scene could not be rendered (after the renderer's own retry), or its frame cannot show the
    scene (black, saturated, no driver); ``image`` is then the unusable frame, kept for inspection."""

    def __init__(self, message: str = "", image: Path | None = None):
        super().__init__(message)
        self.image = image


@dataclass
class RenderResult:
    image: Path                                              # sRGB PNG
    channels: dict[str, Path] = field(default_factory=dict)  # e.g. {"seg": ..., "depth": ...}
    timings: dict[str, float] = field(default_factory=dict)  # update_s, render_s, write_s, total_s
    cached: bool = False
    visibility: dict[str, float] = field(default_factory=dict)  # feature -> visible share (things that exist)
    occluded: list[str] = field(default_factory=list)           # features seen too little to be judged
    up: dict[str, list[float]] = field(default_factory=dict)    # instance -> where its top points (object_axes)
    variety: dict[str, Any] = field(default_factory=dict)       # the camera jitter and sensor effects drawn (variety)


class Renderer(Protocol):
    def render(self, scene: Mapping[str, Any], out: Path) -> RenderResult:
        """Render a valid (canonical) scene to ``out`` (a .png path); raise RenderError on failure."""

    def close(self) -> None: ...


@dataclass
class SUTRequest:
    mode: str                       # "vqa" or "vc"
    image: Path
    prompt: str
    questions: Sequence[Question] = ()


@dataclass
class SUTResponse:
    raw: str = ""                                  # what the SUT said, verbatim (kept in the archive)
    answers: dict[str, str] | None = None          # vqa: parsed answers, keys of the questions
    caption: str | None = None                     # vc
    problems: list[str] = field(default_factory=list)  # parse problems, per feature where possible
    error: str | None = None                       # SUT error: timeout, HTTP failure, unparseable
    latency_s: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)  # e.g. repeats, consistency


class SUT(Protocol):
    id: str

    def query(self, request: SUTRequest) -> SUTResponse: ...


@dataclass
class Verdict:
    """How good a SUT response was for one scene."""
    fitness: dict[str, float]          # e.g. {"f_qa": 0.8} or {"f_emb":..., "f_bleu":..., ...}
    primary: float                     # the value the search minimises
    failed: bool                       # the oracle's verdict at the run's threshold
    details: dict[str, Any] = field(default_factory=dict)  # per-feature status etc.
