"""The bench's stages, each committed in ``OUT/stages.json`` once it has finished, with its result and its
minutes: the bench run again after a kill skips what is finished (a stage cut short resumes inside its
own folder: a run, a dataset and a replay each resume themselves).
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Callable

from ...atomic import write_json
from ...errors import InputError


class Stages:
    def __init__(self, out: Path, identity: dict, log: Callable[[str], None]):
        self.path, self.log = Path(out) / "stages.json", log
        self.data = json.loads(self.path.read_text()) if self.path.is_file() else {"identity": identity, "stages": {}}
        stored = self.data["identity"]
        differences = [f"{key}: {stored.get(key)!r} stored, {identity.get(key)!r} now"
                       for key in sorted(set(stored) | set(identity)) if stored.get(key) != identity.get(key)]
        if differences:
            raise InputError(f"{out} holds a bench augment with other settings ({'; '.join(differences)}); "
                             "run it with the stored settings or choose another --out")

    def done(self, name: str) -> bool:
        return name in self.data["stages"]

    def result(self, name: str) -> dict:
        return self.data["stages"][name]

    def run(self, name: str, work: Callable[[], dict]) -> dict:
        """``work()``'s result, committed; or the committed one, without running it again."""
        if self.done(name):
            self.log(f"{name}: finished before ({self.result(name)['minutes']:.1f} min), kept")
            return self.result(name)
        self.log(f"{name}: starting")
        start = time.monotonic()
        # as stored: a result read back on a later run is the same as the one used now
        result = json.loads(json.dumps(dict(work(), minutes=(time.monotonic() - start) / 60)))
        self.data["stages"][name] = result
        self.path.parent.mkdir(parents=True, exist_ok=True)
        write_json(self.path, self.data, indent=1)
        self.log(f"{name}: finished in {result['minutes']:.1f} min")
        return result
