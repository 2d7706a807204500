"""``transfer --zero-shot``: does the rendered object look like the real one to a model trained on photographs?

No SUT and no training: EfficientNet-Lite0's ImageNet head (``recognition.objects``) scores each frame for the
object a feature's YES shows (``ZERO_SHOT``: "phone in hand" shows a phone) anywhere in the frame, and the AUC
of that score against the labels says how well it separates frames with the thing from frames without. Read
side by side: a score that separates the real photos but not the renders says the rendered object does not yet
look like the real one, whatever a SUT trained on the renders learnt; both near 0.5 says the classifier cannot
see the object at that size at all. Renders are scored where their truth is known (a dataset, or a folder of
frames with their ``.label.json``); what a frame hid from its camera is left out, as the judge leaves it out.

A second photo-trained opinion where there is one: the built-in COCO detector (``DETECTOR``, ``reference.detector``,
read over the frame and its 2x2 tiles as a window model reads it) scores the same frames for the feature's COCO class
("cell phone"). Its AUC on the photos is what a detector alone, with nothing learnt from renders, does there: the
floor a reference model stacked with it (``reference train --detector``) has to rise above for its renders to have
taught anything.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..space import SceneSpace
from .ask import Item
from .scores import positive_class

# a feature -> the object (recognition.objects.PLAUSIBLE) its positive answer puts in the picture
ZERO_SHOT = {"phone_position": "phone"}
DETECTOR = "yolov4-tiny"   # the built-in detector; it reads the features reference.detector.DEFAULT_CLASSES names


def zero_shot_features(features: list[str]) -> dict[str, str]:
    return {f: ZERO_SHOT[f] for f in features if f in ZERO_SHOT}


def zero_shot_scores(groups: dict[str, list[Item]], space: SceneSpace, features: list[str], device: str,
                     progress=None) -> dict:
    """{group (a real set, or "renders"): {feature: {object, auc, n_positive, n_negative, unreadable,
    median_positive, median_negative, detector}}} for the features ``ZERO_SHOT`` knows; a group without both answers
    gets auc None; a frame that cannot be read is counted in ``unreadable`` and left out. ``detector``: the built-in
    detector's {name, class, auc, median_positive, median_negative} on the same frames, {name, unavailable: why}
    when it is not installed, or None for a feature it has no class for."""
    from ..devices import resolve_torch_device
    from ..recognition.objects import ObjectRecogniser
    from ..reference.backbone import read_rgb

    wanted = zero_shot_features(features)
    if not wanted:
        return {}
    recogniser = ObjectRecogniser(device=resolve_torch_device(device).name)
    detector, unavailable = _open_detector(list(wanted))
    out = {}
    for name, items in groups.items():
        out[name] = {}
        for feature, obj in wanted.items():
            positive = positive_class(space.features[feature].options)
            scored, unreadable = [], 0   # (ImageNet score, detector log-odds or None, with the thing)
            for item in (item for item in items if feature in item.truth):
                try:
                    rgb = read_rgb(item.image)
                except InputError:   # an unreadable photo is left out and counted, as transfer's SUT side does
                    unreadable += 1
                    continue
                seen = detector.log_odds(rgb, [feature]).get(feature) if detector else None
                scored.append((recogniser.anywhere(rgb, obj), seen, item.truth[feature] == positive))
            if progress:
                progress(name, len(scored))
            out[name][feature] = {"object": obj, **_separation([(s[0], s[2]) for s in scored]),
                                  "unreadable": unreadable,
                                  "detector": _detector_entry(detector, unavailable, feature, scored)}
    return out


def _open_detector(features: list[str]):
    """(the built-in detector for the features it has a class for, or None; why it is unavailable, or None)."""
    from ..reference.detector import DEFAULT_CLASSES, FrameDetector

    classes = {f: DEFAULT_CLASSES[f] for f in features if f in DEFAULT_CLASSES}
    if not classes:
        return None, None
    try:
        return FrameDetector.open(DETECTOR, classes), None
    except InputError as exc:   # not installed: the ImageNet score stands alone, and the summary says why
        return None, str(exc).strip().splitlines()[0]


def _detector_entry(detector, unavailable: str | None, feature: str, scored: list[tuple]) -> dict | None:
    if detector is None:
        return {"name": DETECTOR, "unavailable": unavailable} if unavailable else None
    if feature not in detector.classes:
        return None
    # the best score as a probability for the medians; its AUC is the log-odds' (the same order)
    separation = _separation([(1.0 / (1.0 + np.exp(-s[1])), s[2]) for s in scored])
    return {"name": DETECTOR, "class": detector.classes[feature], "auc": separation["auc"],
            "median_positive": separation["median_positive"], "median_negative": separation["median_negative"]}


def _separation(scored: list[tuple[float, bool]]) -> dict:
    """AUC, counts and medians of scores against whether the frame has the thing."""
    from ..recognition.tally import auc

    pos = [s for s, with_it in scored if with_it]
    neg = [s for s, with_it in scored if not with_it]
    return {"auc": auc(pos, neg), "n_positive": len(pos), "n_negative": len(neg), "median_positive": _median(pos),
            "median_negative": _median(neg)}


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def format_zero_shot(zero_shot: dict) -> list[str]:
    """One line per group and feature, for the command's table."""
    lines = []
    for name, features in zero_shot.items():
        for feature, r in features.items():
            lines.append(f"zero-shot {r['object']} anywhere (ImageNet classes, no training), {name}, {feature}: "
                         f"AUC {_auc(r['auc'])} (n {r['n_positive']} with, {r['n_negative']} without"
                         + (f", {r['unreadable']} unreadable)" if r.get("unreadable") else ")"))
            seen = r.get("detector")   # absent in a summary written before the detector was read
            if seen and "unavailable" in seen:
                lines.append(f"zero-shot detector {seen['name']}, {name}, {feature}: not read ({seen['unavailable']})")
            elif seen:
                lines.append(f"zero-shot detector {seen['name']} '{seen['class']}' (COCO photos, no training from "
                             f"renders), {name}, {feature}: AUC {_auc(seen['auc'])}")
    return lines


def _auc(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"
