"""Benchmark SUTs: systems with known, structured weaknesses and random perception noise.

They answer from the scene itself (no rendering), so a search can be measured against
them in seconds.  Each weakness (a ``BlindSpot``) is a conjunction of feature values and
image conditions, written in the scene space's own condition language, that makes the
SUT give wrong answers with some probability, as real VLMs do (the ISU-Test paper saw
seat belts missed over black shirts and luggage missed on the back seat).  On top of
that every answer is wrong with a small probability wherever the scene is (noise), so a
search has to separate the SUT's systematic errors from its random ones.

Answers are a deterministic function of (SUT, scene): the same scene always gets the
same answer, as from a VLM at temperature 0, and a replayed search sees the same SUT.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from isu_validate.errors import InputError
from isu_validate.space import SceneSpace
from isu_validate.space.conditions import Condition, Term, parse_condition
from isu_validate.sut.benchmark_names import BENCHMARK_SUTS


ANY_WRONG = "*"


@dataclass(frozen=True)
class BlindSpot:
    """Where ``when`` holds (on the canonical scene), the SUT gives ``answers`` with probability ``p``."""
    name: str
    when: Condition
    answers: Mapping[str, str]   # feature -> the answer given ("*": another option than the truth)
    p: float

    def features(self) -> set[str]:
        return set(self.when.features) | set(self.answers)


@dataclass
class BenchmarkSUT:
    name: str
    description: str
    blind_spots: list[BlindSpot]
    noise: float                      # probability that any one answer is wrong at random
    seed: int = 0
    skipped: list[str] = field(default_factory=list)  # blind spots naming features the space lacks

    def answer(self, space: SceneSpace, canonical: Mapping[str, Any]) -> dict[str, str]:
        """The SUT's answers to the scene's questions (keys of its active predicted features)."""
        rng = self._rng(space.key(canonical))
        questions = space.questions(canonical)
        answers = {q.key: q.truth for q in questions}
        options = {q.key: q.options for q in questions}
        for spot in self.blind_spots:  # the same draws for every scene, so answers stay stable
            hit, pick = rng.random() < spot.p, rng.random()
            if hit and spot.when.matches(canonical):
                for key, given in spot.answers.items():
                    if key in answers:
                        answers[key] = wrong_answer(options[key], answers[key], pick) if given == ANY_WRONG else given
        for q in questions:  # random perception errors, independent per question
            draw, pick = rng.random(), rng.random()
            if draw < self.noise:
                answers[q.key] = wrong_answer(options[q.key], answers[q.key], pick)
        return answers

    def occluded(self, space: SceneSpace, canonical: Mapping[str, Any]) -> list[str]:
        """Features the frame would hide: none, a benchmark SUT sees the scene itself."""
        return []

    def _rng(self, scene_key: str) -> np.random.Generator:
        return np.random.default_rng(scene_state(self.name, self.seed, scene_key))


def scene_state(name: str, seed: int, scene_key: str) -> int:
    """The seed of a benchmark SUT's draws for one scene: the same scene, the same answers."""
    return int.from_bytes(hashlib.sha1(f"{name}|{seed}|{scene_key}".encode()).digest()[:8], "little")


def wrong_answer(options, answer: str, pick: float) -> str:
    """One of the options other than ``answer``, picked by ``pick`` in [0, 1) (the answer itself when
    there is no other)."""
    wrong = [o for o in options if o != answer]
    return wrong[int(pick * len(wrong))] if wrong else answer


# The paper's kinds of weakness, over features that every version of the space keeps.
_PAPER_BLIND_SPOTS = [
    ("seat belt missed over a black T-shirt",
     {"seat_belt": "YES", "tshirt_colour": "BLACK"}, {"seat_belt": "NO"}, 0.7),
    ("luggage on the back seat missed unless the light is high",
     {"luggage_position": "BACK", "external_light": ["LOW", "MEDIUM"]},
     {"luggage": "NO", "luggage_position": "NONE", "luggage_colour": "NONE"}, 0.8),
    ("rear-facing child seat read as front-facing with the cabin lights off",
     {"child_seat_orientation": "REAR_FACING", "car_lights": "OFF"},
     {"child_seat_orientation": "FRONT_FACING"}, 0.8),
    ("child hidden by a rear-facing seat shell",
     {"child_seat_orientation": "REAR_FACING", "child": "YES"}, {"child": "NO"}, 0.6),
    ("phone held low in the lap not seen",
     {"phone_position": ["P7", "P8", "P9", "P10"]}, {"phone_position": "NO"}, 0.7),
    ("smile not seen in low light",
     {"driver_emotion": "HAPPY", "external_light": "LOW"}, {"driver_emotion": "SERIOUS"}, 0.6),
]


def paper_blind_spots(space: SceneSpace, noise: float, name: str) -> BenchmarkSUT:
    spots, skipped = [], []
    for label, when, answers, p in _PAPER_BLIND_SPOTS:
        needed = set(when) | set(answers)
        if not needed <= set(space.features) or not _values_exist(space, when):
            skipped.append(label)
            continue
        spots.append(BlindSpot(label, parse_condition(when, label), answers, p))
    description = (f"{len(spots)} paper-like blind spots (conjunctions of feature values and light), "
                   f"{noise:.0%} random error per answer")
    return BenchmarkSUT(name, description, spots, noise, skipped=skipped)


def _values_exist(space: SceneSpace, when: dict) -> bool:
    for feature, spec in when.items():
        values = spec if isinstance(spec, list) else [spec]
        if space.features[feature].discrete and not set(values) <= set(space.features[feature].values):
            return False
    return True


def random_blind_spots(space: SceneSpace, seed: int, noise: float = 0.03, n_spots: int = 6,
                       terms: int = 2, p: float = 0.8) -> BenchmarkSUT:
    """Blind spots drawn over any space: each makes one predicted feature wrong where
    ``terms`` other features take a drawn value (a third of the range for ordered ones).
    A drawn spot is kept only if 2-40% of random scenes fall in it with the feature asked."""
    rng = np.random.default_rng(seed)
    predicted = [f for f in space.predicted if len(f.options) > 1]
    if not predicted:
        raise InputError(f"space {space.name!r} has no predicted feature: a benchmark SUT has nothing to get wrong")
    probe = [space.canonical(s) for s in space.sample(np.random.default_rng(seed + 1), 1000)]
    spots: list[BlindSpot] = []
    for _ in range(100 * n_spots):
        if len(spots) == n_spots:
            break
        target = predicted[int(rng.integers(len(predicted)))]
        others = [f for f in space.features.values() if f.name != target.name and f.span > 0]
        chosen = rng.choice(len(others), size=min(terms, len(others)), replace=False)
        condition = Condition(tuple(_random_term(others[int(j)], rng) for j in sorted(chosen)))
        share = np.mean([target.name in s and condition.matches(s) for s in probe])
        if 0.02 <= share <= 0.4:
            spots.append(BlindSpot(f"{target.name} wrong where {condition.to_toml_dict()}",
                                   condition, {target.name: ANY_WRONG}, p))
    return BenchmarkSUT(f"random-spots-{seed}", f"{len(spots)} random blind spots of {terms} terms "
                        f"(drawn with seed {seed}), {noise:.0%} random error per answer", spots, noise, seed=seed)


def make_benchmark_sut(name: str, space: SceneSpace) -> BenchmarkSUT:
    """``blind-spots`` | ``blind-spots-noisy`` | ``random-spots[-SEED]``."""
    if name == "blind-spots":
        return paper_blind_spots(space, 0.03, name)
    if name == "blind-spots-noisy":
        return paper_blind_spots(space, 0.08, name)
    if name == "random-spots" or name.startswith("random-spots-"):
        suffix = name[len("random-spots-"):] if name != "random-spots" else "1"
        if not suffix.isdigit():
            raise InputError(f"benchmark SUT {name!r}: write random-spots-SEED with a whole number SEED")
        return random_blind_spots(space, int(suffix))
    raise InputError(f"unknown benchmark SUT {name!r}; use one of {', '.join(BENCHMARK_SUTS)} "
                     "(random-spots-SEED draws other blind spots)")



def _random_term(feature, rng: np.random.Generator) -> Term:
    if feature.discrete:
        return Term(feature.name, inside=(feature.values[int(rng.integers(len(feature.values)))],))
    width = (feature.high - feature.low) / 3
    low = float(feature.low + rng.uniform(0, feature.high - feature.low - width))
    return Term(feature.name, low=low, high=low + width)
