"""``exposure apply``: develop saved linear renders (an EXR, or every EXR of a run) through a camera model.

Runs keep their images: the developed frames go to a folder of their own (default
``RUN/camera-<camera name>/``), one PNG per test plus ``exposure.jsonl`` (what the camera chose for each),
written as they are made; a second call skips what is already there, so a killed job resumes."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import cv2
import numpy as np

from isu_validate.archive.run_dir import IMAGES_DIR
from isu_validate.atomic import atomic_path
from isu_validate.errors import InputError, InputNotFound
from isu_validate.exr import read_exr

from .apply import apply
from .model import ImagingModel


def read_linear(path: str | Path) -> np.ndarray:
    path = Path(path)
    if not path.exists():
        raise InputNotFound(f"{path} does not exist")
    try:
        passes = read_exr(path)
    except (ValueError, KeyError, IndexError, OSError) as exc:
        raise InputError(f"{path}: not a readable linear EXR ({exc})") from None
    try:
        return np.dstack([next(v for k, v in passes.items() if k.split(".")[-1] == c) for c in "RGB"])
    except StopIteration:
        raise InputError(f"{path}: the EXR has no R, G, B channels (has {', '.join(passes)})") from None


def seed_of(path: Path) -> int:
    """The noise seed of a render: from its name, so developing it again gives the same frame."""
    return int(hashlib.sha256(path.stem.encode()).hexdigest()[:8], 16)


def develop_file(exr: str | Path, model: ImagingModel, out: str | Path) -> dict:
    exr, out = Path(exr), Path(out)
    image, exposure = apply(read_linear(exr), model, seed=seed_of(exr))
    with atomic_path(out, keep_suffix=True) as tmp:
        if not cv2.imwrite(str(tmp), cv2.cvtColor(image, cv2.COLOR_RGB2BGR)):
            raise OSError(f"could not write {out}")
    return {"exr": str(exr), "image": str(out), "mean_level": float(image.mean() / 255.0),
            **({"exposure": exposure.to_dict()} if exposure is not None else {})}


def run_exrs(run_dir: Path) -> list[Path]:
    exrs = sorted(p for p in (run_dir / IMAGES_DIR).glob("*.exr") if not p.name.startswith("."))
    if not exrs:
        raise InputNotFound(f"{run_dir}/images has no linear EXR renders; run with `--channels exr` (or render "
                            "with --channels exr) so the linear light is kept")
    return exrs


def develop_run(run_dir: str | Path, model: ImagingModel, out_dir: str | Path, progress=None) -> list[dict]:
    run_dir, out_dir = Path(run_dir), Path(out_dir)
    exrs = run_exrs(run_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    _claim(out_dir, model)
    log = out_dir / "exposure.jsonl"
    logged = [json.loads(line) for line in log.read_text().splitlines() if line.strip()] if log.exists() else []
    done = {row["exr"]: row for row in logged}
    rows = []
    with open(log, "a") as fh:
        for i, exr in enumerate(exrs, 1):
            png = out_dir / f"{exr.stem}.png"
            if str(exr) in done and png.exists():
                rows.append(done[str(exr)])
            else:
                row = develop_file(exr, model, png)
                fh.write(json.dumps(row) + "\n")
                fh.flush()
                rows.append(row)
            if progress:
                progress(i, len(exrs), rows[-1])
    return rows


def _claim(out_dir: Path, model: ImagingModel) -> None:
    """A folder holds frames of one camera model: resuming with another would mix two cameras."""
    stamp = out_dir / "camera.json"
    if stamp.exists():
        had = json.loads(stamp.read_text())
        if had.get("model") != model.hash:
            raise InputError(f"{out_dir} holds frames developed with another camera model ({had.get('source')}); "
                             "choose another --out folder")
        return
    stamp.write_text(json.dumps({"model": model.hash, "source": model.source}, indent=1))
