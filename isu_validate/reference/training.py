"""Training the reference ISU on scenes the project renders itself.

The training set is balanced per predicted feature (each answer equally likely where
the scene allows it), rendered with the project's renderer, and committed image by
image, so an interrupted ``reference train`` resumes without re-rendering.  Accuracy
is measured on a separately seeded held-out set and written to a model card as it is;
the held-out scenes (or their first N) may also be rendered at other presets, to show
how the model does on images it was not trained on.
"""
from __future__ import annotations

import hashlib
import json
import shlex
import time
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from ..progress import Progress, tracked
from ..space import SceneSpace
from .backbone import Backbone, read_rgb
from .feature_bank import FILES, FeatureSet, save_bank
from .fine_tune import WEIGHTS_FILE, FineTune, fine_tune_backbone, save_tuned
from .heads import CLIP_SIGMA, REGULARISATION_C, Head, fit_head, save_heads
from .detector import FrameDetector
from .stacking import FOLDS
from .windows import WindowSettings, calibration_folds, fit_window_heads, frame_probabilities, save_held_out
from ..errors import InputError


@dataclass
class Example:
    image: Path
    scene: dict      # canonical


def balanced_scenes(space: SceneSpace, n: int, rng: np.random.Generator, pool_factor: int = 6) -> list[dict]:
    """Valid scenes in which each predicted feature's answers are about equally frequent
    (uniform values would make, e.g., 'no phone in hand' 1 in 11) wherever the rest of the
    scene leaves the feature free to take any of them.

    Each candidate draws every predicted feature's answer uniformly, then is repaired; ``n``
    scenes are then chosen greedily from ``pool_factor * n`` candidates, each time the one that
    best lifts the answers seen least so far.  A scene counts towards a feature's balance only
    where the constraints would allow every answer of it: balancing, say, the phone on the
    co-driver seat over all scenes would need it on every seat free of a child seat, and
    then together with the can and the bottle (a head could not tell them apart: they were
    once learnt as one 'something on the seat' head with identical weights)."""
    pool = [space.repair(_uniform_answers(space, scene, rng), rng) for scene in space.sample(rng, n * pool_factor)]
    columns = [(f.name, answer) for f in space.predicted for answer in sorted({f.truth(v) for v in f.values})]
    column_of = {key: j for j, key in enumerate(columns)}
    feature_of = np.array([space.names.index(name) for name, _ in columns])
    target = np.array([1.0 / sum(1 for other, _ in columns if other == name) for name, _ in columns])
    onehot = np.zeros((len(pool), len(columns)))
    for i, scene in enumerate(pool):
        canonical = space.canonical(scene)
        for feature in space.predicted:
            if feature.name in canonical and _free(space, scene, feature):
                onehot[i, column_of[(feature.name, feature.truth(canonical[feature.name]))]] = 1.0
    counts, totals = np.zeros(len(columns)), np.zeros(len(space.names))
    jitter = rng.uniform(0, 1e-6, len(pool))   # breaks ties without favouring pool order
    chosen = []
    for _ in range(n):
        share = counts / np.maximum(totals[feature_of], 1.0)
        score = onehot @ (target - share) + jitter
        score[chosen] = -np.inf
        pick = int(np.argmax(score))
        chosen.append(pick)
        counts += onehot[pick]
        np.add.at(totals, feature_of, onehot[pick])
    return [pool[i] for i in chosen]


def _free(space: SceneSpace, scene: dict, feature) -> bool:
    """Whether the constraints let ``feature`` give every one of its answers, the rest of the scene as it is."""
    allowed = {feature.truth(v) for v in feature.values if space.is_valid({**scene, feature.name: v})}
    return allowed == {feature.truth(v) for v in feature.values}


def _uniform_answers(space: SceneSpace, scene: dict, rng: np.random.Generator) -> dict:
    """The scene with each predicted feature set to a uniformly drawn answer (then a value giving it)."""
    for feature in space.predicted:
        by_answer = defaultdict(list)
        for value in feature.values:
            by_answer[feature.truth(value)].append(value)
        answers = sorted(by_answer)
        values = by_answer[answers[int(rng.integers(len(answers)))]]
        scene[feature.name] = values[int(rng.integers(len(values)))]
    return scene


def render_examples(space: SceneSpace, scenes: list[dict], renderer, folder: Path, label: str) -> list[Example]:
    """Render each scene once into ``folder``; images already there (same scene, same renderer
    settings as far as the renderer's cache key tells) are kept."""
    folder.mkdir(parents=True, exist_ok=True)
    progress = Progress(len(scenes), label=f"rendering {label}", verdicts=False)
    examples = []
    for i, scene in enumerate(scenes):
        canonical = space.canonical(scene)
        image, meta = folder / f"{i:05d}.png", folder / f"{i:05d}.json"
        key = renderer.cache_key(canonical) if hasattr(renderer, "cache_key") else None
        wanted = {"scene": canonical, "render_key": key}
        if not (image.exists() and meta.exists() and json.loads(meta.read_text()) == wanted):
            renderer.render(canonical, image)
            meta.write_text(json.dumps(wanted))
        examples.append(Example(image, visible_label(canonical, image)))
        progress.update()
    progress.close()
    return examples


def visible_label(canonical: dict, image: Path) -> dict:
    """The scene as a training label, less the features its render hid from the camera (the render label's
    ``occluded``: below the space's ``min_visible``), as the judge leaves them out of a verdict: a phone at the
    far ear, out of the camera's sight, is no example of a phone. A render without a label keeps every feature."""
    from ..render.outputs import read_label
    from ..render.visibility import without_hidden

    label = read_label(image)
    return without_hidden(canonical, label) if label is not None else canonical


def hidden_counts(space: SceneSpace, scenes: list[dict], examples: list[Example]) -> dict[str, int]:
    """How many of the scenes' features their examples leave out as hidden from the camera."""
    counts: dict[str, int] = defaultdict(int)
    for scene, example in zip(scenes, examples, strict=True):
        for name in space.canonical(scene).keys() - example.scene.keys():
            counts[name] += 1
    return dict(sorted(counts.items()))


def embed(backbone: Backbone, examples: list[Example]) -> np.ndarray:
    return embed_images(backbone, [e.image for e in examples])


def embed_images(backbone: Backbone, images: list[Path], chunk: int = 64) -> np.ndarray:
    """Features of image files, read a chunk at a time (a large set never sits in memory whole)."""
    parts = [backbone.features([read_rgb(path) for path in images[i:i + chunk]])
             for i in range(0, len(images), chunk)]
    return np.concatenate(parts) if parts else np.zeros((0, backbone.dim), np.float32)


def fit_heads(space: SceneSpace, X: np.ndarray, scenes: list[dict], seed: int) -> list[Head]:
    """One head per predicted feature, on the rows whose scene has it (a scene's label)."""
    heads = []
    for feature in space.predicted:
        rows = [i for i, scene in enumerate(scenes) if feature.name in scene]
        if not rows:
            raise InputError(f"no training scene has feature {feature.name!r} active; use a larger --n")
        labels = [feature.truth(scenes[i][feature.name]) for i in rows]
        heads.append(fit_head(feature.name, X[rows], labels, seed=seed))
    return heads


def accuracy(space: SceneSpace, heads: list[Head], X: np.ndarray, scenes: list[dict]) -> dict:
    """Per-feature held-out accuracy, overall and split by external light level."""
    answers = [{} for _ in scenes]
    for head in heads:
        rows = [i for i, scene in enumerate(scenes) if head.feature in scene]
        for i, answer in zip(rows, head.predict(X[rows]) if rows else [], strict=True):
            answers[i][head.feature] = answer
    return answer_accuracy(space, answers, scenes)


def answer_accuracy(space: SceneSpace, answers: list[dict[str, str]], scenes: list[dict]) -> dict:
    """Per-feature accuracy of answers given per scene (a feature a scene lacks is not asked), overall and split
    by external light level."""
    by_light: dict[str, dict[str, list[bool]]] = defaultdict(lambda: defaultdict(list))
    overall: dict[str, list[bool]] = defaultdict(list)
    for said, scene in zip(answers, scenes, strict=True):
        for name, answer in said.items():
            if name not in scene:
                continue
            correct = answer == space.features[name].truth(scene[name])
            overall[name].append(correct)
            by_light[scene.get("external_light", "-")][name].append(correct)
    def summarise(d):   # in the space's order of features, as the heads are
        return {k: {"accuracy": float(np.mean(d[k])), "n": len(d[k])} for k in space.features if k in d}
    return {"per_feature": summarise(overall),
            "by_external_light": {light: summarise(d) for light, d in sorted(by_light.items())}}


def train_reference(space: SceneSpace, renderer, out: Path, workdir: Path, n_train: int, n_test: int,
                    seed: int, preset: str, backbone: Backbone | None = None,
                    other_presets: Mapping[str, int] | None = None,
                    renderer_for: Callable[[str], object] | None = None, renderer_version: str = "",
                    device: str = "auto", variety: dict | None = None, fine_tune: FineTune | None = None,
                    windows: WindowSettings | None = None, rigs: Mapping[str, str] | None = None,
                    detector: FrameDetector | None = None) -> dict:
    """Render, embed, fit and write the heads, the model card and the features of both sets (so that
    ``reference train --extra`` never renders them again). ``other_presets`` maps a preset name to how
    many of the held-out scenes to render at it as well (``renderer_for(name)`` opens a renderer for
    it, closed here). ``device``: where the backbone runs (``devices.py``), named in the card. ``variety``:
    the camera jitter and sensor effects the renderers apply (``render.variety.Variety.describe()``), recorded
    in the card and the stored features; {} or None for the camera file's frames. ``fine_tune``: train the
    backbone's last blocks on the training renders first (``fine_tune.py``; a checkpoint in ``workdir`` resumes it).
    ``windows``: fit window heads for these yes/no features too (``windows.py``), which then answer them;
    ``detector``: stack each with a photo-trained detector's score (``detector.py``). ``rigs``: the camera and cabin
    the renderer was opened with, as the command named them (the card's reproduce line)."""
    start = time.time()
    train_scenes = balanced_scenes(space, n_train, np.random.default_rng(seed))
    test_scenes = balanced_scenes(space, n_test, np.random.default_rng(seed + 10_000))
    train = render_examples(space, train_scenes, renderer, workdir / "train", "training set")
    test = render_examples(space, test_scenes, renderer, workdir / "held-out", "held-out set")
    others = {name: _render_at(name, space, test_scenes[:n], renderer_for, workdir)
              for name, n in (other_presets or {}).items() if name != preset}
    backbone = backbone or Backbone(device=device)
    tuning = _fine_tune(space, backbone, train, fine_tune, workdir) if fine_tune else None
    made_with = {"space": space.name, "space_hash": space.hash, "renderer": renderer_version, "preset": preset,
                 "backbone": backbone.name, "input_size": list(backbone.size), "seed": seed,
                 **({"variety": variety} if variety else {})}
    bank = [FeatureSet(embed(backbone, part), [e.scene for e in part], dict(made_with, scenes_seed=scenes_seed))
            for part, scenes_seed in ((train, seed), (test, seed + 10_000))]
    heads, card = fit_and_describe(space, bank[0], bank[1], seed, {
        name: (embed(backbone, examples), [e.scene for e in examples]) for name, examples in others.items()})
    card["hidden_from_camera"] = {"training": hidden_counts(space, train_scenes, train),
                                  "held_out": hidden_counts(space, test_scenes, test)}
    window_heads, window_held_out = (_fit_windows(space, windows, backbone, train, {preset: test, **others}, seed,
                                                  card, detector) if windows else ([], None))
    card.update({"render_preset": preset, "renderer": renderer_version, "device": backbone.device.describe(),
                 "train_seconds": round(time.time() - start, 1), **({"variety": variety} if variety else {}),
                 **({"fine_tune": tuning} if tuning else {}), **({"rigs": dict(rigs)} if rigs else {})})
    write_model(out, heads, card, bank, backbone=backbone, window_heads=window_heads, window_held_out=window_held_out,
                detector=detector)
    return card


def _fit_windows(space: SceneSpace, settings: WindowSettings, backbone: Backbone, train: list[Example],
                 held_out: dict[str, list[Example]], seed: int, card: dict, detector: FrameDetector | None = None
                 ) -> tuple[list[Head], list[dict]]:
    """Fit the window heads; the card's figures for their features (training, held-out at every preset) become
    theirs, the whole-frame heads' kept beside them under ``windows``. Returns the heads and their answers on the
    held-out scenes of the training preset (``windows.save_held_out``)."""
    from ..render.outputs import read_label

    started = time.time()
    labels = [read_label(e.image) for e in train]
    plan = calibration_folds(labels, seed)
    heads, calibration, counts, training_read = fit_window_heads(
        space, settings, backbone, [e.image for e in train], [e.scene for e in train], labels, seed, detector, plan)
    whole = card["held_out_by_preset"]
    card["windows"] = {**settings.describe(), "calibration": {n: c.describe() for n, c in calibration.items()},
                       "calibration_folds": plan.describe(),
                       **({"detector": detector.describe()} if detector else {}),
                       "training_windows": counts,
                       "whole_frame_held_out": {n: whole[card["render_preset"]]["per_feature"].get(n)
                                                for n in settings.features}}
    card["training"].update(answer_accuracy(space, _answers(training_read), [e.scene for e in train])["per_feature"])
    read_at = {}
    for preset, examples in held_out.items():
        figures, read_at[preset] = _window_accuracy(space, settings, heads, calibration, backbone, examples, detector)
        whole[preset]["per_feature"].update(figures["per_feature"])
        for light, by_feature in figures["by_external_light"].items():
            whole[preset]["by_external_light"].setdefault(light, {}).update(by_feature)
    card["windows"]["seconds"] = round(time.time() - started, 1)
    return heads, read_at[card["render_preset"]]


def _window_accuracy(space: SceneSpace, settings: WindowSettings, heads: list[Head], calibration: dict,
                     backbone: Backbone, examples: list[Example], detector: FrameDetector | None = None
                     ) -> tuple[dict, list[dict]]:
    """(the window heads' accuracy on ``examples``, their class probabilities per example: {} where not asked)."""
    read = []
    for example in tracked(examples, "window heads: held-out frames"):
        asked = [h for h in heads if h.feature in example.scene]
        rgb = read_rgb(example.image) if asked else None
        seen = detector.log_odds(rgb, [h.feature for h in asked]) if detector and asked else None
        read.append(frame_probabilities(asked, calibration, settings.maps(backbone, rgb), seen) if asked else {})
    return answer_accuracy(space, _answers(read), [e.scene for e in examples]), read


def _answers(read: list[dict[str, dict[str, float]]]) -> list[dict[str, str]]:
    """Each frame's most probable class per feature."""
    return [{n: max(p, key=p.get) for n, p in probabilities.items()} for probabilities in read]


def _fine_tune(space: SceneSpace, backbone: Backbone, train: list[Example], settings: FineTune, workdir: Path) -> dict:
    """Tune ``backbone`` on the training renders; the checkpoint is named by the settings and the training set, so
    another set or other settings in the same workdir start afresh."""
    scenes = [e.scene for e in train]
    key = hashlib.sha256(json.dumps([settings.key, list(backbone.size), scenes], sort_keys=True).encode())
    started = time.time()
    card = fine_tune_backbone(backbone, [e.image for e in train], scenes, space, settings,
                              checkpoint=workdir / f"fine-tune-{key.hexdigest()[:16]}.pt")
    return {**card, "seconds": round(time.time() - started, 1)}


def fit_and_describe(space: SceneSpace, train: FeatureSet, held_out: FeatureSet, seed: int,
                     others: Mapping[str, tuple[np.ndarray, list[dict]]] | None = None) -> tuple[list[Head], dict]:
    """Fit the heads on ``train``; the card's accuracies on ``held_out`` (and on ``others``: the held-out
    scenes rendered at other presets, {preset: (features, scenes)})."""
    preset = held_out.meta["preset"]
    heads = fit_heads(space, train.features, train.scenes, seed)
    by_preset = {preset: accuracy(space, heads, held_out.features, held_out.scenes)}
    by_preset.update({name: accuracy(space, heads, X, scenes) for name, (X, scenes) in (others or {}).items()})
    card = {"backbone": train.meta["backbone"], "input_size": train.meta["input_size"], "space": space.name,
            "space_hash": space.hash, "training_scenes": len(train.scenes), "held_out_scenes": len(held_out.scenes),
            "seed": seed, "render_preset": preset, "held_out": by_preset[preset], "held_out_by_preset": by_preset,
            "held_out_scenes_by_preset": {name: len(scenes) for name, (_, scenes) in
                                          {preset: (None, held_out.scenes), **(others or {})}.items()},
            "training": accuracy(space, heads, train.features, train.scenes)["per_feature"],
            "heads": {"C": REGULARISATION_C, "clip_sigma": CLIP_SIGMA}}
    return heads, card


def write_model(out: Path, heads: list[Head], card: dict, bank: list[FeatureSet] | None,
                markdown: Callable[[dict], str] | None = None, backbone: Backbone | None = None,
                window_heads: list[Head] = (), window_held_out: list[dict] | None = None,
                detector: FrameDetector | None = None) -> None:
    """Heads (and window heads), card and stored features; a tuned backbone's weights beside them (``heads.json``
    names the file)."""
    meta = {k: card[k] for k in ("backbone", "input_size", "space", "space_hash", "seed")}
    if window_heads:
        kept = ("features", "height", "cells", "calibration", "calibration_folds", "detector")
        meta["windows"] = {k: card["windows"][k] for k in kept if k in card["windows"]}
    if detector is not None:   # the model folder carries its detector, as it carries a tuned backbone
        detector.detector.copy_into(out)
    if backbone is not None and backbone.tuned_blocks:
        out.mkdir(parents=True, exist_ok=True)
        meta["backbone_weights"] = save_tuned(backbone, out)
    save_heads(heads, out, meta, window_heads)
    if window_held_out is not None:
        save_held_out(out, window_held_out)
    if bank:
        save_bank(out, *bank)
    (out / "model_card.json").write_text(json.dumps(card, indent=2))
    (out / "MODEL_CARD.md").write_text((markdown or model_card_markdown)(card))


def _render_at(preset: str, space: SceneSpace, scenes: list[dict], renderer_for, workdir: Path) -> list[Example]:
    if renderer_for is None:
        raise ValueError(f"held-out scenes at preset {preset!r} need a way to open a renderer for it")
    renderer = renderer_for(preset)
    try:
        return render_examples(space, scenes, renderer, workdir / f"held-out-{preset}", f"held-out set at {preset}")
    finally:
        close = getattr(renderer, "close", None)
        if close:
            close()


def model_card_markdown(card: dict) -> str:
    presets = card.get("held_out_by_preset", {card["render_preset"]: card["held_out"]})
    counts = card.get("held_out_scenes_by_preset", {card["render_preset"]: card["held_out_scenes"]})
    others = [p for p in presets if p != card["render_preset"]]
    also = "".join(f" (rendered at `{p}` too, the first {counts[p]})" for p in others)
    reproduce = "".join(f" --check-preset {p}:{counts[p]}" for p in others)
    lines = ["# Reference ISU: model card", "",
             "A small, real in-car scene understanding system shipped with isu-validate so that runs work offline.",
             "It is imperfect in honest ways: the accuracies below are measured, not planted.", "",
             f"- Backbone: {card['backbone']}, input {card['input_size'][0]}x{card['input_size'][1]}"
             + (f", run on {card['device']}" if card.get("device") else ""),
             "- Heads: one L2-regularised logistic regression per predicted feature (scikit-learn)"
             + _fit_words(card.get("heads")) + ", stored as plain arrays",
             f"- Scene space: {card['space']} (hash {card['space_hash']})",
             f"- Training set: {card['training_scenes']} rendered scenes, balanced per feature, seed {card['seed']}, "
             f"render preset `{card['render_preset']}`",
             f"- Held-out set: {card['held_out_scenes']} scenes, seed {card['seed'] + 10_000}{also}",
             *_variety_lines(card.get("variety")),
             *_fine_tune_lines(card.get("fine_tune")),
             *_window_lines(card.get("windows")),
             *_hidden_lines(card.get("hidden_from_camera")),
             f"- Reproduce: `isu-validate reference train{_where_flags(card)} --n {card['training_scenes']} "
             f"--held-out {card['held_out_scenes']} --seed {card['seed']} --preset {card['render_preset']}{reproduce}"
             + _variety_flags(card.get("variety"))
             + (f" --fine-tune {card['fine_tune']['blocks']}" if card.get("fine_tune") else "")
             + (f" --windows {','.join(card['windows']['features'])}" if card.get("windows") else "")
             + _detector_flags((card.get("windows") or {}).get("detector")) + "`",
             f"- Stored features: `{FILES['train']}` and `{FILES['held_out']}` hold the backbone features (float32), "
             "scenes and renderer version of both sets, so `isu-validate reference train --extra DATASET...` "
             "retrains on them plus the dataset without rendering them again, and compares on the same held-out scenes",
             "", "## Held-out accuracy per feature", "",
             "| feature | " + " | ".join(f"{p} | n" for p in presets) + " | training accuracy |",
             "|---|" + "---|---|" * len(presets) + "---|"]
    for feature in card["held_out"]["per_feature"]:
        cells = []
        for p in presets:
            row = presets[p]["per_feature"].get(feature)
            cells += [f"{row['accuracy']:.3f}", str(row["n"])] if row else ["-", "0"]
        train = card["training"].get(feature, {}).get("accuracy", float("nan"))
        lines.append(f"| {feature} | " + " | ".join(cells) + f" | {train:.3f} |")
    for p, result in presets.items():
        lines += _by_light(result, f"## Held-out accuracy by external light (preset `{p}`)")
    return "\n".join(lines) + "\n"


def _fit_words(fit: dict | None) -> str:
    """How the heads were fitted; a card from before clipping says nothing (its heads read features unclipped)."""
    if not fit:
        return ""
    return (f" with C {fit['C']}, on standardised features clipped at +-{fit['clip_sigma']:g} training standard "
            "deviations (a photo's channel counts at most as far as the renders moved it)")


def _hidden_lines(hidden: dict | None) -> list[str]:
    if hidden is None:
        return []
    said = "; ".join(f"{role.replace('_', '-')}: " + (", ".join(f"{name} {n}" for name, n in counts.items()) or "none")
                     for role, counts in hidden.items())
    return [f"- Hidden from the camera, so not learnt from nor scored (the render label's `occluded`): {said}"]


def _variety_lines(variety: dict | None) -> list[str]:
    if not variety:
        return []
    from ..render.variety import card_lines

    return ["- Variety (training, held-out and checked sets alike):", *("  " + line for line in card_lines(variety))]


def _fine_tune_lines(tuning: dict | None) -> list[str]:
    if not tuning:
        return []
    return [f"- Fine-tuned: the backbone's last {tuning['blocks']} blocks trained on the {tuning['images']} training "
            f"renders for {tuning['epochs']} epochs (lr {tuning['learning_rate']:g}, batch {tuning['batch']}, crops, "
            f"colour, grey, blur and sensor noise; every predicted feature at once), {tuning['seconds']:.0f} s; "
            f"the heads were fitted on the tuned features. Weights: `{WEIGHTS_FILE}`"]


def _where_flags(card: dict) -> str:
    """The space and rigs a model was trained in, where not the defaults (a card from before rigs were recorded
    names the space only)."""
    flags = f" --space {card['space']}" if card.get("space", "isu-paper") != "isu-paper" else ""
    return flags + "".join(f" --{rig} {name}" for rig, name in (card.get("rigs") or {}).items() if name != "default")


def _window_lines(windows: dict | None) -> list[str]:
    if not windows:
        return []
    h = windows["height"]
    before = "; ".join(f"{name} {fig['accuracy']:.3f}" for name, fig in windows["whole_frame_held_out"].items() if fig)
    counts = "; ".join(f"{name} {c['YES']} showing it, {c['NO']} not"
                       for name, c in windows["training_windows"].items())
    return [f"- Window heads: {', '.join(f'`{n}`' for n in windows['features'])} answered from the most positive "
            f"{windows['cells']}x{windows['cells']}-cell window of the backbone's map of the frame scaled to {h} px "
            f"high, its aspect kept (trained on the render labels' part boxes; windows: {counts}); their rows below "
            "are the window heads'. "
            f"The whole-frame heads' held-out accuracy: {before or '-'}. {_calibration_line(windows)}",
            *_detector_lines(windows.get("detector"),
                             windows.get("calibration_folds") or windows.get("stacking_folds", f"{FOLDS} by frame"))]


def _calibration_line(windows: dict) -> str:
    """How the window heads' log-odds became probabilities; models fitted before ``calibration_folds`` was recorded
    calibrated a head that stands alone on its own training frames."""
    if "calibration_folds" in windows:
        return ("Each head is calibrated on the training renders' log-odds out of fold (folds "
                f"{windows['calibration_folds']}): a head fitted without the frame's fold scores it")
    return "A head calibrated alone was calibrated on its own training frames' log-odds (in sample)"


def _detector_lines(detector: dict | None, stacking_folds: str) -> list[str]:
    if not detector:
        return []
    classes = ", ".join(f"`{f}` <- '{c}'" for f, c in detector["classes"].items())
    views = "the frame and its 2x2 tiles" if detector.get("tiles", 1) == 2 else "the whole frame"
    return [f"- Detector: the window heads it has a class for are stacked with an object detector's best score "
            f"({classes}; any other window head is calibrated alone; "
            f"`{detector['file']}`, sha256 {detector['sha256'][:12]}, input {detector['input']} px, over {views}), "
            "the stacking "
            f"fitted on the training renders with the window's log-odds out of fold (folds {stacking_folds}). "
            "The detector was trained by its "
            f"makers on their own data (for a COCO detector, photographs), not by this project; its licence: "
            f"{detector['licence']}"]


def _detector_flags(detector: dict | None) -> str:
    if not detector:
        return ""
    named = shlex.quote(detector["named"]) if "named" in detector else "DETECTOR.onnx"   # fitted before it was kept
    return (f" --detector {named} --detector-tiles {detector.get('tiles', 1)}"
            + "".join(f" --detector-class {f}='{c}'" for f, c in detector["classes"].items()))


def _variety_flags(variety: dict | None) -> str:
    if not variety:
        return ""
    return "".join(f" --{name.replace('_', '-')} {variety[name]}"
                   for name in ("camera_jitter", "sensor_effects", "camera_mix") if variety.get(name))


def _by_light(result: dict, heading: str) -> list[str]:
    lights = result["by_external_light"]
    lines = ["", heading, "", "| feature | " + " | ".join(lights) + " |", "|---|" + "---|" * len(lights)]
    for feature in result["per_feature"]:
        cells = [f"{lights[light][feature]['accuracy']:.3f} ({lights[light][feature]['n']})"
                 if feature in lights[light] else "-" for light in lights]
        lines.append(f"| {feature} | " + " | ".join(cells) + " |")
    return lines
