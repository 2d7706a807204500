"""A real photo set read through a label map: each photo's true answers, feature by feature.

A photo answers a feature when one of its labels maps it (its class, a box class), or, for a feature some
box class maps, when none of those boxes is in it and the map says what ``[absent]`` means. Two labels of
one photo that answer a feature differently are a conflict: an error naming the photo, or with
``skip_conflicts`` the photo is left out of that feature and counted.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from .label_map import LabelMap
from .layouts import Box, PhotoSet


@dataclass(frozen=True)
class LabelledPhoto:
    path: Path
    answers: dict[str, str]            # feature -> true answer (an option of its question)
    boxes: tuple[Box, ...] = ()
    labels: tuple[str, ...] = ()       # the set's own labels of it (class, box classes), sorted


@dataclass
class LabelledSet:
    photos: list[LabelledPhoto]
    source: dict                                        # PhotoSet.describe()
    conflicts: Counter = field(default_factory=Counter)  # feature -> photos left out of it for conflicting labels
    unmapped: Counter = field(default_factory=Counter)   # labels of the set the map says nothing about
    unanswered: int = 0                                  # photos whose labels answer no feature

    def describe(self) -> dict:
        return {**self.source, "labelled_photos": len(self.photos), "unanswered_photos": self.unanswered,
                "conflicts": dict(self.conflicts), "unmapped_labels": dict(self.unmapped)}


def label_photos(photo_set: PhotoSet, label_map: LabelMap, skip_conflicts: bool = False) -> LabelledSet:
    out = LabelledSet([], photo_set.describe())
    mapped = set(label_map.classes) | set(label_map.boxes)
    for photo in photo_set.photos:
        out.unmapped.update(label for label in photo.labels() if label not in mapped)
        answers, conflicting = _answers(photo.classes, photo.boxes, label_map)
        if conflicting and not skip_conflicts:
            feature, given = next(iter(conflicting.items()))
            raise InputError(f"{photo.path}: its labels answer {feature} both {' and '.join(sorted(given))}; fix the "
                             "label map (or the labels), or pass --skip-conflicts to leave such photos out of that "
                             "feature and count them")
        out.conflicts.update(conflicting.keys())
        if not answers:
            out.unanswered += 1
            continue
        out.photos.append(LabelledPhoto(photo.path, answers, photo.boxes, tuple(sorted(photo.labels()))))
    if not out.photos:
        raise InputError(f"no photo of {photo_set.root} has a label that {label_map.path} maps (its labels: "
                         f"{', '.join(sorted(out.unmapped)) or 'none'})")
    return out


def _answers(classes, boxes, label_map: LabelMap) -> tuple[dict[str, str], dict[str, set[str]]]:
    """(answers, {feature: the differing answers} for the conflicting features, which get no answer)."""
    given: dict[str, set[str]] = {}
    for table in [label_map.classes.get(c, {}) for c in classes] + [label_map.boxes.get(b.label, {}) for b in boxes]:
        for feature, answer in table.items():
            given.setdefault(feature, set()).add(answer)
    boxed = {f for b in boxes for f in label_map.boxes.get(b.label, {})}
    for feature, answer in label_map.absent.items():
        if feature not in boxed:
            given.setdefault(feature, set()).add(answer)
    conflicting = {f: a for f, a in given.items() if len(a) > 1}
    return {f: next(iter(a)) for f, a in given.items() if len(a) == 1}, conflicting
