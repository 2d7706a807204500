"""Which scene goes into each slot of a dataset: a deterministic function of its settings.

A dataset of ``n`` images takes the first ``n`` slots whose frame is usable (a frame that cannot show the
scene, black or with everything asked about occluded, is skipped, as a run records it as a render
error); the slots after them replace skipped ones. Slots come from one stream of scenes (``SceneStream``)
that does not depend on how many are drawn, so a resumed dataset renders exactly the slots an
uninterrupted one would.
"""
from __future__ import annotations

import numpy as np

from ..space import SceneSpace
from .focus import FocusedScene, Region, SceneStream, excluded_keys, focus_regions, load_focus_runs
from .settings import DatasetSettings

UNIFORM = "uniform over the space"


def max_slots(n: int) -> int:
    """Slots tried before a dataset gives up on reaching ``n`` usable frames (a camera that sees nothing)."""
    return 5 * n + 20


class Plan:
    def __init__(self, space: SceneSpace, settings: DatasetSettings, runs=None):
        """``runs``: the loaded ``from_runs`` when the caller has them. Raises InputError (nothing to focus on,
        a bad rule) before any slot is used."""
        if runs is None:
            runs = load_focus_runs(settings.from_runs, space) if settings.from_runs else []
        self.regions: list[Region] = focus_regions(space, runs, settings.focus) if settings.focus else []
        self.limit = max_slots(settings.n)
        self._stream = SceneStream(space, self.regions or [Region(UNIFORM, None)],
                                   np.random.default_rng(settings.seed), excluded_keys(space, runs))
        self._slots: list[FocusedScene] = []
        self.slot(settings.n - 1)   # drawn now: a region that holds too few new scenes fails before any render

    def slot(self, i: int) -> FocusedScene:
        while len(self._slots) <= i:
            self._slots.append(self._stream.next())
        return self._slots[i]
