"""Render cache: a scene seen before (same canonical scene, rigs, preset, channels, renderer version)
costs a file copy. Entries are written to a temporary folder and renamed into place, so processes of a
pool can share one cache folder."""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path


class RenderCache:
    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)  # made by the first put: opening a cache writes nothing

    def _entry(self, key: str) -> Path:
        return self.root / key[:2] / key

    def get(self, key: str, out: Path, where: dict[str, Path]) -> dict | None:
        """Copy a cached render to ``out`` (and its channels to ``where``); None on a miss."""
        entry = self._entry(key)
        meta_path = entry / "meta.json"
        if not meta_path.is_file():
            return None
        meta = json.loads(meta_path.read_text())
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(entry / "image.png", out)
        paths = {}
        for name, file in meta["files"].items():
            shutil.copyfile(entry / file, where[name])
            paths[name] = where[name]
        return {"channels": paths, "meta": meta}

    def put(self, key: str, out: Path, channels: dict[str, Path], meta: dict) -> None:
        entry = self._entry(key)
        if entry.exists():
            return
        entry.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=entry.parent, prefix=".tmp-"))
        shutil.copyfile(out, tmp / "image.png")
        files = {}
        for name, path in channels.items():
            files[name] = f"{name}{''.join(Path(path).suffixes[-1:])}"
            shutil.copyfile(path, tmp / files[name])
        (tmp / "meta.json").write_text(json.dumps({**meta, "files": files}, indent=1))
        try:
            os.rename(tmp, entry)
        except OSError:  # another process stored the same scene first
            shutil.rmtree(tmp, ignore_errors=True)
