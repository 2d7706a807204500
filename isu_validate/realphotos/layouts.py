"""Reading a real photo set in the layout its makers chose: the one home of these four formats.

- ``classes``: ``ROOT/<class>/*.jpg`` (``c0/ c1/ ...`` or named folders): each photo has one image-level class.
- ``yolo``: ``data.yaml`` (``names``) with ``images/`` and ``labels/`` (``ROOT/images/x.jpg`` <->
  ``ROOT/labels/x.txt``, also per split: ``train/images``, ``images/train``); a label line is
  ``class cx cy w h``, normalised; a photo without a label file has no boxes (YOLO's background image).
- ``coco``: a COCO JSON (``images``, ``annotations``, ``categories``; Roboflow's ``_annotations.coco.json``
  per split too); a file name is relative to the JSON's folder (or its ``images/``).
- ``csv``: a CSV with an image column (``image``, ``img``, ``filename``, ``file``, ``path``) and a label column
  (``label``, ``class``, ``classname``); an image is found beside the CSV, under ``ROOT/<label>/`` or under
  ``ROOT/images/``.

Boxes are kept in pixels, (x0, y0, x1, y1) with exclusive ends, as the yardsticks' frames have them.
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, InputNotFound
from ..image_files import IMAGE_SUFFIXES

LAYOUTS = ("classes", "yolo", "coco", "csv")
IMAGE_COLUMNS = ("image", "img", "filename", "file_name", "file", "path")
LABEL_COLUMNS = ("label", "class", "classname", "class_name", "category")


@dataclass(frozen=True)
class Box:
    label: str
    xyxy: tuple[int, int, int, int]


@dataclass(frozen=True)
class Photo:
    path: Path
    classes: tuple[str, ...] = ()      # image-level labels (a class folder, a CSV label)
    boxes: tuple[Box, ...] = ()        # box labels (YOLO, COCO)

    def labels(self) -> set[str]:
        return set(self.classes) | {b.label for b in self.boxes}


@dataclass
class PhotoSet:
    root: Path
    layout: str
    photos: list[Photo]
    notes: list[str] = field(default_factory=list)   # what was left out while reading, and why

    def describe(self) -> dict:
        return {"root": str(self.root.resolve()), "layout": self.layout, "photos": len(self.photos),
                "notes": list(self.notes)}


def read_photo_set(root: str | Path, layout: str | None = None) -> PhotoSet:
    """The photos of ``root`` and their labels; ``layout`` one of ``LAYOUTS`` or None to tell from the files."""
    root = Path(root)
    if not root.exists():
        raise InputNotFound(f"real photo set {root} does not exist")
    layout = layout or detect_layout(root)
    if layout not in LAYOUTS:
        raise InputError(f"unknown real photo layout {layout!r}; use one of {', '.join(LAYOUTS)}")
    photo_set = {"classes": _class_folders, "yolo": _yolo, "coco": _coco, "csv": _csv}[layout](root)
    if not photo_set.photos:
        raise InputError(f"real photo set {root} ({layout} layout) holds no photos ({', '.join(IMAGE_SUFFIXES)})")
    return photo_set


def detect_layout(root: Path) -> str:
    if root.is_file():
        suffix = root.suffix.lower()
        if suffix == ".json":
            return "coco"
        if suffix == ".csv":
            return "csv"
        if suffix in (".yaml", ".yml"):
            return "yolo"
        raise InputError(f"{root} is a file that is no real photo set: give a folder, a COCO .json, a .csv or a "
                         "YOLO data.yaml")
    if _yaml_files(root):
        return "yolo"
    if _coco_files(root):
        return "coco"
    if _class_dirs(root):   # class folders first: a CSV beside them is usually metadata (drivers, splits)
        return "classes"
    if sorted(root.glob("*.csv")):
        return "csv"
    raise InputError(f"cannot tell the layout of {root}: it has no data.yaml (YOLO), no COCO .json, no .csv and no "
                     "class folders of images; point at the folder that holds them or pass --layout")


# ---- class folders

def _class_dirs(root: Path) -> list[Path]:
    return sorted(d for d in root.iterdir() if d.is_dir() and not d.name.startswith(".") and _images_in(d))


def _images_in(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir()
                  if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith("."))


def _class_folders(root: Path) -> PhotoSet:
    dirs = _class_dirs(root)
    if not dirs:
        raise InputError(f"{root} has no class folders holding images (ROOT/<class>/*.jpg)")
    photos = [Photo(p, (d.name,)) for d in dirs for p in _images_in(d)]
    loose = _images_in(root)
    notes = [f"{len(loose)} image(s) directly in {root} have no class folder: left out"] if loose else []
    return PhotoSet(root, "classes", photos, notes)


# ---- YOLO

def _yaml_files(root: Path) -> list[Path]:
    return sorted(p for p in root.iterdir() if p.name.lower() in ("data.yaml", "data.yml", "dataset.yaml"))


def _yolo(root: Path) -> PhotoSet:
    import yaml
    from PIL import Image

    configs = [] if root.is_file() else _yaml_files(root)
    config = root if root.is_file() else configs[0] if configs else None
    if config is None:
        raise InputError(f"{root} has no data.yaml: a YOLO set names its classes there")
    base = config.parent
    try:
        names = (yaml.safe_load(config.read_text()) or {}).get("names")
    except yaml.YAMLError as exc:
        raise InputError(f"{config}: not valid YAML ({exc})") from None
    if isinstance(names, list):
        names = dict(enumerate(names))
    if not isinstance(names, dict) or not names:
        raise InputError(f"{config} has no 'names' (a list or a map of class ids to names)")
    names = {int(k): str(v) for k, v in names.items()}
    images = sorted(p for p in base.rglob("*") if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
                    and "images" in p.relative_to(base).parts[:-1])
    photos, unlabelled = [], 0
    for image in images:
        label_file = _yolo_label_file(base, image)
        if not label_file.is_file():
            unlabelled += 1
            photos.append(Photo(image))
            continue
        with Image.open(image) as im:
            width, height = im.size
        photos.append(Photo(image, boxes=tuple(_yolo_boxes(label_file, names, width, height))))
    notes = [f"{unlabelled} image(s) have no label file: read as photos without boxes"] if unlabelled else []
    return PhotoSet(base, "yolo", photos, notes)


def _yolo_label_file(base: Path, image: Path) -> Path:
    parts = list(image.relative_to(base).parts)
    i = len(parts) - 2 - parts[:-1][::-1].index("images")     # the last 'images' folder on the way
    parts[i] = "labels"
    return (base.joinpath(*parts)).with_suffix(".txt")


def _yolo_boxes(path: Path, names: dict[int, str], width: int, height: int) -> list[Box]:
    boxes = []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        fields = line.split()
        if not fields:
            continue
        try:
            cls, cx, cy, w, h = int(fields[0]), *map(float, fields[1:5])
        except (ValueError, TypeError):
            raise InputError(f"{path}:{n}: not a YOLO box line ('class cx cy w h', normalised): {line!r}") from None
        if cls not in names:
            raise InputError(f"{path}:{n}: class {cls} is not in data.yaml's names (0..{max(names)})")
        if len(fields) > 5:   # a polygon (YOLO segmentation): its bounding box
            xs, ys = list(map(float, fields[1::2])), list(map(float, fields[2::2]))
            cx, cy, w, h = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2, max(xs) - min(xs), max(ys) - min(ys)
        boxes.append(Box(names[cls], _clip((cx - w / 2) * width, (cy - h / 2) * height,
                                           (cx + w / 2) * width, (cy + h / 2) * height, width, height)))
    return boxes


def _clip(x0, y0, x1, y1, width, height) -> tuple[int, int, int, int]:
    x0, y0 = max(0, int(round(x0))), max(0, int(round(y0)))
    return x0, y0, max(x0 + 1, min(width, int(round(x1)))), max(y0 + 1, min(height, int(round(y1))))


# ---- COCO

def _coco_files(root: Path) -> list[Path]:
    found = []
    for path in sorted(root.glob("*.json")) + sorted(root.glob("*/*.json")):
        try:
            head = path.open().read(4096)
        except OSError:
            continue
        if '"images"' in head or '"categories"' in head or '"annotations"' in head or '"info"' in head:
            found.append(path)
    return found


def _coco(root: Path) -> PhotoSet:
    files = [root] if root.is_file() else _coco_files(root)
    if not files:
        raise InputError(f"{root} has no COCO .json (images, annotations, categories)")
    photos, notes = [], []
    for path in files:
        part, note = _coco_file(path)
        photos += part
        notes += note
    return PhotoSet(root if root.is_dir() else root.parent, "coco", photos, notes)


def _coco_file(path: Path) -> tuple[list[Photo], list[str]]:
    try:
        data = json.loads(path.read_text())
        categories = {c["id"]: str(c["name"]) for c in data["categories"]}
        images = {im["id"]: im for im in data["images"]}
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a COCO file with images and categories ({exc})") from None
    boxes: dict = {i: [] for i in images}
    for a in data.get("annotations", ()):
        im = images.get(a.get("image_id"))
        if im is None or a.get("category_id") not in categories or len(a.get("bbox") or ()) != 4:
            raise InputError(f"{path}: annotation {a.get('id')} names no known image or category, or has no bbox")
        x, y, w, h = map(float, a["bbox"])
        boxes[im["id"]].append(Box(categories[a["category_id"]],
                                   _clip(x, y, x + w, y + h, im.get("width", x + w), im.get("height", y + h))))
    photos, missing = [], 0
    for image_id, im in images.items():
        file = _find(path.parent, str(im["file_name"]))
        if file is None:
            missing += 1
            continue
        photos.append(Photo(file, boxes=tuple(boxes[image_id])))
    notes = [f"{path.name}: {missing} image(s) listed but not found beside it: left out"] if missing else []
    return photos, notes


def _find(base: Path, name: str, *also: str) -> Path | None:
    for folder in (base, *(base / a for a in also), base / "images"):
        if (folder / name).is_file():
            return folder / name
    return None


# ---- CSV

def _csv(root: Path) -> PhotoSet:
    files = [root] if root.is_file() else sorted(root.glob("*.csv"))
    base = root.parent if root.is_file() else root
    photos, notes = [], []
    for path in files:
        rows, (image_col, label_col) = read_csv(path, "a real-photo CSV", image=IMAGE_COLUMNS, label=LABEL_COLUMNS)
        missing = 0
        for row in rows:
            label = str(row[label_col]).strip()
            file = _find(path.parent, str(row[image_col]).strip(), label, f"train/{label}")
            if file is None:
                missing += 1
                continue
            photos.append(Photo(file, (label,)))
        if missing:
            notes.append(f"{path.name}: {missing} image(s) listed but not found: left out")
    return PhotoSet(base, "csv", photos, notes)


def read_csv(path: Path, what: str, **wanted: tuple[str, ...]) -> tuple[list[dict], list[str]]:
    """(rows, the column chosen for each ``wanted`` role: the first of its names the CSV has, any case)."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    columns = {c.lower().strip(): c for c in (rows[0].keys() if rows else ())}
    chosen = [next((columns[c] for c in names if c in columns), None) for names in wanted.values()]
    if None in chosen:
        needs = " and ".join(f"an {role} column ({', '.join(names)})" if role[0] in "aeiou" else
                             f"a {role} column ({', '.join(names)})" for role, names in wanted.items())
        raise InputError(f"{path}: {what} needs {needs}; it has {', '.join(columns) or 'none'}")
    return rows, chosen
