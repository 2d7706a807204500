"""Asking the SUT about photographs whose true answers are known: one request per image, the questions its
labels answer (never the truth), replies through the response cache so an interrupted ``transfer`` goes
on where it stopped and never pays a SUT call twice."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..progress import Progress
from ..space import Question, SceneSpace
from ..sut.prompt import questions_request
from ..sut.runner import query_guarded


@dataclass(frozen=True)
class Item:
    name: str                 # unique within its set (the path under the set's root)
    image: Path
    truth: dict[str, str]     # feature -> true answer
    group: str | None = None  # its cluster (driver, clip) where the set says
    labels: tuple[str, ...] = ()   # a real photo's own labels (class folder, box classes): answers per label


def ask_all(sut, space: SceneSpace, items: list[Item], features: list[str], label: str, prompt: str | None = None,
            style: str | None = None, stream=None) -> list[dict]:
    """One record per item: ``truth``, ``said`` (None where unanswered), ``p`` (class probabilities where
    the SUT gives them), ``error``, ``latency_s``, ``cached``."""
    progress = Progress(len(items), label=f"asking about {label}", stream=stream)
    records = []
    for item in items:
        questions = [_question(space, f, item.truth[f]) for f in features if f in item.truth]
        response = query_guarded(sut, questions_request(space, questions, item.image, prompt, style))
        said = response.answers or {}
        probabilities = (response.extra.get("meta") or {}).get("probabilities") or {}
        records.append({"name": item.name, "image": str(item.image), "group": item.group,
                        "truth": {q.key: q.truth for q in questions},
                        "said": {q.key: said.get(q.key) for q in questions},
                        "p": {q.key: probabilities[q.key] for q in questions if q.key in probabilities},
                        "error": response.error, "problems": list(response.problems),
                        "latency_s": round(response.latency_s, 4),
                        "cached": all(response.extra.get("cached", [False])),
                        **({"labels": list(item.labels)} if item.labels else {})})
        progress.update(failed=any(said.get(q.key) != q.truth for q in questions), errored=bool(response.error),
                        resumed=records[-1]["cached"])
    progress.close()
    return records


def _question(space: SceneSpace, feature: str, truth: str) -> Question:
    f = space.features[feature]
    return Question(f.name, f.question, f.options, f.weight, truth)
