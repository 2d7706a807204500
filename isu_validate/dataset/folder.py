"""A dataset folder: where its files lie and how they are read and written (the contract of
docs/ARCHITECTURE.md, "Dataset folder")::

    DIR/images/<slot>.png              a render; <slot>_style<k>.png its copy in the k-th style
    DIR/metadata.jsonl                 one row per image (the Hugging Face image-folder convention)
    DIR/annotations.json               COCO instance segmentation
    DIR/vqa.jsonl                      one chat per image: the SUT's prompt, then the expected answer
    DIR/dataset.json                   settings, versions, space hash, counts, regions, licences
    DIR/DATASET_CARD.md                the same for people
    DIR/manifest/<slot>.json           one entry per finished slot, committed atomically once its images
                                       are in place: what a resume reads and the files above are built from
    DIR/logs/                          Blender's console log per worker process

``metadata.jsonl``, ``annotations.json``, ``vqa.jsonl`` and the card are written when the dataset is
complete (``dataset.json`` says ``"complete": true``); until then the manifest holds every finished image.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ..atomic import write_json
from ..errors import InputNotFound, UserError

FORMAT = "isu-validate-dataset/1"
DATASET_FILE = "dataset.json"
METADATA_FILE = "metadata.jsonl"
ANNOTATIONS_FILE = "annotations.json"
VQA_FILE = "vqa.jsonl"
CARD_FILE = "DATASET_CARD.md"
IMAGES_DIR = "images"
MANIFEST_DIR = "manifest"
LOGS_DIR = "logs"
WORK_DIR = ".work"          # renders land here first (hidden: no image loader walks into it)


class DatasetError(UserError):
    """A folder that cannot be started or resumed as a dataset; the message says what to do."""


@dataclass(frozen=True)
class DatasetDir:
    path: Path

    @property
    def info_file(self) -> Path:
        return self.path / DATASET_FILE

    def is_dataset(self) -> bool:
        return self.info_file.is_file()

    def info(self) -> dict:
        try:
            return json.loads(self.info_file.read_text())
        except FileNotFoundError:
            raise InputNotFound(f"{self.path} is not a dataset folder (no {DATASET_FILE}); give a folder "
                                "`isu-validate dataset --out` wrote") from None
        except ValueError as exc:
            raise DatasetError(f"{self.info_file} is not valid JSON ({exc})") from None

    def write_info(self, info: dict) -> None:
        write_json(self.info_file, info, indent=1)

    # ---- images
    @staticmethod
    def image_name(slot: int, style: int | None = None) -> str:
        """The file name of a slot's render (or of its copy in style ``style``, from 1), relative to DIR."""
        return f"{IMAGES_DIR}/{slot:06d}{'' if style is None else f'_style{style}'}.png"

    def work_dir(self) -> Path:
        return self.path / WORK_DIR / str(os.getpid())

    # ---- manifest
    def entry_file(self, slot: int) -> Path:
        return self.path / MANIFEST_DIR / f"{slot:06d}.json"

    def commit(self, entry: dict) -> None:
        """Record a finished slot (its images already in place): atomically, so a kill leaves it whole or absent."""
        write_json(self.entry_file(entry["slot"]), entry)

    def entries(self) -> dict[int, dict]:
        """Every committed slot by number (temporary files of an interrupted write are not entries)."""
        folder = self.path / MANIFEST_DIR
        found = {}
        for path in sorted(folder.glob("[0-9]*.json")) if folder.is_dir() else ():
            entry = json.loads(path.read_text())
            found[int(entry["slot"])] = entry
        return found

    # ---- the outputs
    def metadata(self) -> list[dict]:
        """The rows of a complete dataset's metadata.jsonl."""
        path = self.path / METADATA_FILE
        if not path.is_file():
            raise DatasetError(f"{self.path} holds no {METADATA_FILE}: the dataset is not complete; "
                               f"finish it with `isu-validate dataset --out {self.path} --resume`")
        return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def open_dataset(path: str | os.PathLike) -> DatasetDir:
    """The dataset folder at ``path``; InputNotFound when no dataset was started there."""
    folder = DatasetDir(Path(path))
    folder.info()
    return folder
