"""The sim/real pairs directory: read and written here, and nowhere else.

Layout (a contract, ARCHITECTURE.md)::

    PAIRS/pairs.json              how the samples were chosen and ordered (``recreate``)
    PAIRS/index.html              every recreation sheet, one A4 page each
    PAIRS/nst.json                ``stylize --pairs``: settings, per-image timings and preservation, answer flips
    PAIRS/<sample>/scene.json     the run's label file (scene and truth), byte for byte
    PAIRS/<sample>/sim.png        the render the SUT saw in the run
    PAIRS/<sample>/sim.label.json the renderer's label beside it (visible parts), when the run kept one
    PAIRS/<sample>/camera.toml    the camera rig the render used
    PAIRS/<sample>/sheet.html     the recreation sheet
    PAIRS/<sample>/sheet.png      the scene rendered for the sheet (standard preset, 640 px wide or more),
                                  with its render label sheet.label.json; not a role: sim.png is what the SUT saw
    PAIRS/<sample>/real/*.png     captured frames, each with a .json sidecar (device, exposure, ISO/gain, time;
                                  ``"stand_in": true`` on a stand-in render: ``Sample.provenance``)
    PAIRS/<sample>/align/*.png    the alignment aid of each real frame (render edges and ghost over the frame)
    PAIRS/<sample>/nst.png        the render after style transfer (``stylize --pairs``)
    PAIRS/<sample>/votes.json     validity votes: {"votes": {annotator: {"same": bool, "at": time}}}

Commands reach these files only through ``PairsDir`` and ``Sample``.
"""
from __future__ import annotations

import datetime as _dt
import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from capture.sidecar import Provenance, provenance, read_sidecar

from .atomic import write_text
from .errors import UserError
from .image_files import IMAGE_SUFFIXES

ROLES = ("sim", "real", "nst")
MANIFEST = "pairs.json"
INDEX = "index.html"
NST_REPORT = "nst.json"


class PairsError(UserError, ValueError):
    """A pairs directory (or one of its samples) that cannot be used; the message names the fix."""


@dataclass(frozen=True)
class Sample:
    """One recreated scene: its render, its real frames, and what was said about them."""
    path: Path

    @property
    def name(self) -> str:
        return self.path.name

    # ---- files
    @property
    def scene_file(self) -> Path:
        return self.path / "scene.json"

    @property
    def sim(self) -> Path:
        return self.path / "sim.png"

    @property
    def sim_label(self) -> Path:
        return self.path / "sim.label.json"

    @property
    def camera(self) -> Path:
        return self.path / "camera.toml"

    @property
    def sheet(self) -> Path:
        return self.path / "sheet.html"

    @property
    def sheet_image(self) -> Path:
        """The scene rendered for printing (``recreate``); sim.png stays the run's frame."""
        return self.path / "sheet.png"

    @property
    def real_dir(self) -> Path:
        return self.path / "real"

    @property
    def align_dir(self) -> Path:
        return self.path / "align"

    @property
    def nst(self) -> Path:
        return self.path / "nst.png"

    @property
    def votes_file(self) -> Path:
        return self.path / "votes.json"

    def real_frames(self) -> list[Path]:
        """The captured frames, sorted by name (an empty list when there is no ``real/``)."""
        if not self.real_dir.is_dir():
            return []
        return sorted(p for p in self.real_dir.iterdir()
                      if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith("."))

    def role_images(self, role: str) -> list[Path]:
        if role == "real":
            return self.real_frames()
        image = self.sim if role == "sim" else self.nst
        return [image] if image.is_file() else []

    @staticmethod
    def sidecar(frame: Path) -> dict:
        """A real frame's sidecar ({} when it has none or it cannot be read)."""
        return read_sidecar(frame)

    def provenance(self) -> Provenance:
        """The real frames split into stand-ins and real captures (their sidecars say which)."""
        return provenance(self.real_frames())

    def next_frame_index(self) -> int:
        """The number the next captured frame gets (``frame_0003.png`` after three)."""
        taken = [int(p.stem.split("_")[-1]) for p in self.real_frames()
                 if p.stem.startswith("frame_") and p.stem.split("_")[-1].isdigit()]
        return max(taken, default=-1) + 1

    def align_image(self, frame: Path) -> Path:
        return self.align_dir / f"{frame.stem}.png"

    # ---- scene
    def label(self) -> dict:
        """``scene.json`` as written by the run; raises PairsError naming the file when unusable."""
        try:
            raw = json.loads(self.scene_file.read_text())
        except FileNotFoundError:
            raise PairsError(f"{self.scene_file} is missing: copy the run's labels/<test_id>.json there "
                             "(isu-validate recreate does)") from None
        except (OSError, ValueError) as exc:
            raise PairsError(f"cannot read {self.scene_file}: {exc}") from None
        if not isinstance(raw, dict):
            raise PairsError(f"{self.scene_file} is not a JSON object")
        return raw

    def scene(self) -> dict:
        """The scene's feature values (a run's label holds them under ``scene``; a bare scene file is the scene)."""
        from .space.scene_file import scene_of   # lazily: the space package costs its numpy
        return scene_of(self.label())

    def render_label(self) -> dict:
        try:
            return json.loads(self.sim_label.read_text())
        except (OSError, ValueError):
            return {}

    # ---- votes
    def votes(self) -> dict[str, bool]:
        """annotator -> "same scenario?" answer."""
        try:
            raw = json.loads(self.votes_file.read_text())
        except FileNotFoundError:
            return {}
        except (OSError, ValueError) as exc:
            raise PairsError(f"cannot read the votes in {self.votes_file}: {exc}; fix or delete the file "
                             "and vote again") from None
        return {str(k): bool(v["same"]) for k, v in raw.get("votes", {}).items()}

    def record_vote(self, annotator: str, same: bool, note: str = "") -> None:
        """Store one annotator's vote at once (a second vote by the same annotator replaces the first)."""
        try:
            raw = json.loads(self.votes_file.read_text())
        except (OSError, ValueError):
            raw = {}
        raw.setdefault("votes", {})[annotator] = {
            "same": bool(same), "at": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            **({"note": note} if note else {})}
        write_text(self.votes_file, json.dumps(raw, indent=2) + "\n")


class PairsDir:
    """A pairs directory: its samples in name order (``recreate`` names them in recreation order)."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)

    @staticmethod
    def looks_like(folder: str | os.PathLike) -> bool:
        folder = Path(folder)
        return folder.is_dir() and any((d / "sim.png").is_file() or (d / "scene.json").is_file()
                                       for d in folder.iterdir() if d.is_dir())

    def require(self) -> "PairsDir":
        if not self.root.is_dir():
            raise PairsError(f"pairs directory {self.root} does not exist; make one with "
                             "`isu-validate recreate RUN --out DIR`")
        if not self.looks_like(self.root):
            raise PairsError(f"{self.root} is not a pairs directory (no <sample>/sim.png or "
                             "<sample>/scene.json inside); make one with `isu-validate recreate RUN --out DIR`")
        return self

    def samples(self) -> list[Sample]:
        self.require()
        return [Sample(d) for d in sorted(self.root.iterdir())
                if d.is_dir() and ((d / "sim.png").is_file() or (d / "scene.json").is_file())]

    def sample(self, name_or_path: str | os.PathLike) -> Sample:
        path = Path(name_or_path)
        folder = path if path.is_dir() else self.root / str(name_or_path)
        if not folder.is_dir():
            names = ", ".join(s.name for s in self.samples())
            raise PairsError(f"no sample {name_or_path!r} in {self.root} (samples: {names})")
        return Sample(folder)

    def role_images(self, role: str) -> list[Path]:
        """The images of one role across all samples, in sample order."""
        if role not in ROLES:
            raise PairsError(f"unknown pairs role {role!r}; choose one of {', '.join(ROLES)}")
        found = [p for s in self.samples() for p in s.role_images(role)]
        if not found:
            hint = {"nst": " (run `isu-validate stylize --pairs` to write nst.png)",
                    "real": " (capture them with `isu-validate capture shoot --pair DIR/<sample>`)"}.get(role, "")
            raise PairsError(f"pairs directory {self.root} has no {role} images{hint}")
        return found

    # ---- the manifest
    @property
    def manifest_file(self) -> Path:
        return self.root / MANIFEST

    def manifest(self) -> dict:
        try:
            return json.loads(self.manifest_file.read_text())
        except (OSError, ValueError):
            return {}

    @property
    def index_file(self) -> Path:
        """Every recreation sheet, one A4 page each (``recreate``)."""
        return self.root / INDEX

    @property
    def nst_report(self) -> Path:
        """``stylize --pairs``'s settings, timings, preservation and answer flips."""
        return self.root / NST_REPORT

    def write_manifest(self, data: dict[str, Any]) -> None:
        self.root.mkdir(parents=True, exist_ok=True)
        write_text(self.manifest_file, json.dumps(data, indent=2, default=str) + "\n")

    # ---- writing a sample (recreate)
    def new_sample(self, name: str, label_file: Path, render: Path, camera: Path | None,
                   render_label: Path | None = None) -> Sample:
        """Copy a run's label, render and camera rig into a new sample folder."""
        sample = Sample(self.root / name)
        sample.path.mkdir(parents=True, exist_ok=False)
        shutil.copyfile(label_file, sample.scene_file)  # unchanged: the run's truth travels as the run wrote it
        shutil.copyfile(render, sample.sim)
        if camera is not None:
            shutil.copyfile(camera, sample.camera)
        if render_label is not None and render_label.is_file():
            shutil.copyfile(render_label, sample.sim_label)
        return sample
