"""What the SUT is asked: the VQA prompt built from the scene space, and the captioning prompt.

The VQA prompt follows the paper's Figure 2: the space's rules, then one line per
active predicted feature with its key, question and answer options, then the JSON
shape to return.  Only the scene's active predicted features are asked (no
question about luggage colour when there is no luggage); the true answers never
leave this process (``Question.to_dict`` carries no truth).
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping, Sequence

from ..protocols import SUTRequest
from ..space import Question, SceneSpace

DEFAULT_CAPTION_PROMPT = "Describe what is visible in the scene, paying attention especially to humans and loose objects"
MODES = ("vqa", "vc")
QUESTIONS_SLOT = "{questions}"


def questions_block(questions: Sequence[Question]) -> str:
    lines = [f'- "{q.key}": {q.question} Options: {", ".join(q.options)}' for q in questions]
    shape = json.dumps({q.key: "|".join(q.options) for q in questions})
    return "Questions (key: question, options):\n" + "\n".join(lines) + f"\n\nReturn JSON of this shape: {shape}"


def vqa_prompt(space: SceneSpace, questions: Sequence[Question], header: str | None = None) -> str:
    """The space's rules (or a user's ``header``) followed by the questions.

    A user header may place the questions with a ``{questions}`` slot; otherwise they follow it.
    """
    block = questions_block(questions)
    if header is None:
        header = "\n".join(space.prompt_rules) or "Answer each question about the image with one of its options."
    if QUESTIONS_SLOT in header:
        return header.replace(QUESTIONS_SLOT, block)
    return f"{header.rstrip()}\n\n{block}"


def build_request(space: SceneSpace, scene: Mapping[str, Any], image: str | Path, mode: str,
                  prompt: str | None = None) -> SUTRequest:
    """The request for one scene: VQA questions about its active predicted features, or a caption prompt."""
    if mode not in MODES:
        raise ValueError(f"unknown SUT mode {mode!r}; use 'vqa' (questions) or 'vc' (captioning)")
    if mode == "vc":
        return SUTRequest(mode="vc", image=Path(image), prompt=prompt or DEFAULT_CAPTION_PROMPT, questions=())
    questions = space.questions(scene)
    return SUTRequest(mode="vqa", image=Path(image), prompt=vqa_prompt(space, questions, prompt),
                      questions=tuple(questions))
