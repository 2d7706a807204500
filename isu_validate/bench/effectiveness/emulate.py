"""An emulation of a stored SUT: tune the search on a costly SUT's past runs without calling it.

``EmulatedSUT.fit`` reads finished run directories of any SUT (VQA mode, per-feature
verdicts) and learns, from the scene alone, which features the frame hides (the judge's
``occluded``) and which answers come back wrong.  Real VLMs err on several features at
once (a suitcase missed is also a wrong suitcase position and colour), so the features
are learnt as one scikit-learn ``ClassifierChain``: each feature's occlusion or error is
predicted from the scene and from the outcomes of the features before it in the chain,
and the emulator draws them in that order.  The base learner is a decision tree with
large leaves (``min_samples_leaf``), so a weakness is only emulated where the stored
runs saw it repeatedly; elsewhere the emulator errs at the rate it saw nearby.

Like a benchmark SUT, the answers are a deterministic function of (emulation, scene), as
from a VLM at temperature 0.  It is an emulation: the bench says so in every table, and
its figures are a tuning aid, not a measurement of the real SUT.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from sklearn.multioutput import ClassifierChain
from sklearn.tree import DecisionTreeClassifier

from isu_validate.errors import InputError
from isu_validate.evaluate.vqa import CORRECT, OCCLUDED, WRONG
from isu_validate.space import SceneSpace
from isu_validate.archive.run_dir import ARCHIVE_FILE, RunDir, RunDirError
from isu_validate.search.surrogate import SceneEncoder
from isu_validate.sut.planted import scene_state, wrong_answer

MIN_LEAF_SHARE, MIN_LEAF = 0.01, 20   # a tree leaf holds at least this share of the tests (and this many)


@dataclass
class EmulatedSUT:
    name: str
    description: str
    space: SceneSpace
    chain: ClassifierChain
    outputs: list[tuple[str, str]]     # per chain output: ("occluded" | "wrong", feature)
    seed: int = 0

    @classmethod
    def fit(cls, space: SceneSpace, run_dirs: list[Path], seed: int = 0) -> "EmulatedSUT":
        records = _stored_records(space, run_dirs)
        encoder = SceneEncoder(space)
        X = encoder.encode([r.canonical for r in records])
        outputs, columns = [], []
        for feature in space.predicted:
            statuses = [_status(r, feature.name) for r in records]
            for kind in ("occluded", "wrong"):
                y = np.array([s == kind for s in statuses], dtype=int)
                if y.any():  # an outcome never seen is never emulated
                    outputs.append((kind, feature.name))
                    columns.append(y)
        if not outputs:
            raise InputError("the stored runs hold no wrong or occluded answer: nothing to emulate "
                             "(a SUT that is always right needs no search)")
        leaf = max(MIN_LEAF, int(MIN_LEAF_SHARE * len(records)))
        chain = ClassifierChain(DecisionTreeClassifier(min_samples_leaf=leaf, random_state=seed),
                                order=list(range(len(outputs))), random_state=seed)
        chain.fit(X, np.column_stack(columns))
        sut = _sut_name(run_dirs)
        rate = np.mean([r.primary for r in records])
        description = (f"EMULATION of {sut} (not the real SUT): per-feature occlusion and errors learnt from "
                       f"{len(records)} stored tests in {len(run_dirs)} run(s), mean f_qa there {rate:.3f}")
        return cls(f"emulated:{sut}", description, space, chain, outputs, seed)

    def answer(self, space: SceneSpace, canonical: Mapping[str, Any]) -> dict[str, str]:
        questions = space.questions(canonical)
        drawn, state = self._draw(canonical)
        rng = np.random.default_rng([state, 1])  # which wrong answer: apart from the chain's draws
        answers = {}
        for q in questions:
            wrong = drawn.get(("wrong", q.key), False) and not drawn.get(("occluded", q.key), False)
            answers[q.key] = wrong_answer(q.options, q.truth, rng.random()) if wrong else q.truth
        return answers

    def occluded(self, space: SceneSpace, canonical: Mapping[str, Any]) -> list[str]:
        drawn, _ = self._draw(canonical)
        return [q.key for q in space.questions(canonical) if drawn.get(("occluded", q.key), False)]

    def _draw(self, canonical: Mapping[str, Any]) -> tuple[dict, int]:
        """The chain's outcomes for the scene, drawn in chain order (each given the ones before)."""
        key = self.space.key(canonical)
        if self._last[0] == key:  # answer() and occluded() of one scene: one draw
            return self._last[1], self._last[2]
        state = scene_state(self.name, self.seed, key)
        rng = np.random.default_rng(state)
        x = self._encoder.encode([dict(canonical)])[0]
        drawn: list[float] = []
        for estimator in self.chain.estimators_:
            row = np.concatenate([x, drawn])[None, :]
            proba = estimator.predict_proba(row)[0]
            p = proba[list(estimator.classes_).index(1)] if 1 in estimator.classes_ else 0.0
            drawn.append(float(rng.random() < p))
        outcomes = {out: bool(v) for out, v in zip(self.outputs, drawn)}
        self._last = (key, outcomes, state)
        return outcomes, state

    def __post_init__(self):
        self._encoder = SceneEncoder(self.space)
        self._last: tuple = (None, {}, 0)


def _status(record, feature: str) -> str:
    item = ((record.details.get("verdict") or {}).get("features") or {}).get(feature)
    if item is None:
        return "not asked"
    status = item.get("status")
    return status if status in (CORRECT, OCCLUDED) else WRONG


def _stored_records(space: SceneSpace, run_dirs: list[Path]) -> list:
    records = []
    for folder in run_dirs:
        run_dir = RunDir(Path(folder))
        if not run_dir.has_archive():
            raise RunDirError(f"{folder}: not a run directory (no {ARCHIVE_FILE}); give finished runs of the SUT "
                              "to emulate, e.g. --emulate runs/effect-reference/rs-s*")
        for record in run_dir.records():
            if record.errored or record.primary is None:
                continue
            if not ((record.details.get("verdict") or {}).get("features")):
                raise InputError(f"{folder}: test {record.test_id} has no per-feature verdict; only VQA runs "
                                 "can be emulated")
            unknown = set(record.canonical) - set(space.features)
            if unknown:
                raise InputError(f"{folder}: its scenes have features {sorted(unknown)} that space "
                                 f"{space.name!r} lacks; give the runs' space with --space")
            records.append(record)
    if not records:
        raise InputError(f"no test with a verdict in {', '.join(map(str, run_dirs))}: nothing to emulate")
    return records


def _sut_name(run_dirs: list[Path]) -> str:
    names = set()
    for folder in run_dirs:
        try:
            names.add(RunDir(Path(folder)).info()["config"]["pipeline"]["sut"])
        except (OSError, KeyError, ValueError):
            names.add("stored SUT")
    return "+".join(sorted(names))
