"""The renders beside the real photographs: what the same SUT does on rendered scenes, and their images.

Two sources, the first that applies:
- ``--renders DATASET`` (a folder ``isu-validate dataset`` wrote): its renders are asked the same questions
  through the same SUT, the truth from each slot's scene; its images are also the render side of KID/FID.
- a reference ISU model folder (``--model``, or ``--sut reference``): its own held-out renders, from the
  backbone features stored beside its heads (``held_out_features.npz``; a window head's answers from
  ``held_out_windows.json``): the figures its card reports, with no image rendered again. No images, so no
  KID without ``--renders``.
A folder of plain images as ``--renders`` gives KID/FID only (no truth to score against).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..dataset.folder import DatasetDir
from ..errors import InputError, InputNotFound
from ..render.visibility import without_hidden
from ..space import SceneSpace
from .ask import Item


def dataset_items(dataset: DatasetDir, space: SceneSpace, features: list[str]) -> list[Item]:
    """The dataset's renders (style copies left out) with their true answers for ``features``."""
    folder = dataset.path
    items = []
    for slot, entry in sorted(dataset.entries().items()):
        if entry.get("status") != "ok":
            continue
        seen = without_hidden(entry["scene"], entry)     # what the frame hid is not asked, as the judge does
        truth = {q.key: q.truth for q in space.questions(entry["scene"]) if q.key in features and q.key in seen}
        for f in entry["files"]:
            if f.get("variant") == "render" and truth:
                items.append(Item(f"{slot:06d}", folder / f["file_name"], truth))
    if not items:
        raise InputError(f"dataset {folder} holds no finished render that answers {', '.join(features)}")
    return items


def labelled_frames(folder: Path, space: SceneSpace, features: list[str]) -> list[Item]:
    """The frames of a folder of renders that carry their render label (``render --random``, a reference's
    training sets), with the true answers for ``features`` less what the frame hid (the label's ``occluded``)."""
    from ..render.outputs import read_label

    items = []
    for image in render_images(folder):
        data = read_label(image)
        if data is None:
            continue
        seen = without_hidden(data["scene"], data)
        truth = {q.key: q.truth for q in space.questions(data["scene"]) if q.key in features and q.key in seen}
        if truth:
            items.append(Item(image.stem, image, truth))
    return items


def render_images(folder: Path) -> list[Path]:
    """The render images of ``--renders``: a dataset's renders, or the images of a plain folder."""
    if not folder.is_dir():
        raise InputNotFound(f"render set {folder} is not a folder: give a dataset (`isu-validate dataset --out`) "
                            "or a folder of rendered images")
    dataset = DatasetDir(folder)
    if dataset.is_dataset():
        return [folder / f["file_name"] for _, e in sorted(dataset.entries().items())
                if e.get("status") == "ok" for f in e["files"] if f.get("variant") == "render"]
    from ..realism.images import list_images   # frames only: a contact sheet or a mask would bias KID/FID
    return list_images(folder)


def held_out_records(model_dir: Path, space: SceneSpace, features: list[str]) -> tuple[list[dict], dict]:
    """Records (as ``ask.ask_all`` makes them) of the reference model in ``model_dir`` on its own held-out
    renders, from their stored features; and what those renders were (renderer, preset, n)."""
    from ..reference.feature_bank import FILES, load_feature_set
    from ..reference.heads import load_heads, load_window_heads
    from ..reference.windows import load_held_out

    path = model_dir / FILES["held_out"]
    if not path.is_file():
        raise InputNotFound(f"the model in {model_dir} keeps no held-out features ({FILES['held_out']}); give a "
                            "render set with --renders, or retrain it with `isu-validate reference train`")
    held_out = load_feature_set(path)
    heads, meta = load_heads(model_dir)
    heads = {h.feature: h for h in heads}
    windows = {h.feature for h in load_window_heads(model_dir, meta)}
    window_read = load_held_out(model_dir) if windows else []
    if held_out.meta.get("space_hash") != space.hash:
        trained_in = held_out.meta.get("space")
        fix = (f"the space file changed since (hash {held_out.meta.get('space_hash')} then, {space.hash} now): retrain "
               "the model" if trained_in == space.name else f"pass --space {trained_in}")
        raise InputError(f"the held-out features in {model_dir} belong to space {trained_in!r}, not {space.name!r} "
                         f"as it is: {fix}")
    records = []
    for feature in [f for f in features if f in heads]:
        head = heads[feature]
        rows = [i for i, scene in enumerate(held_out.scenes) if feature in scene]
        if not rows:
            continue
        if feature in windows:   # answered from windows: their stored answers, not the whole-frame head's
            p = np.array([[window_read[i][feature][c] for c in head.classes] for i in rows])
        else:
            p = head.probabilities(held_out.features[rows].astype(np.float64))
        for i, probs in zip(rows, p, strict=True):
            records.append({"name": f"{i:05d}", "truth": {feature: space.features[feature].truth(
                held_out.scenes[i][feature])}, "said": {feature: head.classes[int(np.argmax(probs))]},
                "p": {feature: dict(zip(head.classes, map(float, probs), strict=True))}, "error": None})
    about = {"source": f"held-out renders of {model_dir}", "renderer": held_out.meta.get("renderer"),
             "preset": held_out.meta.get("preset"), "scenes": len(held_out.scenes)}
    return records, about
