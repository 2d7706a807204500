"""Frames for the yardsticks from what a user has: a run, a dataset, a sim/real pairs folder, or a folder
of frames with their render labels (``<frame>.label.json`` beside each, as ``render`` writes them).

Boxes come from the renders' own masks (a run's and a folder's render labels, a dataset's COCO boxes). A
pair's real frames have none: they take the sim frame's boxes and occlusion (pairs are recreated and
aligned to the sim frame), and their face is any face the detector finds (alignment is never exact)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from capture.sidecar import is_stand_in

from ..archive.run_dir import RunDir
from ..dataset.folder import DatasetDir
from ..errors import InputError, InputNotFound
from ..image_files import IMAGE_SUFFIXES
from ..pairs import PairsDir
from ..recognition.frames import UNITS, Frame
from ..render.labels import INSTANCES
from ..render.outputs import by_product

LABEL_SUFFIX = ".label.json"


def frames_of(source: Path) -> tuple[str, list[Frame]]:
    """(what the source is, its frames); a user error naming the four kinds for anything else."""
    if not source.exists():
        raise InputNotFound(f"{source} does not exist: give a run, a dataset, a pairs folder or a folder of frames")
    if RunDir(source).is_run():
        return "run", _run_frames(RunDir(source))
    dataset = DatasetDir(source)
    if dataset.is_dataset():
        return "dataset", _dataset_frames(dataset)
    if source.is_dir() and PairsDir.looks_like(source):
        return "pairs", _pairs_frames(PairsDir(source))
    if source.is_dir():
        return "frames", _folder_frames(source)
    raise InputError(f"{source} is a file: give a run folder (`run --out`), a dataset (`dataset --out`), a pairs "
                     "folder (`recreate --out`) or a folder of frames with their .label.json (`render --random --out`)")


def _label_frame(image: Path, label: dict, name: str, kind: str = "render") -> Frame:
    """A frame described by a render label: its scene, preset, visible boxes (inclusive ends in the label) and
    where the placed things' tops point (labels before ``up`` was written have none)."""
    boxes = {n: (b[0], b[1], b[2] + 1, b[3] + 1) for n, v in (label.get("visible") or {}).items()
             if (b := v.get("bbox"))}
    return Frame(image, name, kind, label.get("preset"), dict(label.get("scene") or {}), boxes,
                 frozenset(label.get("occluded") or ()), up=_ups(label.get("up"), image))


def _ups(raw, image: Path) -> dict:
    """{instance: (dx, dy)} of a label's ``up``, each a unit vector; a malformed one names the frame."""
    try:
        ups = {str(k): (float(v[0]), float(v[1])) for k, v in (raw or {}).items()}
    except (AttributeError, TypeError, ValueError, IndexError, KeyError):
        ups = None
    if ups is None or any(not 0.99 < math.hypot(*u) < 1.01 for u in ups.values()):
        raise InputError(f"the label of {image} has a malformed 'up' ({raw!r}): it maps things to unit vectors "
                         "[dx, dy]; render the frame again (`isu-validate render` writes it) or remove 'up'")
    return ups


def _run_frames(run: RunDir) -> list[Frame]:
    frames = []
    for record in run.records():
        image, label = run.image_path(record), run.render_label(record.test_id)
        if image is not None and label is not None and not record.render_error:
            frames.append(_label_frame(image, label, record.test_id))
    if not frames:
        raise InputError(f"run {run.path} has no rendered test with its render label (images/<test>.label.json)")
    return frames


def _dataset_frames(folder: DatasetDir) -> list[Frame]:
    preset = (folder.info().get("preset") or {}).get("name")
    names = {i: n for i, (n, _) in INSTANCES.items()}
    frames = []
    for slot, entry in sorted(folder.entries().items()):
        if entry.get("status") != "ok":
            continue
        boxes = {names[a["category_id"]]: _xyxy(a["bbox"]) for a in entry.get("annotations", ())
                 if a["category_id"] in names}
        for f in entry["files"]:
            if f.get("variant") == "render":   # style copies are not renders of the renderer under test
                frames.append(Frame(folder.path / f["file_name"], f"{slot:06d}", "render", preset, entry["scene"],
                                    boxes, frozenset(entry.get("occluded") or ()),
                                    up=_ups(entry.get("up"), folder.path / f["file_name"])))
    if not frames:
        raise InputError(f"dataset {folder.path} holds no finished render yet; build it with `isu-validate dataset`")
    return frames


def _xyxy(bbox) -> tuple[int, int, int, int]:
    x, y, w, h = (int(round(v)) for v in bbox)
    return x, y, x + w, y + h


def _pairs_frames(pairs: PairsDir) -> list[Frame]:
    frames = []
    for sample in pairs.samples():
        label = sample.render_label() or {"scene": sample.scene(), "preset": None}
        sim = _label_frame(sample.sim, label, f"{sample.name}/sim") if sample.sim.is_file() else None
        if sim is not None:
            frames.append(sim)
        base = sim or _label_frame(sample.sim, label, sample.name)
        size = (label.get("camera") or {}).get("image") or {}   # the rendered size the sim boxes are in
        for real in sample.real_frames():
            frames.append(Frame(real, f"{sample.name}/{real.stem}", "stand-in" if is_stand_in(real) else "real",
                                base.preset, base.scene, base.boxes, base.occluded, own_boxes=False,
                                boxes_size=(size["width"], size["height"]) if "width" in size else None,
                                up=base.up))
    if not frames:
        raise InputError(f"pairs folder {pairs.root} has no sim.png and no real frames")
    return frames


def _folder_frames(folder: Path) -> list[Frame]:
    images = sorted(p for p in folder.iterdir()   # a render's channels and contact sheet are not frames
                    if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file() and by_product(p) is None)
    if not images:
        raise InputError(f"{folder} holds no frames (png, jpg...): give a run, a dataset, a pairs folder or a "
                         "folder of frames with their labels")
    unlabelled = [p.name for p in images if not (p.parent / (p.stem + LABEL_SUFFIX)).is_file()]
    if unlabelled:
        raise InputError(f"{len(unlabelled)} frame(s) in {folder} have no render label beside them (e.g. "
                         f"{unlabelled[0]} needs {Path(unlabelled[0]).stem}{LABEL_SUFFIX}): the yardsticks need "
                         "the scene and where its features are; `isu-validate render` writes both")
    return [_label_frame(p, _read_label(p.parent / (p.stem + LABEL_SUFFIX)), p.stem) for p in images]


def _read_label(path: Path) -> dict:
    try:
        label = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read render label {path}: {exc}") from None
    if not isinstance(label, dict) or "scene" not in label:
        raise InputError(f"{path} is not a render label (no 'scene'); `isu-validate render` writes them")
    return label


def real_set_frames(root: Path, labels: Path | None, space, layout: str | None = None) -> list[Frame]:
    """A labelled real photo set (``realphotos``: class folders, YOLO, COCO, CSV) as frames of kind ``real``.
    Without a label map every photo is read for a face only (anywhere in it: no head box). With one, each
    photo's scene holds a value for every answer its labels give (phone in hand YES -> P1, so the phone is
    looked for), and a box class that says a thing is there is that thing's box (a phone, a bottle)."""
    from ..realphotos import label_photos, load_label_map, read_photo_set

    photo_set = read_photo_set(root, layout)
    if labels is None:
        return [Frame(p.path, f"{root.name}/{p.path.name}", "real", None, {}, face_anywhere=True)
                for p in photo_set.photos]
    label_map = load_label_map(labels, space)
    frames = []
    for photo in label_photos(photo_set, label_map, skip_conflicts=True).photos:
        scene = {f: _value_for(space.features[f], answer) for f, answer in photo.answers.items()}
        boxes = {}
        for box in photo.boxes:
            for feature in label_map.boxes.get(box.label, {}):
                unit = next((u for u in UNITS if u.feature == feature and u.present), None)
                if unit and scene.get(feature) in unit.present[1]:
                    boxes.setdefault(unit.instance, box.xyxy)
        frames.append(Frame(photo.path, f"{root.name}/{photo.path.name}", "real", None, scene, boxes,
                            face_anywhere=True))
    return frames


def _value_for(feature, answer: str) -> str:
    """The first value of ``feature`` whose true answer is ``answer`` (a label says YES, a scene says P1)."""
    return next((str(v) for v in feature.values if feature.truth(v) == answer), answer)
