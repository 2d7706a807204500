"""New scenes concentrated where earlier runs failed (or passed, or inside one rule), never a scene of
those runs: the data a SUT has not been judged on.

    regions = focus_regions(space, runs, "failing")       # the decision-tree regions `report` prints
    scenes = focus_scenes(space, runs, "failing", 200, np.random.default_rng(0))

``failing``: the failure regions of the runs' tests (``analysis/regions.py``, as ``report`` prints them),
plus the failing tests no region holds; each region gets new scenes in proportion to the failing tests
it holds, each drawn near one of them in the space's own distance (``SceneSpace.distances``: a few
features changed, then repaired) and inside the region's rule. ``passing`` the same for passing tests.
``rule:TEXT`` one rule by hand: near the runs' failing tests inside it, or drawn uniformly inside it
when none lies there.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ..analysis.regions import failure_regions
from ..analysis.runs import Run, load_run
from ..archive import find_runs
from ..errors import InputError
from ..space import SceneSpace
from .rules import Rule, parse_rule
from .settings import FOCUS_MODES, RULE_PREFIX

NEAR = 0.2            # a new scene lies within this mean per-feature distance of its anchor (~4 of 19 features)
TRIES = 300           # draws per scene before the neighbourhood is widened (doubled), then given up
MAX_CHANGED = 3       # features a mutation redraws (1..3), before repair


@dataclass
class Region:
    """Where new scenes go: a rule (None: anywhere near the anchors), the runs' tests it holds and the
    anchors new scenes are drawn near (the focused tests inside it; none: uniformly inside the rule)."""
    name: str
    rule: Rule | None
    tests: int = 0                 # the runs' tests with a verdict inside it
    focused: int = 0               # of those, the failing (or passing) ones
    anchors: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"region": self.name, "tests": self.tests, "focused": self.focused,
                "drawn": "near the focused tests" if self.anchors else "uniformly inside the rule"}


@dataclass(frozen=True)
class FocusedScene:
    scene: dict        # a full valid scene (latent values of inactive features included)
    region: str


def load_focus_runs(paths: Sequence[str | Path | Run], space: SceneSpace) -> list[Run]:
    """The runs (a folder of runs stands for each run in it), all of ``space``; RunDirError for a folder
    that is not a run, InputError for a run of another space."""
    runs = [p if isinstance(p, Run) else None for p in paths]
    loaded = [r for r in runs if r is not None]
    folders = [p for p in paths if not isinstance(p, Run)]
    loaded += [load_run(p) for p in (find_runs(folders) if folders else [])]
    for run in loaded:
        if run.space.hash != space.hash:
            raise InputError(f"run {run.path} tested scene space {run.space.name!r} (hash {run.space.hash}), not "
                             f"{space.name!r} (hash {space.hash}); give --space as the run had it")
    return loaded


def runs_digest(runs: Sequence[Run]) -> str:
    """Identifies what the runs hold (a run resumed since gets another digest)."""
    rows = sorted((str(r.path.resolve()), t.test_id, t.scene_key, bool(t.failed), bool(t.errored))
                  for r in runs for t in r.records)
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()[:16]


def excluded_keys(space: SceneSpace, runs: Sequence[Run]) -> set[str]:
    """Every scene the runs tested (errors included): a dataset never holds one."""
    return {space.key(t.canonical) for run in runs for t in run.records}


def focus_regions(space: SceneSpace, runs: Sequence[Run], mode: str) -> list[Region]:
    """The regions of ``mode`` (failing | passing | rule:TEXT) over the runs' tests with a verdict.
    InputError when there is nothing to focus on (no failing test for ``failing``)."""
    if mode.startswith(RULE_PREFIX):
        rule = parse_rule(space, mode[len(RULE_PREFIX):])
        return [_rule_region(rule, runs)]
    if mode not in FOCUS_MODES:
        raise InputError(f"unknown focus {mode!r}; use failing, passing or rule:\"FEATURE = VALUE and ...\"")
    tests = [(run, t) for run in runs for t in run.valid]
    outcome = [bool(t.failed) == (mode == "failing") for _, t in tests]
    if not any(outcome):
        where = ", ".join(f"{run.path} (threshold {run.oracle_threshold})" for run in runs)
        raise InputError(f"no {mode} test in {where}: nothing to focus on; use "
                         f"--focus {'passing' if mode == 'failing' else 'failing'} or a rule, or drop --from-run")
    scenes = [t.canonical for _, t in tests]
    regions, covered = [], set()
    for leaf in failure_regions(space, scenes, outcome):
        rule = parse_rule(space, leaf["rule"])
        inside = [i for i, s in enumerate(scenes) if rule.holds(s)]
        anchors = [i for i in inside if outcome[i] and i not in covered]
        covered.update(anchors)
        if anchors:
            regions.append(Region(leaf["rule"], rule, len(inside), len(anchors), [scenes[i] for i in anchors]))
    rest = [i for i, hit in enumerate(outcome) if hit and i not in covered]
    if rest:
        name = f"near the {mode} tests" + (" outside these regions" if regions else "")
        regions.append(Region(name, None, len(rest), len(rest), [scenes[i] for i in rest]))
    return regions


def _rule_region(rule: Rule, runs: Sequence[Run]) -> Region:
    inside = [t for run in runs for t in run.valid if rule.holds(t.canonical)]
    anchors = [t.canonical for t in inside if t.failed]
    return Region(rule.text, rule, len(inside), len(anchors), anchors)


class SceneStream:
    """New scenes one after another, each from the region furthest below its share (shares in proportion to
    the regions' focused tests), so every prefix of the stream is proportional within one scene and the
    stream never depends on how long it will be; none of ``excluded``, no two alike."""

    def __init__(self, space: SceneSpace, regions: Sequence[Region], rng: np.random.Generator, excluded: set[str]):
        self.space, self.regions, self.rng = space, list(regions), rng
        weights = np.array([max(r.focused, 1) for r in self.regions], dtype=float)
        self.shares = weights / weights.sum()
        self.counts = np.zeros(len(self.regions))
        self.taken = set(excluded)

    def next(self) -> FocusedScene:
        i = int(np.argmax(self.shares * (self.counts.sum() + 1) - self.counts))
        self.counts[i] += 1
        scene = _draw(self.space, self.regions[i], self.rng, self.taken)
        self.taken.add(self.space.key(scene))
        return FocusedScene(scene, self.regions[i].name)


def focus_scenes(space: SceneSpace, runs: Sequence[Run | str | Path], mode: str, n: int,
                 rng: np.random.Generator) -> list[FocusedScene]:
    """``n`` new valid scenes focused as ``mode`` says (see the module), none a scene of the runs and no
    two alike (canonically). InputError when a region holds no new scene."""
    runs = load_focus_runs(runs, space)
    regions = focus_regions(space, runs, mode)
    return sample_regions(space, regions, n, rng, excluded_keys(space, runs))


def sample_regions(space: SceneSpace, regions: Sequence[Region], n: int, rng: np.random.Generator,
                   excluded: set[str]) -> list[FocusedScene]:
    stream = SceneStream(space, regions, rng, excluded)
    return [stream.next() for _ in range(n)]


def _draw(space: SceneSpace, region: Region, rng: np.random.Generator, taken: set[str]) -> dict:
    radius = NEAR
    anchors = [space.canonical_vector(a) for a in region.anchors]
    for attempt in range(TRIES * 4):
        if attempt and attempt % TRIES == 0:
            radius *= 2   # the neighbourhood is used up: look further out
        if region.anchors:
            k = int(rng.integers(len(region.anchors)))
            scene = space.repair(_mutate(space, region.anchors[k], rng), rng)
        elif region.rule is not None:
            scene = space.repair(region.rule.force(space, space.sample(rng)[0], rng), rng)
        else:   # no anchor, no rule: anywhere in the space
            scene = space.sample(rng)[0]
        canonical = space.canonical(scene)
        if space.key(canonical) in taken or (region.rule is not None and not region.rule.holds(canonical)):
            continue
        if region.anchors and space.distances(space.canonical_vector(canonical), anchors[k][None])[0] > radius:
            continue
        return scene
    raise InputError(f"region {region.name!r} holds no new scene (every scene near its tests is taken or "
                     "breaks its rule or the space's constraints); ask for fewer images or another focus")


def _mutate(space: SceneSpace, anchor: dict, rng: np.random.Generator) -> dict:
    """The anchor (latent values drawn for its inactive features) with 1..MAX_CHANGED features redrawn."""
    scene = {name: anchor[name] if name in anchor else space.random_value(f, rng)
             for name, f in space.features.items()}
    names = list(space.features)
    for i in rng.choice(len(names), size=int(rng.integers(1, MAX_CHANGED + 1)), replace=False):
        scene[names[i]] = space.random_value(space.features[names[i]], rng)
    return scene
