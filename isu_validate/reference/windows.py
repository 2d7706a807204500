"""Window heads: a yes/no feature read where its object is in the frame, not from the whole frame's features.

Why: a phone in a driver's hand fills about a hundredth of the frame. Averaged over the whole frame its trace is
faint, and a head fitted on renders learns the pose round it instead, which real drivers strike without a phone
(State Farm's drinking photos ranked above its phone photos in every whole-frame recipe). The renders know where
the phone is (the instance boxes of their labels), so a head can learn what a phone looks like where it is.

How: the backbone runs once over the frame scaled to ``HEIGHT`` (480 px, a render's height, where a phone is some
30-60 px; the aspect kept, so a square or wide photo gives a narrower or wider map); its last map (20 x 15 cells
of 32 px for a 4:3 frame) is averaged over every ``CELLS`` x ``CELLS`` window (96 px). Training: a window whose
centre lies within ``NEAR`` cells of the centre of the feature's part box (``visible_parts`` in the render label)
is a positive; ``NEGATIVES`` windows drawn per render (from the feature's own seeded stream), clear of the box or
from a render whose answer is the negative one, are negatives. One logistic head per feature on those window
features (``heads.fit_head``); a frame's P(YES) is its most positive window's log-odds, calibrated on the training
frames, or stacked there with a photo-trained detector's score (``stacking.py``, ``detector.py``).
Measured in the README ("Where the phone is").
"""
from __future__ import annotations

import json
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..progress import tracked
from .backbone import CELL_PX, Backbone, read_rgb
from .detector import FrameDetector
from .heads import Head, fit_head
from .stacking import Folds, Stacking, fit_stacking

HEIGHT = 480         # every frame is read this many pixels high, its aspect kept (a render's own height)
CELLS = 3            # a window is CELLS x CELLS cells of the last map
NEAR = 1.0           # a positive window's centre is within this many cells of the part box's centre, either way
NEGATIVES = 8        # negative windows drawn per training render


@dataclass(frozen=True)
class WindowSettings:
    """Which features get window heads, and the frame height and window they read (the model card records it)."""
    features: tuple[str, ...]
    height: int = HEIGHT
    cells: int = CELLS

    @classmethod
    def parse(cls, text: str | None, space) -> "WindowSettings | None":
        """``FEATURE[,FEATURE...]`` (None: no window heads), each checked against the space."""
        if text is None:
            return None
        names = tuple(dict.fromkeys(n.strip() for n in str(text).split(",") if n.strip()))
        if not names:
            raise InputError("--windows: name the yes/no features to read from windows, e.g. --windows phone_position")
        for name in names:
            _check(space, name)
        return cls(names)

    @classmethod
    def from_meta(cls, meta: dict) -> "WindowSettings":
        return cls(tuple(meta["features"]), int(meta["height"]), int(meta["cells"]))

    def describe(self) -> dict:
        return {"features": list(self.features), "height": self.height, "cells": self.cells}

    def maps(self, backbone: Backbone, rgb: np.ndarray) -> np.ndarray:
        """The window features of a frame: (rows, columns, 1280)."""
        return backbone.windows(rgb, self.cells, self.height)


def _check(space, name: str) -> None:
    feature = space.features.get(name)
    if feature is None or not feature.predicted:
        raise InputError(f"--windows {name}: space {space.name!r} has no predicted feature {name!r}; predicted: "
                         + ", ".join(f.name for f in space.predicted))
    if sorted(feature.options) != ["NO", "YES"]:
        raise InputError(f"--windows {name}: a window head answers a yes/no question, and {name!r} asks "
                         f"{'/'.join(feature.options)}")
    if not feature.visible_parts:
        raise InputError(f"--windows {name}: the space names no render part that shows {name!r} (visible_parts), "
                         "so no render says where it is")


def part_box(label: dict, parts, scale: float) -> tuple[float, float, float, float] | None:
    """The box round every pixel of ``parts`` in a render label (frame pixels times ``scale``), or None."""
    boxes = [label["visible"][p]["bbox"] for p in parts if (label.get("visible") or {}).get(p, {}).get("bbox")]
    if not boxes:
        return None
    b = np.array(boxes, float)
    return tuple(float(v) * scale for v in (b[:, 0].min(), b[:, 1].min(), b[:, 2].max() + 1, b[:, 3].max() + 1))


def training_windows(maps: np.ndarray, answer: str, box, cells: int, rng: np.random.Generator
                     ) -> tuple[list[np.ndarray], list[str]]:
    """A render's training windows: YES windows centred on the part's box, NO windows clear of it (a YES render
    without a box shows no place to learn from, so gives none)."""
    rows, cols = maps.shape[:2]
    if answer == "YES" and box is None:
        return [], []
    X, y = [], []
    if answer == "YES":
        cx, cy = (box[0] + box[2]) / 2 / CELL_PX, (box[1] + box[3]) / 2 / CELL_PX
        for j in range(rows):
            for i in range(cols):
                if abs(i + cells / 2 - cx) <= NEAR and abs(j + cells / 2 - cy) <= NEAR:
                    X.append(maps[j, i])
                    y.append("YES")
    for j, i in zip(rng.integers(rows, size=NEGATIVES), rng.integers(cols, size=NEGATIVES), strict=True):
        if answer == "YES" and _overlaps((i * CELL_PX, j * CELL_PX, (i + cells) * CELL_PX, (j + cells) * CELL_PX), box):
            continue
        X.append(maps[j, i])
        y.append("NO")
    return X, y


def _overlaps(a, b) -> bool:
    return not (a[2] <= b[0] or a[0] >= b[2] or a[3] <= b[1] or a[1] >= b[3])


def calibration_folds(labels: list[dict | None], seed: int) -> Folds:
    """The calibration's folds for training renders with these labels: by the camera rig each was seen through (its
    label's camera name; jittered frames keep their rig's) when there are several (``Folds.plan``)."""
    return Folds.plan([((label or {}).get("camera") or {}).get("name") for label in labels], seed)


def fit_window_heads(space, settings: WindowSettings, backbone: Backbone, images: list[Path], scenes: list[dict],
                     labels: list[dict | None], seed: int, detector: FrameDetector | None = None,
                     fold_plan: Folds | None = None) -> tuple[list[Head], dict[str, Stacking], dict, list[dict]]:
    """One window head per feature of ``settings`` from the training renders (``scenes``: their labels less what
    the frame hid; ``labels``: their render labels, the boxes), and how a frame's best window makes its probability:
    calibrated alone, or stacked with ``detector`` (``stacking.py``), on log-odds out of the folds of ``fold_plan``
    (by default ``calibration_folds`` of the labels); (heads, calibrations, how many windows each learnt from, the
    class probabilities per training frame: {} where not asked).

    The calibration: a frame's best window is the most positive of some 200, so its raw probability says YES to
    frames without the thing far more often than one window would. A logistic fit of the training frames' answers
    on their best window's log-odds out of fold (with the detector's beside them) turns it into the frame's
    probability."""
    # one stream per feature, so that a feature's windows do not change with the other features asked for
    rngs = {name: np.random.default_rng([seed, zlib.crc32(name.encode())]) for name in settings.features}
    examples: dict[str, list[tuple[int, np.ndarray, str]]] = {name: [] for name in settings.features}
    frames = list(zip(images, scenes, labels, strict=True))
    for frame, (image, scene, label) in enumerate(tracked(frames, "window heads: reading training frames")):
        asked = [n for n in settings.features if n in scene]
        if not asked:
            continue
        rgb = read_rgb(image)
        maps = settings.maps(backbone, rgb)
        scale = settings.height / rgb.shape[0]   # the aspect is kept: one scale for both axes
        for name in asked:
            feature = space.features[name]
            box = part_box(label or {}, feature.visible_parts, scale)
            X, y = training_windows(maps, feature.truth(scene[name]), box, settings.cells, rngs[name])
            examples[name].extend((frame, x, answer) for x, answer in zip(X, y, strict=True))
    counts = {name: {answer: sum(e[2] == answer for e in rows) for answer in ("YES", "NO")}
              for name, rows in examples.items()}
    heads = [_fit_windows_of(name, rows, seed) for name, rows in examples.items()]
    plan = fold_plan if fold_plan is not None else calibration_folds(labels, seed)
    fold_of = plan.of
    stacked = {name for name in examples if detector and name in detector.classes}   # the others: calibrated alone
    fold_heads = {name: [_fit_windows_of(name, [e for e in rows if fold_of[e[0]] != k], seed) for k in range(len(plan))]
                  for name, rows in examples.items()}
    # a second pass over the frames: the calibration needs the fitted heads, and keeping every frame's map from the
    # first pass would hold about 1 MB a frame (600 MB for 600 renders) to save a minute
    read_frames = [_read_training_frame(settings, backbone, heads, fold_heads, fold_of[i], image, scene, detector)
                   for i, (image, scene) in enumerate(tracked(list(zip(images, scenes, strict=True)),
                                                               "window heads: scoring training frames"))]
    stackings, read = {}, [{} for _ in images]
    for head in heads:
        name, feature = head.feature, space.features[head.feature]
        rows = [i for i, frame in enumerate(read_frames) if name in frame]
        truth = np.array([feature.truth(scenes[i][name]) == "YES" for i in rows])
        # calibrated on log-odds out of fold, alone or stacked: in sample the head is far surer than on frames it
        # never saw, and a calibration fitted there sets its threshold where unseen frames seldom reach (stacking.py)
        window = np.array([read_frames[i][name].out_of_fold for i in rows])
        seen = np.array([read_frames[i][name].detector for i in rows]) if name in stacked else None
        stackings[name] = fit_stacking(name, window, seen, truth)
        for i in rows:
            frame = read_frames[i][name]
            read[i][name] = _classes(head, stackings[name].probability(frame.window, frame.detector))
    return heads, stackings, counts, read


def _fit_windows_of(name: str, rows: list[tuple[int, np.ndarray, str]], seed: int) -> Head:
    answers = [e[2] for e in rows]
    yes, no = answers.count("YES"), answers.count("NO")
    if not yes or not no:
        raise InputError(f"--windows {name}: the training renders (or those left when a fold, a fifth of them or "
                         f"one viewpoint's, is left out to calibrate it) give {yes} windows that show it and {no} "
                         f"that do not; both are needed: use a larger --n")
    return fit_head(name, np.stack([e[1] for e in rows]), answers, seed=seed)


class TrainingRead(NamedTuple):
    """One training frame's log-odds of one feature."""
    window: float                 # the best window's, by the head fitted on every frame
    out_of_fold: float            # the best window's, by the head fitted without the frame's fold
    detector: float               # the detector's (0 without one)


def _read_training_frame(settings: WindowSettings, backbone: Backbone, heads: list[Head],
                         fold_heads: dict[str, list[Head]], fold: int, image: Path, scene: dict,
                         detector: FrameDetector | None) -> dict[str, TrainingRead]:
    """{feature: its log-odds} for one training frame."""
    asked = [h for h in heads if h.feature in scene]
    if not asked:
        return {}
    rgb = read_rgb(image)
    flat = _flat(settings.maps(backbone, rgb))
    seen = detector.log_odds(rgb, [h.feature for h in asked]) if detector else {}
    return {h.feature: TrainingRead(_best_log_odds(h, flat), _best_log_odds(fold_heads[h.feature][fold], flat),
                                    seen.get(h.feature, 0.0)) for h in asked}


def _flat(maps: np.ndarray) -> np.ndarray:
    return maps.reshape(-1, maps.shape[-1])


def _classes(head: Head, p_yes: float) -> dict[str, float]:
    return {c: (p_yes if c == "YES" else 1.0 - p_yes) for c in head.classes}


def _best_log_odds(head: Head, flat: np.ndarray) -> float:
    """The log-odds of YES of the most positive window, from the head's logits in float64 (a probability of a sure
    window rounds to 1 and has no finite log-odds). A yes/no head stores one row: the log-odds of its second class."""
    z = (head.standardise(flat.astype(np.float64)) @ head.weight.T + head.bias)[:, 0]
    return float((z if head.classes.index("YES") == 1 else -z).max())


def frame_probabilities(heads: list[Head], stackings: dict[str, Stacking], maps: np.ndarray,
                        detector: dict[str, float] | None = None) -> dict[str, dict[str, float]]:
    """Each window head's class probabilities for a frame: its best window's log-odds through its calibration, or
    stacked with the detector's log-odds (``detector``: {feature: log-odds}, for a model that has one)."""
    flat = _flat(maps)
    return {h.feature: _classes(h, stackings[h.feature].probability(_best_log_odds(h, flat),
                                                                    (detector or {}).get(h.feature, 0.0)))
            for h in heads}


HELD_OUT_FILE = "held_out_windows.json"   # the window heads' answers on the model's held-out renders


def save_held_out(folder: Path, read: list[dict[str, dict[str, float]]]) -> None:
    """The window heads' class probabilities per held-out scene (in the stored held-out features' order; {} where a
    scene does not have the feature), so that ``transfer`` sets the renders beside the photos without rendering."""
    from ..atomic import write_text

    write_text(folder / HELD_OUT_FILE, json.dumps(read))


def load_held_out(folder: Path) -> list[dict[str, dict[str, float]]]:
    path = folder / HELD_OUT_FILE
    if not path.is_file():
        raise InputError(f"the model in {folder} has window heads but not their answers on its held-out renders "
                         f"({HELD_OUT_FILE}); copy the model folder whole, or train it again")
    return json.loads(path.read_text())
