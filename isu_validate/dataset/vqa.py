"""A dataset image as a VLM fine-tuning conversation: the prompt the SUT gets, then the right answer.

One row of ``vqa.jsonl``, in the chat-messages form of VLM fine-tuning (Hugging Face TRL's vision
datasets: ``messages`` with typed content, the image placeholder ``{"type": "image"}``, the image files in
``images``)::

    {"file_name": "images/000000.png", "images": ["images/000000.png"], "occluded": [...],
     "messages": [{"role": "user", "content": [{"type": "text", "text": PROMPT}, {"type": "image"}]},
                  {"role": "assistant", "content": [{"type": "text", "text": ANSWER_JSON}]}]}

The prompt is ``sut.build_request``'s for the scene (text before image, as the OpenAI-compatible adapter
sends it); the answer holds the true answer of every question asked, in the prompt's key order, so the
VQA judge scores it 1.0 (features in ``occluded`` are not judged; their true answer is still given).
"""
from __future__ import annotations

import json
from typing import Sequence

from ..space import SceneSpace
from ..sut import build_request


def vqa_row(space: SceneSpace, scene: dict, file_name: str, occluded: Sequence[str], prompt_style: str) -> dict:
    request = build_request(space, scene, file_name, "vqa", style=prompt_style)
    answer = json.dumps({q.key: q.truth for q in request.questions})
    return {"file_name": file_name, "images": [file_name], "occluded": list(occluded),
            "messages": [{"role": "user", "content": [{"type": "text", "text": request.prompt}, {"type": "image"}]},
                         {"role": "assistant", "content": [{"type": "text", "text": answer}]}]}
