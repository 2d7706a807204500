"""The reference caption of a scene, built from its active features.

Templates live in ``data/captions/<name>.toml`` (format described in
``data/captions/isu-paper.toml``); a space's default is the one named after it, and
another (``isu-paper-compact``, or any file) can be chosen.  A space without a template file falls back to
its features' ``caption`` fragments: "The scene shows a male driver, who looks happy, ...".
Inactive features never reach the caption.
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Collection, Mapping

from ..paths import data_dir
from ..space import SceneSpace, SpaceError
from ..space.conditions import Condition, parse_condition

_SLOT = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")


@dataclass(frozen=True)
class Sentence:
    text: str
    when: Condition | None
    slots: tuple[str, ...]


@dataclass(frozen=True)
class CaptionTemplate:
    sentences: tuple[Sentence, ...]
    phrases: Mapping[str, Mapping[str, str]]

    def fill(self, space: SceneSpace, scene: Mapping[str, Any], hidden: Collection[str] = ()) -> str:
        """The caption; ``hidden`` features (occluded in the frame) silence every sentence naming them."""
        canonical = space.canonical(scene)
        out = []
        for sentence in self.sentences:
            if any(name not in canonical for name in sentence.slots):
                continue
            if hidden and set(hidden) & set(sentence.slots + (sentence.when.features if sentence.when else ())):
                continue
            if sentence.when is not None and not sentence.when.matches(canonical):
                continue
            out.append(_SLOT.sub(lambda m: self.phrase(m.group(1), canonical[m.group(1)]), sentence.text))
        return tidy(" ".join(out))

    def phrase(self, feature: str, value: Any) -> str:
        table = self.phrases.get(feature, {})
        key = str(value)
        if key in table:
            return table[key]
        if "*" in table:
            return table["*"]
        return (key.lower().replace("_", "-") if isinstance(value, str)
                else f"{value:g}" if isinstance(value, float) else key)


def tidy(text: str) -> str:
    """Collapse the gaps an empty phrase leaves ("car  ." -> "car.")."""
    text = re.sub(r"\s+", " ", text)
    text = re.sub(r"\b([Aa]) (?=[aeiouAEIOU])", r"\1n ", text)  # "a anthracite suitcase" -> "an ..."
    return re.sub(r"\s+([.,;:!?])", r"\1", text).strip()


def parse_template(raw: Mapping[str, Any], space: SceneSpace, where: str) -> CaptionTemplate:
    sentences = []
    for i, spec in enumerate(raw.get("sentences", [])):
        here = f"{where}: sentence {i + 1}"
        if not isinstance(spec, Mapping) or not isinstance(spec.get("text"), str):
            raise SpaceError(f"{here}: needs a `text` string")
        slots = tuple(_SLOT.findall(spec["text"]))
        when = parse_condition(spec["when"], f"{here} when") if "when" in spec else None
        for name in slots + (when.features if when else ()):
            if name not in space.features:
                raise SpaceError(f"{here}: names unknown feature {name!r} of space {space.name!r}")
        sentences.append(Sentence(spec["text"], when, slots))
    if not sentences:
        raise SpaceError(f"{where}: no [[sentences]]; a caption template needs at least one")
    phrases = raw.get("phrases", {})
    for name, table in phrases.items():
        if name not in space.features or not isinstance(table, Mapping):
            raise SpaceError(f"{where}: [phrases.{name}] must be a table for a feature of space {space.name!r}")
    return CaptionTemplate(tuple(sentences), {k: {str(a): str(b) for a, b in v.items()} for k, v in phrases.items()})


def fragments_template(space: SceneSpace) -> CaptionTemplate:
    """Fallback: one clause per feature with a ``caption`` fragment (YES/NO features only when YES)."""
    sentences = []
    for name, feature in space.features.items():
        if not feature.caption:
            continue
        fragment = feature.caption.replace("{value}", "{" + name + "}")
        when = None
        if set(feature.values) == {"YES", "NO"}:
            when = parse_condition({name: "YES"}, name)
        elif "{" + name + "}" not in fragment:
            continue  # a fixed phrase for a many-valued feature would say nothing about its value
        sentences.append(Sentence(fragment + ",", when, (name,)))
    if not sentences:
        raise SpaceError(f"space {space.name!r} has no caption template (data/captions/{space.name}.toml) "
                         "and no feature has a `caption` fragment; write one of them")
    head = Sentence("The scene shows", None, ())
    return CaptionTemplate((head, *sentences), {})


@lru_cache(maxsize=16)
def _template_for(space_id: int, space: SceneSpace, template: str | None) -> CaptionTemplate:
    path = template_path(space, template)
    if path is None:
        return fragments_template(space)
    try:
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SpaceError(f"{path}: not valid TOML: {exc}") from None
    meant_for = raw.get("space", space.name)
    if meant_for != space.name:
        raise SpaceError(f"{path}: a caption template for space {meant_for!r}, not for {space.name!r}; "
                         f"choose a template written for {space.name!r}")
    return parse_template(raw, space, str(path))


def template_path(space: SceneSpace, template: str | Path | None = None) -> Path | None:
    """The template file: ``template`` as a name in data/captions (``isu-paper-compact``) or a
    .toml path; by default data/captions/<space name>.toml, or None (use the fragments)."""
    folder = data_dir() / "captions"
    if template is None:
        path = folder / f"{space.name}.toml"
        return path if path.is_file() else None
    text = str(template)
    path = Path(text) if text.endswith(".toml") or "/" in text else folder / f"{text}.toml"
    if not path.is_file():
        shipped = ", ".join(sorted(p.stem for p in folder.glob("*.toml")))
        raise SpaceError(f"caption template {text!r} not found (looked for {path}); give a .toml file "
                         f"or a shipped name: {shipped}")
    return path


def template_for(space: SceneSpace, template: str | Path | None = None) -> CaptionTemplate:
    return _template_for(id(space), space, None if template is None else str(template))


def reference_caption(space: SceneSpace, scene: Mapping[str, Any], template: str | Path | None = None,
                      hidden: Collection[str] = ()) -> str:
    """The caption the scene's truth reads as, from ``template`` (see ``template_path``), saying
    nothing about the ``hidden`` features."""
    text = template_for(space, template).fill(space, scene, hidden)
    return re.sub(r",\s*$", ".", text) if not text.endswith(".") else text
