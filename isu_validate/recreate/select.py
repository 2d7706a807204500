"""Which tests of one or more runs to recreate: failing, passing or a mix, drawn at random (seeded).

The paper drew failing and passing tests at random. ``mixed`` keeps the runs' failing share
(pooled over the runs) unless a share is given. Only tests with a verdict, a render and a
label can be recreated; a scene that appears in several runs is drawn at most once.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.runs import Run
from ..archive import TestRecord
from ..errors import InputError

MODES = ("failing", "passing", "mixed")


@dataclass
class Candidate:
    run: Run
    record: TestRecord
    position: int            # in the run order: runs as given, tests as evaluated

    @property
    def label_file(self) -> Path:
        return self.run.directory.label_file(self.record.test_id)

    @property
    def image(self) -> Path | None:
        return self.run.image_path(self.record)

    @property
    def render_label(self) -> Path | None:
        """The renderer's label beside the image (visible parts, camera at render size)."""
        image = self.image
        return image.with_name(image.stem + ".label.json") if image else None

    @property
    def failed(self) -> bool:
        return bool(self.record.failed)


@dataclass
class Selection:
    chosen: list[Candidate]   # in run order
    available_failing: int
    available_passing: int
    notes: list[str]


def candidates(runs: list[Run]) -> list[Candidate]:
    found, seen, position = [], set(), 0
    for run in runs:
        for record in run.valid:
            c = Candidate(run, record, position)
            position += 1
            if record.scene_key in seen or c.image is None or not c.label_file.is_file():
                continue
            seen.add(record.scene_key)
            found.append(c)
    return found


def select(runs: list[Run], mode: str, n: int, seed: int, failing_share: float | None = None) -> Selection:
    if mode not in MODES:
        raise InputError(f"unknown selection {mode!r}; use one of {', '.join(MODES)}")
    if n <= 0:
        raise InputError(f"--n must be positive, got {n}")
    if failing_share is not None and not 0.0 <= failing_share <= 1.0:
        raise InputError(f"--failing-share must be between 0 and 1, got {failing_share}")
    pool = candidates(runs)
    failing = [c for c in pool if c.failed]
    passing = [c for c in pool if not c.failed]
    if not pool:
        raise InputError("the run(s) hold no test with a verdict, an image and a label to recreate")
    if mode == "mixed":
        share = failing_share if failing_share is not None else len(failing) / len(pool)
        want = {"failing": round(n * share), "passing": n - round(n * share)}
    else:
        want = {"failing": n if mode == "failing" else 0, "passing": n if mode == "passing" else 0}
    rng = np.random.default_rng(seed)
    chosen, notes = [], []
    for kind, group in (("failing", failing), ("passing", passing)):
        k = want[kind]
        if k > len(group):
            notes.append(f"asked for {k} {kind} tests but the run(s) have only {len(group)}: taking all of them")
            k = len(group)
        if k:
            chosen += [group[i] for i in rng.choice(len(group), size=k, replace=False)]
    if not chosen:
        raise InputError(f"no {mode} tests to recreate in the run(s) ({len(failing)} failing, {len(passing)} passing)")
    chosen.sort(key=lambda c: c.position)
    return Selection(chosen, len(failing), len(passing), notes)
