"""A label map: what each real label means as answers to the scene space's questions (TOML).

```toml
[classes.c1]                 # an image-level class (a class folder, a CSV label)
phone_position = "YES"       # the question's option, or a value of the feature (P3 -> YES)
[boxes.Cellphone_texting]    # a box class (YOLO, COCO): present in the photo -> these answers
phone_position = "YES"
[absent]                     # what the absence of every box class mapping a feature means (optional)
phone_position = "NO"
```

Only features asked of a SUT (``predicted``) can be mapped; an unknown feature or answer is an error that
names the choices. The map is checked against a space when loaded, so a typo never measures nothing.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..space import SceneSpace
from ..tomlfile import read_toml

SECTIONS = ("classes", "boxes", "absent")


class LabelMapError(InputError):
    pass


@dataclass(frozen=True)
class LabelMap:
    path: Path
    classes: dict[str, dict[str, str]]     # image-level class -> {feature: answer}
    boxes: dict[str, dict[str, str]]       # box class -> {feature: answer}
    absent: dict[str, str]                 # feature -> answer when no box class mapping it is in the photo
    digest: str                            # of the map's meaning (what decides a measurement)


def load_label_map(path: str | Path, space: SceneSpace) -> LabelMap:
    path = Path(path)
    raw = read_toml(path, LabelMapError, "label map")
    unknown = set(raw) - set(SECTIONS)
    if unknown:
        raise LabelMapError(f"{path}: unknown table(s) {sorted(unknown)}; a label map has [classes.NAME], "
                            "[boxes.NAME] and [absent]")
    classes = {str(k): _answers(path, f"classes.{k}", v, space) for k, v in raw.get("classes", {}).items()}
    boxes = {str(k): _answers(path, f"boxes.{k}", v, space) for k, v in raw.get("boxes", {}).items()}
    absent = _answers(path, "absent", raw.get("absent", {}), space)
    stray = set(absent) - {f for a in boxes.values() for f in a}
    if stray:
        raise LabelMapError(f"{path}: [absent] answers {sorted(stray)}, which no [boxes.NAME] maps: absence of a box "
                            "can only speak for features some box class answers")
    if not classes and not boxes:
        raise LabelMapError(f"{path} maps no label: add [classes.NAME] or [boxes.NAME] tables")
    meaning = json.dumps({"classes": classes, "boxes": boxes, "absent": absent}, sort_keys=True)
    return LabelMap(path, classes, boxes, absent, hashlib.sha1(meaning.encode()).hexdigest()[:16])


def _answers(path: Path, where: str, table, space: SceneSpace) -> dict[str, str]:
    if not isinstance(table, dict):
        raise LabelMapError(f"{path}: [{where}] must be a table of feature = answer")
    asked = [f.name for f in space.predicted]
    out = {}
    for name, value in table.items():
        feature = space.features.get(name)
        if feature is None or not feature.predicted:
            what = "is not a feature of" if feature is None else "is not asked of a SUT in"
            raise LabelMapError(f"{path}: [{where}] {name!r} {what} space {space.name!r}; map one of: "
                                f"{', '.join(asked)}")
        out[name] = _answer(path, where, feature, value)
    return out


def _answer(path: Path, where: str, feature, value) -> str:
    text = str(value)
    if text in feature.options:
        return text
    if text in {str(v) for v in feature.values}:
        return feature.truth(text)
    raise LabelMapError(f"{path}: [{where}] {feature.name} = {text!r} is neither an answer option "
                        f"({', '.join(feature.options)}) nor a value ({', '.join(map(str, feature.values))}) "
                        f"of {feature.name}")
