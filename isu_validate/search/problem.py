"""The scene space as a pymoo mixed-variable problem (two objectives, evaluated outside pymoo)."""
from __future__ import annotations

from typing import Any, Mapping

from pymoo.core.problem import Problem
from pymoo.core.variable import Choice, Integer, Real

from ..space import SceneSpace

N_OBJECTIVES = 2  # minimise the SUT's response fitness, maximise diversity (as -f_div)


def _variable(feature):
    if feature.type == "categorical":
        return Choice(options=list(feature.values))
    if feature.type == "ordinal":
        return Integer(bounds=(0, len(feature.values) - 1))
    if feature.type == "integer":
        return Integer(bounds=(int(feature.low), int(feature.high)))
    return Real(bounds=(feature.low, feature.high))


class SceneProblem(Problem):
    """One pymoo variable per feature whose domain has more than one value.

    Single-valued features are constants, not variables: pymoo's polynomial mutation
    divides by the bound width, and a constant has nothing to search anyway.
    """

    def __init__(self, space: SceneSpace):
        self.space = space
        self.constants = {n: (f.values[0] if f.discrete else f.low)
                          for n, f in space.features.items() if f.span == 0}
        variables = {n: _variable(f) for n, f in space.features.items() if n not in self.constants}
        super().__init__(vars=variables, n_obj=N_OBJECTIVES)

    def to_scene(self, x: Mapping[str, Any]) -> dict:
        scene = {}
        for name, feature in self.space.features.items():
            if name in self.constants:
                scene[name] = self.constants[name]
            elif feature.type == "ordinal":
                scene[name] = feature.values[int(round(float(x[name])))]
            elif feature.type == "integer":
                scene[name] = int(round(float(x[name])))
            elif feature.type == "continuous":
                scene[name] = float(x[name])
            else:
                scene[name] = str(x[name])
        return scene

    def to_x(self, scene: Mapping[str, Any]) -> dict:
        x = {}
        for name in self.vars:
            feature = self.space.features[name]
            x[name] = feature.values.index(scene[name]) if feature.type == "ordinal" else scene[name]
        return x

    def _evaluate(self, X, out, *args, **kwargs):
        raise RuntimeError("scenes are evaluated by the run loop (render + SUT), not by pymoo")
