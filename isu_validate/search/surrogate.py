"""A surrogate of the SUT learned from the run's own tests: where does it answer wrongly?

The response fitness is a weighted sum of per-feature correctness (F_qa), so the
surrogate learns, for every predicted feature, the probability that the SUT gets that
feature wrong in a scene: one scikit-learn decision tree per feature (the failure
regions of NSGA-II-DT, Abdessalem et al. 2018), with a Beta posterior over the error
rate in each leaf.  A candidate's expected fitness combines the features' error
probabilities with the space's weights, so two weaknesses seen apart (a belt missed
over a black shirt, a phone missed in the lap) predict a lower fitness where they meet,
before any such scene was tried.  Random errors of the SUT fall into leaves with few
errors among many tests and stay improbable; systematic ones gather in leaves of their own.

Without per-feature verdicts (captioning, or ``tell`` without records) one tree models
the loss 1 - fitness itself.

Cost: trees are refitted when the archive has grown by a tenth since the last fit, on
at most ``max_rows`` tests drawn at random; in between, new tests only update the leaf
counts (an ``apply`` through the existing trees), so a 10,000-test archive stays cheap.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.tree import DecisionTreeClassifier, DecisionTreeRegressor

from ..space import SceneSpace

FITNESS_TARGET = "fitness"   # the target when no per-feature verdicts are known
INACTIVE_CODE = -1.0         # an inactive feature in the encoding (outside [0, 1])


class SceneEncoder:
    """Canonical scenes to numeric rows for the trees: one-hot for categorical features with
    more than two values, [0,1] for the rest, -1 in every column of an inactive feature."""

    def __init__(self, space: SceneSpace):
        self.space = space
        self.n_columns = 0
        self._codes: dict[str, dict] = {}  # ordered and two-valued features: value -> [0,1] code
        self._plan: list[tuple[str, int, dict | None, float, float]] = []  # name, column, one-hot map, low, span
        for name, feature in space.features.items():
            if feature.span == 0:
                continue
            if feature.type == "categorical" and len(feature.values) > 2:
                self._plan.append((name, self.n_columns, {v: i for i, v in enumerate(feature.values)}, 0.0, 1.0))
                self.n_columns += len(feature.values)
            elif feature.discrete:
                self._codes[name] = {v: i / feature.span for i, v in enumerate(feature.values)}
                self._plan.append((name, self.n_columns, None, 0.0, 1.0))
                self.n_columns += 1
            else:
                self._plan.append((name, self.n_columns, None, float(feature.low), feature.span))
                self.n_columns += 1

    def encode(self, canonical_scenes: list[dict]) -> np.ndarray:
        out = np.full((len(canonical_scenes), self.n_columns), INACTIVE_CODE, dtype=np.float32)
        for i, scene in enumerate(canonical_scenes):
            row = out[i]
            for name, column, onehot, low, span in self._plan:
                value = scene.get(name)
                if value is None:
                    continue
                if onehot is not None:
                    row[column:column + len(onehot)] = 0.0
                    row[column + onehot[value]] = 1.0
                elif name in self._codes:
                    row[column] = self._codes[name][value]
                else:
                    row[column] = (float(value) - low) / span
        return out


def record_targets(record) -> dict[str, float] | None:
    """What a test says about the SUT's errors: {feature: 1 wrong / 0 right} from the VQA
    verdict, else {"fitness": 1 - fitness}; None for a test without a verdict.  An occluded
    feature says nothing about the SUT (the judge leaves it out too): hiding things earns the
    search nothing."""
    if record.errored or record.primary is None:
        return None
    features = (record.details.get("verdict") or {}).get("features")
    if isinstance(features, dict) and features:
        judged = {key: float(item.get("status") != "correct") for key, item in features.items()
                  if item.get("status") != "occluded"}
        return judged or None
    return {FITNESS_TARGET: float(np.clip(1.0 - float(record.primary), 0.0, 1.0))}


@dataclass
class _Leaves:
    """One target's tree and the Beta posterior of the error rate in each of its leaves."""
    tree: object | None        # None: no structure learnt yet, one leaf for everything
    prior: tuple[float, float]
    errors: np.ndarray         # per tree node (leaves used): sum of the target over tests there
    counts: np.ndarray         # per tree node: number of tests there

    def leaves(self, X: np.ndarray) -> np.ndarray:
        if self.tree is None:
            return np.zeros(len(X), dtype=np.intp)
        # the fitted tree_ itself: the estimator's apply() re-validates its input on every call,
        # which cost more than the lookup; rows here are always float32 and C-contiguous
        return self.tree.tree_.apply(np.ascontiguousarray(X, dtype=np.float32))

    def add(self, X: np.ndarray, y: np.ndarray) -> None:
        leaves = self.leaves(X)
        np.add.at(self.errors, leaves, y)
        np.add.at(self.counts, leaves, 1.0)

    def mean(self, leaves: np.ndarray) -> np.ndarray:
        a, b = self.prior
        return (a + self.errors[leaves]) / (a + b + self.counts[leaves])

    def draw(self, leaves: np.ndarray, rng: np.random.Generator, n_draws: int) -> np.ndarray:
        """(n_draws, len(leaves)) error rates drawn from the leaves' posteriors."""
        a, b = self.prior
        used = np.unique(leaves)
        samples = rng.beta(a + self.errors[used], b + self.counts[used] - self.errors[used],
                           size=(n_draws, len(used)))
        return samples[:, np.searchsorted(used, leaves)]


class ErrorModel:
    """Per-target error trees over the tests seen so far."""

    def __init__(self, space: SceneSpace, rng: np.random.Generator, max_rows: int = 2000,
                 min_samples_leaf: int = 3, prior_strength: float = 2.0, refit_growth: float = 0.1):
        self.space, self.rng = space, rng
        self.encoder = SceneEncoder(space)
        self.max_rows, self.min_samples_leaf = max_rows, min_samples_leaf
        self.prior_strength, self.refit_growth = prior_strength, refit_growth
        self.weights = {f.name: f.weight for f in space.predicted}
        if not any(self.weights.values()):  # the judge then counts questions equally; so do we
            self.weights = dict.fromkeys(self.weights, 1.0)
        self.mode: str | None = None          # "features" or "fitness", from the first verdicts
        self._X = np.zeros((0, self.encoder.n_columns), dtype=np.float32)
        self._y: list[dict[str, float]] = []
        self._models: dict[str, _Leaves] = {}
        self._fitted_at = 0
        self._asked = np.zeros((0, 0), dtype=bool)

    def __len__(self) -> int:
        return len(self._y)

    @property
    def targets(self) -> list[str]:
        return list(self.weights) if self.mode == "features" else [FITNESS_TARGET]

    # ------------------------------------------------------------------ learning
    def observe(self, canonical_scenes: list[dict], targets: list[dict[str, float] | None]) -> None:
        kept = [(s, t) for s, t in zip(canonical_scenes, targets) if t is not None]
        if not kept:
            return
        if self.mode is None:
            self.mode = "fitness" if FITNESS_TARGET in kept[0][1] else "features"
        X = self.encoder.encode([s for s, _ in kept])
        asked = self._asked_of([s for s, _ in kept])
        self._X = np.concatenate([self._X, X])
        self._y += [t for _, t in kept]
        self._asked = asked if len(self._asked) == 0 else np.concatenate([self._asked, asked])
        if len(self) >= self._fitted_at * (1 + self.refit_growth) or not self._models:
            self._fit()
        else:
            for target, model in self._models.items():
                y = self._column(target, [t for _, t in kept])
                mask = ~np.isnan(y)
                model.add(X[mask], y[mask])

    def _column(self, target: str, rows: list[dict[str, float]]) -> np.ndarray:
        return np.array([row.get(target, np.nan) for row in rows], dtype=float)

    def _fit(self) -> None:
        X_all = self._X
        rows = np.arange(len(X_all))
        if len(rows) > self.max_rows:  # a uniform subsample keeps the error rates unbiased
            rows = np.sort(self.rng.choice(len(rows), self.max_rows, replace=False))
        self._models = {t: self._fit_target(t, X_all, rows) for t in self.targets}
        self._fitted_at = len(self)

    def _fit_target(self, target: str, X_all: np.ndarray, rows: np.ndarray) -> _Leaves:
        y_all = self._column(target, self._y)
        asked = ~np.isnan(y_all)
        fit_rows = rows[asked[rows]]
        y = y_all[fit_rows]
        base = (y.sum() + 0.5) / (len(y) + 1.0)  # the feature's overall error rate: the leaves' prior
        prior = (self.prior_strength * base, self.prior_strength * (1 - base))
        tree = None
        if len(y) >= 2 * self.min_samples_leaf and 0 < y.sum() < len(y):
            seed = int(self.rng.integers(2**31))
            if self.mode == "fitness":
                tree = DecisionTreeRegressor(min_samples_leaf=self.min_samples_leaf, random_state=seed)
            else:
                tree = DecisionTreeClassifier(min_samples_leaf=self.min_samples_leaf, random_state=seed)
            tree.fit(X_all[fit_rows], y)
        n_nodes = 1 if tree is None else tree.tree_.node_count
        model = _Leaves(tree, prior, np.zeros(n_nodes), np.zeros(n_nodes))
        model.add(X_all[asked], y_all[asked])  # every test counts in the leaves, not just the subsample
        return model

    # ------------------------------------------------------------------ prediction
    def expected_loss(self, canonical_scenes: list[dict]) -> np.ndarray:
        """Posterior mean of 1 - fitness for each scene."""
        return self._loss(canonical_scenes, lambda model, leaves: model.mean(leaves)[None, :])[0]

    def observed_loss(self) -> np.ndarray:
        """Posterior mean of 1 - fitness for each test observed, in order (no re-encoding)."""
        return self._loss_rows(self._X, self._asked, lambda model, leaves: model.mean(leaves)[None, :])[0]

    def sample_loss(self, canonical_scenes: list[dict], n_draws: int) -> np.ndarray:
        """(n_draws, n_scenes) plausible losses (Thompson samples, one model draw per row)."""
        return self._loss(canonical_scenes, lambda model, leaves: model.draw(leaves, self.rng, n_draws))

    def sample_rates(self, canonical_scenes: list[dict], n_draws: int) -> tuple[np.ndarray, np.ndarray]:
        """Thompson draws of every target's error probability, and the weights the judge gives it:
        ((n_draws, n_scenes, n_targets) rates, (n_scenes, n_targets) weights, 0 where not asked)."""
        X, asked = self.encoder.encode(canonical_scenes), self._asked_of(canonical_scenes)
        weights = np.array([self.weights.get(t, 1.0) for t in self.targets]) * asked
        if not self._models:
            return np.zeros((n_draws, len(X), len(self.targets))), weights
        rates = [self._models[t].draw(self._models[t].leaves(X), self.rng, n_draws) for t in self.targets]
        return np.stack(rates, axis=2), weights

    def _loss(self, canonical_scenes: list[dict], rates) -> np.ndarray:
        if not self._models or not canonical_scenes:
            return np.zeros((1, len(canonical_scenes)))
        return self._loss_rows(self.encoder.encode(canonical_scenes), self._asked_of(canonical_scenes), rates)

    def _asked_of(self, canonical_scenes: list[dict]) -> np.ndarray:
        """(scenes, targets): whether the target's question is asked of the scene."""
        if self.mode == "fitness":
            return np.ones((len(canonical_scenes), 1), dtype=bool)
        return np.array([[t in s for t in self.targets] for s in canonical_scenes],
                        dtype=bool).reshape(-1, len(self.targets))

    def _loss_rows(self, X: np.ndarray, asked: np.ndarray, rates) -> np.ndarray:
        if not self._models or len(X) == 0:
            return np.zeros((1, len(X)))
        weighted, total = 0.0, np.zeros(len(X))
        for j, target in enumerate(self.targets):
            model = self._models[target]
            weight = (self.weights.get(target, 1.0)) * asked[:, j]
            weighted = weighted + weight * rates(model, model.leaves(X))
            total += weight
        return weighted / np.where(total > 0, total, 1.0)
