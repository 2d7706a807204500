"""``transfer --zero-shot``: does the rendered object look like the real one to a model trained on photographs?

No SUT and no training: EfficientNet-Lite0's ImageNet head (``recognition.objects``) scores each frame for the
object a feature's YES shows (``ZERO_SHOT``: "phone in hand" shows a phone) anywhere in the frame, and the AUC
of that score against the labels says how well it separates frames with the thing from frames without. Read
side by side: a score that separates the real photos but not the renders says the rendered object does not yet
look like the real one, whatever a SUT trained on the renders learnt; both near 0.5 says the classifier cannot
see the object at that size at all. Renders are scored where their truth is known (a dataset, or a folder of
frames with their ``.label.json``); what a frame hid from its camera is left out, as the judge leaves it out.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..space import SceneSpace
from .ask import Item
from .scores import positive_class

# a feature -> the object (recognition.objects.PLAUSIBLE) its positive answer puts in the picture
ZERO_SHOT = {"phone_position": "phone"}


def zero_shot_features(features: list[str]) -> dict[str, str]:
    return {f: ZERO_SHOT[f] for f in features if f in ZERO_SHOT}


def zero_shot_scores(groups: dict[str, list[Item]], space: SceneSpace, features: list[str], device: str,
                     progress=None) -> dict:
    """{group (a real set, or "renders"): {feature: {object, auc, n_positive, n_negative, unreadable,
    median_positive, median_negative}}} for the features ``ZERO_SHOT`` knows; a group without both answers gets
    auc None; a frame that cannot be read is counted in ``unreadable`` and left out."""
    from ..devices import resolve_torch_device
    from ..recognition.objects import ObjectRecogniser
    from ..recognition.tally import auc
    from ..reference.backbone import read_rgb

    wanted = zero_shot_features(features)
    if not wanted:
        return {}
    recogniser = ObjectRecogniser(device=resolve_torch_device(device).name)
    out = {}
    for name, items in groups.items():
        out[name] = {}
        for feature, obj in wanted.items():
            positive = positive_class(space.features[feature].options)
            scored, unreadable = [], 0
            for item in (item for item in items if feature in item.truth):
                try:
                    scored.append((recogniser.anywhere(read_rgb(item.image), obj), item.truth[feature] == positive))
                except InputError:   # an unreadable photo is left out and counted, as transfer's SUT side does
                    unreadable += 1
            if progress:
                progress(name, len(scored))
            pos = [s for s, with_it in scored if with_it]
            neg = [s for s, with_it in scored if not with_it]
            out[name][feature] = {"object": obj, "auc": auc(pos, neg), "n_positive": len(pos),
                                  "n_negative": len(neg), "unreadable": unreadable, "median_positive": _median(pos),
                                  "median_negative": _median(neg)}
    return out


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def format_zero_shot(zero_shot: dict) -> list[str]:
    """One line per group and feature, for the command's table."""
    lines = []
    for name, features in zero_shot.items():
        for feature, r in features.items():
            value = "-" if r["auc"] is None else f"{r['auc']:.2f}"
            lines.append(f"zero-shot {r['object']} anywhere (ImageNet classes, no training), {name}, {feature}: "
                         f"AUC {value} (n {r['n_positive']} with, {r['n_negative']} without"
                         + (f", {r['unreadable']} unreadable)" if r.get("unreadable") else ")"))
    return lines
