"""Asking the SUT about every image of a pair, judged against the scene's truth.

The SUT is the run's kind (``open_sut``): repeats with the per-feature majority vote, replies
cached on disk, so a rerun or an interrupted ``agree`` does not pay twice. Answers are judged
by the VQA judge, so "correct" means here exactly what it meant in the run.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from ..evaluate.vqa import VQAJudge
from ..space import SceneSpace
from ..sut import build_request, query_guarded
from .compare import Judged


@dataclass
class Asked:
    """One image: the judged answers, what the SUT said, and any problem."""
    judged: Judged
    raw: str = ""
    answers: dict = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    consistency: float | None = None
    unreadable: bool = False        # the image itself is missing or broken: nothing to compare


def short(image: Path) -> str:
    """``real/frame_0001.png`` or ``sim.png``: how a sample's image is named in messages."""
    return f"{image.parent.name}/{image.name}" if image.parent.name == "real" else image.name


def readable_image(path: Path) -> str | None:
    """None when ``path`` is an image we can decode, else why not."""
    try:
        with Image.open(path) as img:
            img.load()
    except FileNotFoundError:
        return f"{path} is missing"
    except (UnidentifiedImageError, OSError, SyntaxError) as exc:
        return f"cannot read {path}: {exc}; re-export it as PNG or remove it"
    return None


class Asker:
    def __init__(self, sut, space: SceneSpace):
        self.sut, self.space, self.judge = sut, space, VQAJudge(space)

    def ask(self, scene: dict, image: Path) -> Asked:
        problem = readable_image(image)
        if problem:
            return Asked(Judged(error=problem), problems=[problem], unreadable=True)
        request = build_request(self.space, scene, image, "vqa")
        response = query_guarded(self.sut, request)
        if response.error:
            return Asked(Judged(error=f"SUT error: {response.error}"), raw=response.raw or "",
                         problems=[f"SUT error on {short(image)}: {response.error}"])
        verdict = self.judge.judge(scene, request, response)
        features = verdict.details.get("features", {})
        judged = Judged({k: (f["answer"], f["status"]) for k, f in features.items()})
        unanswered = [f"{k} ({f['status']})" for k, f in features.items() if f["status"] not in ("correct", "wrong")]
        problems = [f"the SUT did not answer {', '.join(unanswered)} on {short(image)}"] if unanswered else []
        problems += [f"{short(image)}: {p}" for p in response.problems]
        return Asked(judged, response.raw or "", dict(response.answers or {}), problems,
                     response.extra.get("consistency") if isinstance(response.extra, dict) else None)
