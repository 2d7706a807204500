"""A scene read from a JSON file: a plain scene, or a label file as a run writes it.

A plain scene is ``{feature: value, ...}``; a label file (a run's ``labels/<test>.json``, a pair's
``scene.json``) holds the scene under ``scene`` beside its truth, space and test id. Every command
that takes a scene file (``render``, ``sut check --scene``) and the pairs reader take either, so a
file a run wrote can be passed back as it is.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..errors import InputError, InputNotFound

LABEL_KEY = "scene"


def scene_of(data: Any) -> Any:
    """The scene in a parsed file: a label's ``scene``, else the data itself (checked by the space)."""
    if isinstance(data, dict) and LABEL_KEY in data:
        return data[LABEL_KEY]
    return data


def read_scene_file(path: str | Path) -> dict:
    """The scene in ``path``; raises InputNotFound / InputError naming the file and what it should hold."""
    path = Path(path)
    if not path.is_file():
        raise InputNotFound(f"scene file {path} does not exist")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: not valid JSON ({exc})") from None
    scene = scene_of(data)
    if not isinstance(scene, dict):
        raise InputError(f"{path}: a scene is a JSON object {{feature: value, ...}} or a label file with a "
                         f"'{LABEL_KEY}' object (as a run's labels/<test>.json), not a {type(scene).__name__}; "
                         "write one scene per file")
    return scene
