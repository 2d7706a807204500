"""Load and validate scene-space TOML files."""
from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np

from ..paths import resolve_rig
from .conditions import parse_condition
from .errors import SpaceError
from .features import parse_feature
from .space import Constraint, SceneSpace
from ..tomlfile import read_toml

DEFAULT_SPACE = "isu-paper"
_MAX_ENUMERATION = 200_000


def load_space(name_or_path: str | os.PathLike = DEFAULT_SPACE) -> SceneSpace:
    """A space by shipped name (``isu-paper``) or file path; raises SpaceError naming the problem.

        space = load_space("isu-paper")
        scene = space.sample(np.random.default_rng(0))[0]   # a valid random scene
        space.questions(scene)                                # what the SUT is asked about it
    """
    try:
        path = resolve_rig("spaces", name_or_path)
    except FileNotFoundError as exc:
        raise SpaceError(str(exc)) from None
    return space_from_dict(_read_extended(path, ()), where=str(path))


def _read_extended(path: Path, seen: tuple[Path, ...]) -> dict:
    """A space file's tables; with ``extends = "BASE"`` the base space's features come first, then this
    file's (which may add features, never redefine one), and the constraints of both apply."""
    raw = read_toml(path, SpaceError, "scene space")
    base_name = raw.pop("extends", None)
    if base_name is None:
        return raw
    if not isinstance(base_name, str):
        raise SpaceError(f"{path}: extends must name one space (a shipped name or a .toml path), not {base_name!r}")
    try:
        base_path = resolve_rig("spaces", base_name)
    except FileNotFoundError as exc:
        raise SpaceError(f"{path}: extends {base_name!r}: {exc}") from None
    if base_path.resolve() in seen or base_path.resolve() == path.resolve():
        raise SpaceError(f"{path}: extends {base_name!r}, which extends it back; remove one of the two")
    base = _read_extended(base_path, (*seen, path.resolve()))
    own = raw.get("features", {})
    again = sorted(set(own) & set(base.get("features", {})))
    if again:
        raise SpaceError(f"{path}: redefines {', '.join(again)} of the space it extends ({base_name}); "
                         "give the new feature another name, or copy the base file and change it there")
    merged = {**base, **raw, "features": {**base.get("features", {}), **own},
              "constraints": [*base.get("constraints", []), *raw.get("constraints", [])]}
    if "prompt_rules" not in raw and "prompt_rules" in base:
        merged["prompt_rules"] = base["prompt_rules"]
    return merged


def space_from_dict(raw: dict, where: str = "<space>") -> SceneSpace:
    features_raw = raw.get("features")
    if not isinstance(features_raw, dict) or not features_raw:
        raise SpaceError(f"{where}: no [features.*] tables; a space needs at least one feature")
    features = []
    for name, spec in features_raw.items():
        feature = parse_feature(name, spec, where)
        _check_condition_names(feature.active_when, [f.name for f in features], set(features_raw),
                               f"{where}: feature {name!r} active_when")
        features.append(feature)
    space = SceneSpace(
        name=str(raw.get("name", Path(where).stem)),
        features=features,
        constraints=_parse_constraints(raw.get("constraints", []), features_raw, where),
        prompt_rules=raw.get("prompt_rules", ()),
        description=str(raw.get("description", "")),
        source=where,
    )
    _check_condition_values(space, where)
    _check_satisfiable(space, where)
    return space


def _check_condition_names(condition, earlier: list[str], known: set[str], where: str) -> None:
    if condition is None:
        return
    for name in condition.features:
        if name not in known:
            raise SpaceError(f"{where}: names unknown feature {name!r}")
        if name not in earlier:
            raise SpaceError(f"{where}: names {name!r}, which must be declared before the feature that depends on it")


def _parse_constraints(raw, features_raw: dict, where: str) -> list[Constraint]:
    if not isinstance(raw, list):
        raise SpaceError(f"{where}: `constraints` must be an array of tables ([[constraints]])")
    out = []
    for i, spec in enumerate(raw):
        here = f"{where}: constraint {i + 1} ({spec.get('name', 'unnamed') if isinstance(spec, dict) else spec!r})"
        if not isinstance(spec, dict) or "if" not in spec or "then" not in spec:
            raise SpaceError(f"{here}: needs an `if` and a `then` condition")
        if_, then = parse_condition(spec["if"], f"{here} if"), parse_condition(spec["then"], f"{here} then")
        for name in if_.features + then.features:
            if name not in features_raw:
                raise SpaceError(f"{here}: names unknown feature {name!r}")
        out.append(Constraint(str(spec.get("name", f"constraint {i + 1}")), if_, then))
    return out


def _check_condition_values(space: SceneSpace, where: str) -> None:
    """A condition listing a value the feature can never take is a typo, not a rule."""
    conditions = [(f"feature {f.name!r} active_when", f.active_when) for f in space.features.values() if f.active_when]
    conditions += [(f"constraint {c.name!r}", cond) for c in space.constraints for cond in (c.if_, c.then)]
    for label, cond in conditions:
        for term in cond.terms:
            feature = space.features[term.feature]
            if not feature.discrete:
                continue
            for value in (term.inside or ()) + (term.outside or ()):
                if value not in feature.values:
                    raise SpaceError(f"{where}: {label} uses value {value!r} that feature {term.feature!r} "
                                     f"never takes (its values: {list(feature.values)})")


def _check_satisfiable(space: SceneSpace, where: str) -> None:
    """Find one valid scene: exhaustively over the features the rules touch when that is small,
    otherwise by sampling and repair."""
    if not space.constraints:
        return
    involved = {t.feature for c in space.constraints for cond in (c.if_, c.then) for t in cond.terms}
    involved |= {t.feature for f in space.features.values() if f.active_when for t in f.active_when.terms}
    rng = np.random.default_rng(0)
    base = {n: space.random_value(f, rng) for n, f in space.features.items()}
    names = sorted(involved)
    domains = [_probe_values(space, n) for n in names]
    if np.prod([len(d) for d in domains], dtype=float) <= _MAX_ENUMERATION:
        for combo in itertools.product(*domains):
            if space.is_valid(dict(base, **dict(zip(names, combo)))):
                return
    else:
        try:
            space.sample(rng, 1)
            return
        except SpaceError:
            pass
    rules = "; ".join(c.name for c in space.constraints)
    raise SpaceError(f"{where}: the constraints contradict each other and leave no valid scene ({rules})")


def _probe_values(space: SceneSpace, name: str) -> list:
    feature = space.features[name]
    if feature.discrete:
        return list(feature.values)
    points = {feature.low, feature.high, (feature.low + feature.high) / 2}
    for c in space.constraints:
        for cond in (c.if_, c.then):
            for t in cond.terms:
                if t.feature == name:
                    points |= {b for b in (t.low, t.high) if b is not None and feature.low <= b <= feature.high}
    return sorted(int(round(p)) if feature.type == "integer" else p for p in points)
