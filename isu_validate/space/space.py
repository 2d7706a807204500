"""A scene space: features, activity, constraints, encoding, sampling and repair."""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np

from .conditions import Condition, Term
from .errors import SpaceError
from .features import Feature

Scene = dict[str, Any]


@dataclass(frozen=True)
class Constraint:
    name: str
    if_: Condition
    then: Condition

    def holds(self, canonical: Mapping[str, Any]) -> bool:
        return not self.if_.matches(canonical) or self.then.matches(canonical)


@dataclass(frozen=True)
class Question:
    """One question the SUT is asked about an active predicted feature of a scene."""
    key: str
    question: str
    options: tuple[str, ...]
    weight: float
    truth: str

    def to_dict(self) -> dict:
        return {"key": self.key, "question": self.question, "options": list(self.options)}


class SceneSpace:
    """Features in dependency order (a feature's ``active_when`` only names earlier ones)."""

    def __init__(self, name: str, features: Iterable[Feature], constraints: Iterable[Constraint] = (),
                 prompt_rules: Iterable[str] = (), description: str = "", source: str = "<memory>"):
        self.name = name
        self.description = description
        self.source = source
        self.features: dict[str, Feature] = {f.name: f for f in features}
        self.constraints: tuple[Constraint, ...] = tuple(constraints)
        self.prompt_rules: tuple[str, ...] = tuple(prompt_rules)
        self.names: tuple[str, ...] = tuple(self.features)
        categorical = np.array([f.type == "categorical" for f in self.features.values()])
        self._distance_scale = np.where(categorical, 1e4, 1.0)

    # ------------------------------------------------------------------ identity
    def to_dict(self) -> dict:
        return {"name": self.name,
                "features": {n: f.to_toml_dict() for n, f in self.features.items()},
                "constraints": [{"name": c.name, "if": c.if_.to_toml_dict(), "then": c.then.to_toml_dict()}
                                for c in self.constraints]}

    @property
    def hash(self) -> str:
        """Identifies the space's semantics (not its comments or captions)."""
        blob = json.dumps(self.to_dict(), sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    # ------------------------------------------------------------------ activity
    def canonical(self, scene: Mapping[str, Any]) -> Scene:
        """The scene with inactive features removed, in feature order."""
        out: Scene = {}
        for name, feature in self.features.items():
            if feature.is_active(out) and name in scene and scene[name] is not None:
                value = scene[name]
                out[name] = round(float(value), 6) if feature.type == "continuous" else value
        return out

    def key(self, scene: Mapping[str, Any]) -> str:
        """Hash of the canonical scene: equal for scenes that differ only in inactive features."""
        blob = json.dumps(self.canonical(scene), sort_keys=True, separators=(",", ":")).encode()
        return hashlib.sha1(blob).hexdigest()

    def active_names(self, scene: Mapping[str, Any]) -> list[str]:
        return list(self.canonical(scene))

    # ------------------------------------------------------------------ validity
    def violations(self, scene: Mapping[str, Any]) -> list[str]:
        """Everything wrong with a scene, as messages that name the feature."""
        problems = self._unknown(scene)
        seen: Scene = {}
        for name, feature in self.features.items():
            if not feature.is_active(seen):
                continue
            if scene.get(name) is None:
                problems.append(f"feature {name!r} is active here but has no value")
                continue
            if not feature.contains(scene[name]):
                domain = list(feature.values) if feature.discrete else f"[{feature.low}, {feature.high}]"
                problems.append(f"feature {name!r} has value {scene[name]!r} outside its domain {domain}")
            seen[name] = scene[name]
        if problems:
            return problems
        canonical = self.canonical(scene)
        return [f"constraint broken: {c.name}" for c in self.constraints if not c.holds(canonical)]

    def _unknown(self, scene: Mapping[str, Any]) -> list[str]:
        """One message for all unknown keys: the known list once, however many keys are wrong."""
        unknown = [repr(k) for k in scene if k not in self.features]
        if not unknown:
            return []
        which = f"feature {unknown[0]}" if len(unknown) == 1 else f"features {', '.join(unknown)}"
        return [f"unknown {which} (known: {', '.join(self.names)})"]

    def is_valid(self, scene: Mapping[str, Any]) -> bool:
        return not self.violations(scene)

    def check(self, scene: Mapping[str, Any]) -> Scene:
        """Raise SpaceError naming every problem; return the canonical scene."""
        if not isinstance(scene, Mapping):  # e.g. a JSON file holding a list of scenes
            raise SpaceError(f"a scene is a JSON object {{feature: value, ...}} for space {self.name!r}, "
                             f"not a {type(scene).__name__}; write one scene per file")
        problems = self.violations(scene)
        if problems:
            raise SpaceError(f"invalid scene for space {self.name!r}: " + "; ".join(problems))
        return self.canonical(scene)

    # ------------------------------------------------------------------ sampling and repair
    def random_value(self, feature: Feature, rng: np.random.Generator) -> Any:
        if feature.discrete:
            return feature.values[int(rng.integers(len(feature.values)))]
        if feature.type == "integer":
            return int(rng.integers(int(feature.low), int(feature.high) + 1))
        return float(rng.uniform(feature.low, feature.high))

    def sample(self, rng: np.random.Generator, n: int = 1) -> list[Scene]:
        """``n`` valid scenes (full, including latent values of inactive features)."""
        return [self.repair({name: self.random_value(f, rng) for name, f in self.features.items()}, rng)
                for _ in range(n)]

    def repair(self, scene: Mapping[str, Any], rng: np.random.Generator, max_steps: int = 50) -> Scene:
        """A valid scene close to ``scene``: out-of-domain values are clipped, then each broken
        constraint is mended by a random minimal change (make its `then` true, or its `if` false)."""
        fixed = {name: self._clip(f, scene.get(name), rng) for name, f in self.features.items()}
        for _ in range(max_steps):
            canonical = self.canonical(fixed)
            broken = [c for c in self.constraints if not c.holds(canonical)]
            if not broken:
                return fixed
            moves = self._mending_moves(broken[0], fixed, rng)
            if not moves:
                break
            name, value = moves[int(rng.integers(len(moves)))]
            fixed[name] = value
        for _ in range(1000):  # the local mends cycled: fall back to a fresh valid draw
            fresh = {name: self.random_value(f, rng) for name, f in self.features.items()}
            if self.is_valid(fresh):
                return fresh
        raise SpaceError(f"could not repair a scene of space {self.name!r}; are its constraints satisfiable?")

    def _clip(self, feature: Feature, value: Any, rng: np.random.Generator) -> Any:
        if value is None or (feature.discrete and value not in feature.values):
            return self.random_value(feature, rng)
        if feature.discrete:
            return value
        value = min(feature.high, max(feature.low, float(value)))
        return int(round(value)) if feature.type == "integer" else value

    def _mending_moves(self, constraint: Constraint, scene: Scene, rng) -> list[tuple[str, Any]]:
        moves = []
        for term, want in [(t, True) for t in constraint.then.terms] + [(t, False) for t in constraint.if_.terms]:
            feature = self.features[term.feature]
            for value in self._candidate_values(feature, rng):
                trial = dict(scene, **{term.feature: value})
                if value != scene[term.feature] and term.matches(self.canonical(trial)) == want:
                    moves.append((term.feature, value))
        return moves

    def _candidate_values(self, feature: Feature, rng) -> list:
        if feature.discrete:
            return list(feature.values)
        return [self.random_value(feature, rng) for _ in range(8)] + [feature.low, feature.high]

    # ------------------------------------------------------------------ encoding
    def encode(self, scene: Mapping[str, Any]) -> np.ndarray:
        """Full scene to [0,1]^d, one entry per feature (latent values included)."""
        return np.array([f.encode(scene[n]) for n, f in self.features.items()], dtype=float)

    def decode(self, u: Iterable[float]) -> Scene:
        return {n: f.decode(x) for (n, f), x in zip(self.features.items(), u)}

    def canonical_vector(self, scene: Mapping[str, Any]) -> np.ndarray:
        """[0,1] encoding with NaN for inactive features: the input of the diversity measure."""
        canonical = self.canonical(scene)
        return np.array([f.encode(canonical[n]) if n in canonical else np.nan for n, f in self.features.items()])

    def distances(self, vector: np.ndarray, others: np.ndarray) -> np.ndarray:
        """Mean per-feature distance from one canonical vector to each row of ``others``:
        categorical mismatch counts 1 (Hamming), ordered features |a-b| in encoding units
        (|a-b|/range), a feature active in only one of the two counts 1, inactive in both 0."""
        if len(others) == 0:
            return np.zeros(0)
        return self.distances_sentinel(self.distance_rows(vector), self.distance_rows(others))

    def distances_sentinel(self, vector: np.ndarray, others: np.ndarray) -> np.ndarray:
        """``distances`` for vectors prepared by ``distance_rows`` (no NaN: fast)."""
        return np.minimum(np.abs(others - vector), 1.0).mean(axis=1)

    def distance_rows(self, vectors: np.ndarray) -> np.ndarray:
        """Canonical vectors scaled so that ``min(|a-b|, 1)`` is the per-feature distance:
        an inactive feature becomes ``INACTIVE`` (>= 2 away from any active value), and
        categorical columns are stretched so that any mismatch exceeds 1."""
        scaled = np.where(np.isnan(vectors), INACTIVE, vectors) * self._distance_scale
        return scaled.astype(np.float32)

    # ------------------------------------------------------------------ questions
    def questions(self, scene: Mapping[str, Any]) -> list[Question]:
        """Questions about the scene's active predicted features, with the true answers."""
        canonical = self.canonical(scene)
        return [Question(n, f.question, f.options, f.weight, f.truth(canonical[n]))
                for n, f in self.features.items() if f.predicted and n in canonical]

    @property
    def predicted(self) -> list[Feature]:
        return [f for f in self.features.values() if f.predicted]


INACTIVE = 3.0  # stands for "feature absent" in distance computations (outside [0, 1])


__all__ = ["INACTIVE", "SceneSpace", "Constraint", "Question", "Scene", "Term"]
