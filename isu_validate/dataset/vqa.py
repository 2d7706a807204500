"""A dataset image as a VLM fine-tuning conversation: the prompt the SUT gets, then the right answer.

One row of ``vqa.jsonl``, in the chat-messages form of VLM fine-tuning (Hugging Face TRL's vision
datasets: ``messages`` with typed content, the image placeholder ``{"type": "image"}``, the image files in
``images``)::

    {"file_name": "images/000000.png", "images": ["images/000000.png"], "occluded": [...],
     "messages": [{"role": "user", "content": [{"type": "text", "text": PROMPT}, {"type": "image"}]},
                  {"role": "assistant", "content": [{"type": "text", "text": ANSWER_JSON}]}]}

The prompt is ``sut.vqa_prompt``'s, worded as ``build_request`` words it for the SUT (text before image, as
the OpenAI-compatible adapter sends it), over the scene's questions less those about features the frame hides
(``occluded``): the prompt offers no "not visible" answer, so a row never teaches a model to answer what it
cannot see. The answer holds the true answer of every question asked, in the prompt's key order, so the VQA
judge scores it 1.0. ``metadata.jsonl`` keeps every truth, occluded ones marked.
"""
from __future__ import annotations

import json
from typing import Sequence

from ..space import SceneSpace
from ..sut import vqa_prompt

# what the card says about occluded features (one home: the row and the card agree)
OCCLUDED_RULE = ("features the frame hides (`occluded`) are left out of that row's questions and answer in "
                 "`vqa.jsonl`: the prompt offers no \"not visible\" answer, so a model fine-tuned on it is never "
                 "taught to answer what it cannot see; `metadata.jsonl` keeps their truth, marked `occluded`")


def vqa_row(space: SceneSpace, scene: dict, file_name: str, occluded: Sequence[str], prompt_style: str) -> dict:
    hidden = set(occluded)
    questions = [q for q in space.questions(scene) if q.key not in hidden]
    answer = json.dumps({q.key: q.truth for q in questions})
    prompt = vqa_prompt(space, questions, style=prompt_style)
    return {"file_name": file_name, "images": [file_name], "occluded": list(occluded),
            "messages": [{"role": "user", "content": [{"type": "text", "text": prompt}, {"type": "image"}]},
                         {"role": "assistant", "content": [{"type": "text", "text": answer}]}]}
