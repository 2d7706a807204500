"""What the SUT is asked: the VQA prompt built from the scene space, and the captioning prompt.

Two wordings of the VQA prompt (``--prompt-style``):

- ``paper`` (default): the paper's Figure 2. An instruction, the ``# Rules`` (only the
  JSON, no explanations, exactly one of the given ``answer_options`` per question, no new
  answers, "NONE" for something not present), then one ``key`` / ``question`` /
  ``answer_options`` block per question and the JSON object to return.
- ``compact``: isu-validate's earlier wording: four short rules, one line per question
  ("- "key": question Options: A, B") and the JSON shape.

A space's ``prompt_rules`` (or a user's ``--prompt``) replace the text before the
questions in either style; a user header may place the questions with ``{questions}``.
Only the scene's active predicted features are asked (no question about luggage colour
when there is no luggage); the true answers never leave this process
(``Question.to_dict`` carries no truth).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

from ..errors import InputError

if TYPE_CHECKING:   # the styles are read by the command line's --help: no numpy, no space package
    from ..protocols import SUTRequest
    from ..space import Question, SceneSpace

DEFAULT_CAPTION_PROMPT = ("Describe what is visible in the scene, paying attention especially to humans "
                          "and loose objects")
MODES = ("vqa", "vc")
QUESTIONS_SLOT = "{questions}"


def _paper_questions(questions: Sequence[Question]) -> str:
    blocks = [f"key: {json.dumps(q.key)}\nquestion: {json.dumps(q.question)}\n"
              f"answer_options: {json.dumps(list(q.options))}" for q in questions]
    shape = json.dumps({q.key: "..." for q in questions})
    return ("# Questions\n\n" + "\n\n".join(blocks) +
            "\n\n# Output\nOne JSON object that maps each key to the chosen answer: " + shape)


def _compact_questions(questions: Sequence[Question]) -> str:
    lines = [f'- "{q.key}": {q.question} Options: {", ".join(q.options)}' for q in questions]
    shape = json.dumps({q.key: "|".join(q.options) for q in questions})
    return "Questions (key: question, options):\n" + "\n".join(lines) + f"\n\nReturn JSON of this shape: {shape}"


@dataclass(frozen=True)
class PromptStyle:
    name: str
    header: str                                         # everything before the questions
    questions: Callable[[Sequence[Question]], str]      # the questions and the answer's shape


PROMPT_STYLES = {
    "paper": PromptStyle("paper", "\n".join([
        "You are an image analysis assistant to evaluate in-cabin scenes. Your task is to answer the following "
        "questions about the visual scene and return the result in strict JSON format.",
        "",
        "# Rules",
        "- Return only the JSON.",
        "- Do not provide explanations.",
        "- For each question, choose exactly one answer from the given `answer_options`.",
        "- Do not create new answers, only choose from the provided options.",
        '- If a question references something not present, select the provided "NONE".',
    ]), _paper_questions),
    "compact": PromptStyle("compact", "\n".join([
        "You are an in-car scene understanding system looking at one image from the cabin camera.",
        "Answer every question with exactly one of its options.",
        "Answer NONE when the thing asked about is not in the image.",
        "Return only a JSON object that maps each question key to its answer, nothing else.",
    ]), _compact_questions),
}
DEFAULT_PROMPT_STYLE = "paper"


def prompt_style(name: str | None) -> PromptStyle:
    style = PROMPT_STYLES.get(name or DEFAULT_PROMPT_STYLE)
    if style is None:
        raise InputError(f"unknown prompt style {name!r}; use one of {', '.join(PROMPT_STYLES)} "
                         f"(default {DEFAULT_PROMPT_STYLE}: the paper's Figure 2)")
    return style


def vqa_prompt(space: SceneSpace, questions: Sequence[Question], header: str | None = None,
               style: str | None = None) -> str:
    """The header (a user's ``header``, else the space's ``prompt_rules``, else the style's own)
    followed by the questions in the style's layout."""
    chosen = prompt_style(style)
    block = chosen.questions(questions)
    if header is None:
        header = "\n".join(space.prompt_rules) or chosen.header
    if QUESTIONS_SLOT in header:
        return header.replace(QUESTIONS_SLOT, block)
    return f"{header.rstrip()}\n\n{block}"


def build_request(space: SceneSpace, scene: Mapping[str, Any], image: str | Path, mode: str,
                  prompt: str | None = None, style: str | None = None) -> SUTRequest:
    """The request for one scene: VQA questions about its active predicted features, or a caption prompt.

        request = build_request(space, scene, "scene.png", "vqa")     # request.prompt, request.questions
    """
    from ..protocols import SUTRequest

    if mode not in MODES:
        raise InputError(f"unknown SUT mode {mode!r}; use 'vqa' (questions) or 'vc' (captioning)")
    if mode == "vc":
        return SUTRequest(mode="vc", image=Path(image), prompt=prompt or DEFAULT_CAPTION_PROMPT, questions=())
    return questions_request(space, space.questions(scene), image, prompt, style)


def questions_request(space: SceneSpace, questions: Sequence[Question], image: str | Path, prompt: str | None = None,
                      style: str | None = None) -> SUTRequest:
    """The VQA request asking ``questions`` about ``image``: a scene's (``build_request``), or the features a
    real photograph's labels answer (``transfer``), each question carrying its truth."""
    from ..protocols import SUTRequest

    return SUTRequest(mode="vqa", image=Path(image), prompt=vqa_prompt(space, questions, prompt, style),
                      questions=tuple(questions))
