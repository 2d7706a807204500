"""Retraining the reference ISU on its own scenes plus extra data (``reference train --extra``).

The base model's training and held-out features are kept beside its heads (``feature_bank``), so a
retrain embeds only the extra images and fits the heads again: the cost is the extra data's
features plus the fit. The retrained model is measured on the base model's own held-out scenes, and
its card compares every feature with the base model there.
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from .backbone import Backbone
from .feature_bank import FeatureSet, check_made_with, load_bank, load_feature_set, save_feature_set
from .heads import load_heads
from .model import backbone_of
from .training import accuracy, embed_images, fit_and_describe, write_model


@dataclass
class ExtraSet:
    """One dataset's images and their labels, as its reader gives them."""
    source: str                  # the dataset folder, named in the card and in errors
    images: list[Path]
    scenes: list[dict]           # canonical scenes, without the features the frame hides
    meta: dict = field(default_factory=dict)   # space, space_hash, renderer: what the images were made with
    left_out: int = 0            # labels left out: features the frames hide
    content_hash: str = ""       # the images and their labels (``extra_data.content_hash``)
    runs: list[dict] = field(default_factory=list)   # a focused dataset's runs: run, sut, threshold


def retrain_with_extra(space, base: Path, extra: list[ExtraSet], out: Path, renderer_version: str,
                       backbone: Backbone | None = None, cache_dir: Path | None = None, device: str = "auto") -> dict:
    """Fit the heads on ``base``'s training features plus ``extra``; write the model, its card (with the
    comparison against ``base`` on base's held-out scenes) and its features (so it can be a base too)."""
    start = time.time()
    train, held_out = load_bank(Path(base), space, renderer_version)
    for part in extra:
        check_made_with(part.meta, f"dataset {part.source}", space, train.meta["renderer"],
                        f"the base model's features (in {base}) with",
                        "render the dataset again with the current renderer")
    base_heads, base_meta = load_heads(Path(base))
    if base_meta.get("window_heads"):
        raise InputError(f"the model in {base} answers {', '.join(base_meta['window_heads'])} from window heads, "
                         "which --extra cannot retrain (it keeps whole-frame features only); train a new model with "
                         "`reference train --windows` on the scenes you would add, or use a base without windows")
    backbone = backbone or backbone_of(Path(base), base_meta, device)
    if backbone.name != train.meta["backbone"] or list(backbone.size) != list(train.meta["input_size"]):
        raise InputError(f"the features in {base} come from {train.meta['backbone']} at {train.meta['input_size']}, "
                         f"not {backbone.name} at {list(backbone.size)}")
    extra_X = [extra_features(backbone, part, cache_dir) for part in extra]
    embedded = time.time()
    combined = FeatureSet(np.concatenate([train.features, *extra_X]),
                          train.scenes + [scene for part in extra for scene in part.scenes], train.meta)
    heads, card = fit_and_describe(space, combined, held_out, train.meta["seed"])
    before = accuracy(space, base_heads, held_out.features, held_out.scenes)["per_feature"]
    card.update(renderer=train.meta["renderer"], base=str(Path(base).resolve()), base_training_scenes=len(train.scenes),
                extra=[{"dataset": part.source, "content_hash": part.content_hash, "images": len(part.images),
                        "labels_left_out": part.left_out, "runs": part.runs} for part in extra],
                reproduce=reproduce(space, base, extra, out),
                comparison=compare(before, card["held_out"]["per_feature"]),
                embed_seconds=round(embedded - start, 1), fit_seconds=round(time.time() - embedded, 1),
                device=backbone.device.describe(), base_clip_sigma=base_meta.get("clip_sigma"))
    card["change"] = change_summary(card["comparison"])
    write_model(Path(out), heads, card, [combined, held_out], markdown=retrained_markdown, backbone=backbone)
    return card


def extra_features(backbone: Backbone, part: ExtraSet, cache_dir: Path | None) -> np.ndarray:
    """The images' features, kept in ``cache_dir`` under a hash of the images and the backbone (a retrain
    of the same dataset embeds nothing)."""
    digest = hashlib.sha256(f"{backbone.name}{list(backbone.size)}".encode())
    for image in part.images:
        digest.update(Path(image).read_bytes())
    cached = cache_dir / f"{digest.hexdigest()[:24]}.npz" if cache_dir else None
    if cached and cached.is_file():
        return load_feature_set(cached).features
    X = embed_images(backbone, list(part.images))
    if cached:
        cached.parent.mkdir(parents=True, exist_ok=True)
        save_feature_set(cached, X, part.scenes, {"dataset": part.source})
    return X


def compare(before: dict, after: dict) -> dict:
    """{feature: base accuracy, retrained accuracy, change, n} on the same held-out scenes."""
    return {name: {"base": before[name]["accuracy"], "retrained": after[name]["accuracy"],
                   "change": after[name]["accuracy"] - before[name]["accuracy"], "n": after[name]["n"]}
            for name in after if name in before}


def change_summary(comparison: dict) -> dict:
    changes = {name: row["change"] for name, row in comparison.items()}
    worst = min(changes, key=changes.get)
    return {"worst_feature": worst, "worst": changes[worst], "mean": float(np.mean(list(changes.values())))}


def reproduce(space, base: Path, extra: list[ExtraSet], out: Path) -> str:
    """The command that made this model, with absolute paths: it runs as printed, from any folder."""
    import shlex
    words = ["isu-validate", "reference", "train", "--extra", *(part.source for part in extra),
             "--base", str(Path(base).resolve()), "--space", _space_spec(space), "--out", str(Path(out).resolve())]
    return shlex.join(words)


def _space_spec(space) -> str:
    """The space as ``--space`` names it: its shipped name, else the file it came from."""
    from ..space import SpaceError, load_space
    try:
        return space.name if load_space(space.name).hash == space.hash else space.source
    except SpaceError:
        return space.source


def _points(change: float) -> str:
    """An accuracy change in percentage points, as the README and ``bench augment`` speak of them."""
    return f"{100 * change:+.1f} pt"


def _runs(runs: list[dict]) -> str:
    if not runs:
        return "not focused on runs"
    return "drawn near the tests of " + "; ".join(
        f"`{r['run']}`" + (f" (SUT `{r['sut']}`, failing below threshold {r['threshold']})" if r.get("sut") else "")
        for r in runs)


def _fit_change(card: dict) -> list[str]:
    """A base fitted another way (before the heads clipped their features): its share of every change is named."""
    now, base = card.get("heads", {}).get("clip_sigma"), card.get("base_clip_sigma")
    if now == base:
        return []
    return [f"- Heads: features clipped at +-{now:g} training deviations; the base's were read "
            + (f"clipped at +-{base:g}" if base is not None else "unclipped")
            + ", so part of every change below is the fit, not the extra data"]


def retrained_markdown(card: dict) -> str:
    lines = ["# Reference ISU retrained with extra data", "",
             f"- Base: `{card['base']}`: {card['base_training_scenes']} training scenes, seed {card['seed']}, "
             f"render preset `{card['render_preset']}`, renderer `{card['renderer']}` (its stored features: "
             "nothing rendered again)",
             *(f"- Extra: `{row['dataset']}` (content hash {row.get('content_hash', '?')}): {row['images']} images "
               f"({row['labels_left_out']} labels left out: features their frames hide); {_runs(row.get('runs'))}"
               for row in card["extra"]),
             f"- Held-out set: the base model's {card['held_out_scenes']} held-out scenes",
             f"- Backbone: {card['backbone']}, input {card['input_size'][0]}x{card['input_size'][1]}, "
             f"run on {card['device']}",
             f"- Cost: {card['embed_seconds']} s embedding the extra images, {card['fit_seconds']} s fitting",
             *_fit_change(card),
             f"- Reproduce: `{card['reproduce']}`",
             "", "## Held-out accuracy against the base model (same scenes)", "",
             "| feature | base | retrained | change | n |", "|---|---|---|---|---|"]
    for name, row in card["comparison"].items():
        lines.append(f"| {name} | {100 * row['base']:.1f}% | {100 * row['retrained']:.1f}% | {_points(row['change'])} "
                     f"| {row['n']} |")
    summary = card["change"]
    lines += ["", f"Worst change {_points(summary['worst'])} ({summary['worst_feature']}), "
                  f"mean change {_points(summary['mean'])} (percentage points of held-out accuracy)."]
    return "\n".join(lines) + "\n"
