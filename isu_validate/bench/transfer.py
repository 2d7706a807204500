"""``isu-validate bench transfer REAL... --labels MAP --recipe NAME=SPEC... --out DIR``: recipes of renders side
by side, each judged by what a reference ISU trained only on them does on the real sets.

A recipe is how the training renders are made, or a model already trained from renders:
- ``NAME=train:camera=RIG,space=SPACE,cabin=RIG,preset=P,n=N,held_out=N,seed=S,camera_jitter=...,
  sensor_effects=...,camera_mix=RIG,...,fine_tune=BLOCKS,windows=FEATURE,...,detector=yolov4-tiny|FILE,
  detector_tiles=1|2`` (every key optional; the bench's --n, --held-out, --preset and --seed are the defaults;
  camera_jitter, sensor_effects and camera_mix as ``reference train --camera-jitter/--sensor-effects/--camera-mix``
  take them, commas and all; fine_tune as
  ``reference train --fine-tune BLOCKS``; windows, detector and detector_tiles as ``reference train --windows
  --detector --detector-tiles``, its default classes): ``reference train`` as it is, in DIR/recipes/NAME (renders
  kept, so an interrupted bench goes on);
- ``NAME=model:DIR[,renders=FOLDER]``: a model ``reference train`` made elsewhere, e.g. with another
  renderer version's checkout (``reference train --out DIR --workdir W``; its held-out renders, W/held-out,
  are the render side of KID).
Each recipe's model is then measured by ``transfer`` on the real sets (DIR/recipes/NAME/transfer), against
its own held-out renders; one table: balanced accuracy per feature and set with its 95% interval, KID of
each real set against the recipe's held-out renders, and the seconds each recipe took.
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..atomic import write_json, write_text
from ..errors import InputError
from ..transfer.arguments import add_real_set_arguments, parse_groups

TRAIN_KEYS = {"camera": str, "cabin": str, "space": str, "preset": str, "n": int, "held_out": int, "seed": int,
              "camera_jitter": str, "sensor_effects": str, "fine_tune": int, "windows": str, "detector": str,
              "detector_tiles": int, "camera_mix": str}
# values that are lists themselves: pos=0.05,angle=5; default,passenger-door
LISTS = ("camera_jitter", "sensor_effects", "windows", "camera_mix")


@dataclass
class Recipe:
    name: str
    kind: str                          # train | model
    options: dict = field(default_factory=dict)


def register_bench(sub) -> None:
    p = sub.add_parser("transfer", help="recipes of training renders, judged on labelled real photos",
                       description=__doc__.split("\n\n", 1)[1])
    add_real_set_arguments(p)
    p.add_argument("--recipe", action="append", required=True, metavar="NAME=SPEC",
                   help="NAME=train:KEY=VALUE,... or NAME=model:DIR[,renders=FOLDER] (repeatable)")
    p.add_argument("--n", type=int, default=300, help="training scenes of a train recipe (default 300)")
    p.add_argument("--held-out", type=int, default=100, help="held-out scenes of a train recipe (default 100)")
    p.add_argument("--preset", default="draft", help="render preset of a train recipe (default draft)")
    p.add_argument("--render-device", default="cpu", help="Cycles device of a train recipe (default cpu)")
    p.add_argument("--out", type=Path, required=True, help="folder for the recipes' models, measurements and table")
    p.set_defaults(func=run)


def parse_recipe(text: str) -> Recipe:
    name, sep, spec = text.partition("=")
    kind, sep2, rest = spec.partition(":")
    if not sep or not name.strip() or not sep2 or kind not in ("train", "model"):
        raise InputError(f"--recipe {text!r} must read NAME=train:KEY=VALUE,... or NAME=model:DIR[,renders=FOLDER]")
    if kind == "model":
        folder, _, extra = rest.partition(",renders=")
        return Recipe(name.strip(), kind, {"model": folder, "renders": extra or None})
    options, last = {}, None
    for pair in filter(None, rest.split(",")):
        key, eq, value = pair.partition("=")
        if last in LISTS and key not in TRAIN_KEYS:   # the next item of a list-valued key's list
            options[last] += "," + pair
            continue
        last = key
        if not eq or key not in TRAIN_KEYS:
            raise InputError(f"--recipe {name}: {pair!r} is not KEY=VALUE with KEY one of {', '.join(TRAIN_KEYS)}")
        try:
            options[key] = TRAIN_KEYS[key](value)
        except ValueError:
            raise InputError(f"--recipe {name}: {key} must be {TRAIN_KEYS[key].__name__}, got {value!r}") from None
    return Recipe(name.strip(), kind, options)


def run(args) -> int:
    recipes = [parse_recipe(r) for r in args.recipe]
    if len({r.name for r in recipes}) < len(recipes):
        raise InputError("two recipes share a name: give each --recipe its own NAME")
    rows = []
    for recipe in recipes:
        folder = args.out / "recipes" / recipe.name
        started = time.perf_counter()
        model, renders, made = _model(recipe, folder, args)
        trained_s = time.perf_counter() - started
        summary = _measure(args, recipe, model, renders, folder / "transfer")
        rows.append({"recipe": recipe.name, "made": made,
                     "train_s": round(trained_s, 1) if recipe.kind == "train" else None,   # None: trained elsewhere
                     "transfer_s": summary["seconds"], "summary": summary})
    table = format_table(rows)
    print(table)
    write_text(args.out / "table.txt", table + "\n")
    write_json(args.out / "bench.json",
               [{k: v for k, v in r.items() if k != "summary"} | {"scores": _headline(r["summary"])} for r in rows],
               indent=1)
    return 0


def _model(recipe: Recipe, folder: Path, args) -> tuple[Path, Path | None, str]:
    """(model folder, its held-out renders, what made it)."""
    if recipe.kind == "model":
        model = Path(recipe.options["model"])
        if not (model / "heads.npz").is_file():
            raise InputError(f"--recipe {recipe.name}: {model} is no reference ISU model (no heads.npz)")
        card = json.loads((model / "model_card.json").read_text()) if (model / "model_card.json").is_file() else {}
        renders = Path(recipe.options["renders"]) if recipe.options["renders"] else None
        return model, renders, f"model {model} (renderer {card.get('renderer', '?')})"
    return _train(recipe, folder, args)


def recipe_settings(recipe: Recipe, args) -> tuple[dict, str]:
    """(a train recipe's options with the bench's defaults, what its recipe.json holds: those and ``_made_with``)."""
    o = {"camera": "default", "cabin": "default", "space": "isu-paper", "preset": args.preset, "n": args.n,
         "held_out": args.held_out, "seed": args.seed, "camera_jitter": None, "sensor_effects": None,
         **recipe.options}   # no default for fine_tune, windows or detector: a recipe without them reads as before
    return o, json.dumps({**o, **_made_with(o)}, sort_keys=True)


def _made_with(options: dict) -> dict:
    """What else decides a trained recipe's model: the renderer version, the rig files' contents and how the
    heads are fitted (a model kept from another fit would measure that fit)."""
    import hashlib

    from capture.camera import load_camera

    from ..reference.heads import CLIP_SIGMA, REGULARISATION_C
    from ..render import RENDERER_VERSION
    from ..render.cabin import load_cabin

    cabin = json.dumps(load_cabin(options["cabin"]), sort_keys=True, default=str)
    return {"renderer": RENDERER_VERSION, "camera_hash": load_camera(options["camera"]).hash,
            "cabin_hash": hashlib.sha256(cabin.encode()).hexdigest()[:16],
            "heads": {"C": REGULARISATION_C, "clip_sigma": CLIP_SIGMA},
            **(_detector_made_with(options) if options.get("detector") else {})}


def _detector_made_with(options: dict) -> dict:
    """The detector by its content, not its name (a missing file is refused by name before rendering), and the views
    it reads (a recipe that leaves them out reads the default, so a kept model read otherwise is another recipe)."""
    from ..reference.detector import DEFAULT_TILES, digest_of

    try:
        digest = digest_of(options["detector"])
    except InputError:
        digest = "missing"
    return {"detector_sha256": digest, "detector_tiles": options.get("detector_tiles") or DEFAULT_TILES}


def _train(recipe: Recipe, folder: Path, args) -> tuple[Path, Path, str]:
    from ..reference.detector import open_for_windows
    from ..reference.fine_tune import FineTune
    from ..reference.training import train_reference
    from ..reference.windows import WindowSettings
    from ..render import RENDERER_VERSION, open_renderer
    from ..render.variety import Variety, vary
    from ..space import load_space

    o, made = recipe_settings(recipe, args)
    model = folder / "model"
    stored = (folder / "recipe.json").read_text() if (folder / "recipe.json").is_file() else made
    if stored != made:   # a kept model is reused only for what it was made with: a changed rig file is another recipe
        raise InputError(_kept_elsewise(folder, recipe.name, stored, made))
    folder.mkdir(parents=True, exist_ok=True)
    write_text(folder / "recipe.json", made)
    description = f"{RENDERER_VERSION}, " + ", ".join(f"{k}={v}" for k, v in o.items())
    if (model / "heads.npz").is_file():
        return model, folder / "held-out", description
    space = load_space(o["space"])
    variety = Variety.parse(o["camera_jitter"], o["sensor_effects"], o["seed"], o.get("camera_mix"))
    tuning, windows = FineTune.optional(o.get("fine_tune"), o["seed"]), WindowSettings.parse(o.get("windows"), space)
    if o.get("detector_tiles") and not o.get("detector"):
        raise InputError(f"--recipe {recipe.name}: detector_tiles= says how a detector= reads; add "
                         "detector=yolov4-tiny (or a file), or leave detector_tiles out")
    detector = open_for_windows(o.get("detector"), windows, None,   # its default classes
                                f"--recipe {recipe.name}: detector= stacks with window heads; add windows=FEATURE",
                                o.get("detector_tiles"))
    renderer = vary(open_renderer(preset=o["preset"], camera=o["camera"], cabin=o["cabin"], space=space,
                                  cache_dir=folder / "cache", log_dir=folder / "logs", device=args.render_device),
                    variety)
    try:
        train_reference(space, renderer, model, folder, o["n"], o["held_out"], o["seed"], o["preset"],
                        renderer_version=RENDERER_VERSION, device=args.device, variety=variety.describe(),
                        fine_tune=tuning, windows=windows, rigs={"camera": o["camera"], "cabin": o["cabin"]},
                        detector=detector)
    finally:
        renderer.close()
    return model, folder / "held-out", description


def _kept_elsewise(folder: Path, name: str, stored: str, made: str) -> str:
    """Why a recipe folder is refused, and the cheapest way on: a head fit alone is refitted on the kept renders."""
    try:
        kept = json.loads(stored)
        fit_only = {k: v for k, v in kept.items() if k != "heads"} == \
            {k: v for k, v in json.loads(made).items() if k != "heads"}
    except (ValueError, AttributeError):   # a damaged recipe.json: only the general answer
        fit_only = False
    if fit_only:
        return (f"{folder} holds recipe {name} with heads fitted otherwise ({kept.get('heads', 'unclipped')}, now "
                f"{json.loads(made)['heads']}); delete {folder / 'model'} and {folder / 'recipe.json'} to fit them "
                "again on its renders, or choose another --out or recipe name")
    return (f"{folder} holds recipe {name} made with other settings, renderer or rig files ({stored}); choose another "
            f"--out or recipe name, or delete {folder} to make it again")


def _measure(args, recipe: Recipe, model: Path, renders: Path | None, out: Path) -> dict:
    from ..transfer import TransferSettings, measure_transfer

    space = json.loads((model / "heads.json").read_text()).get("space", args.space)   # the space it was trained in
    settings = TransferSettings(tuple(args.real), tuple(args.labels), "reference", {"model_dir": str(model)},
                                space, str(renders) if renders else None, args.layout, args.skip_conflicts,
                                parse_groups(args.groups), args.limit, seed=args.seed, device=args.device,
                                zero_shot=args.zero_shot)
    print(f"bench transfer: measuring recipe {recipe.name}", file=sys.stderr)
    return measure_transfer(settings, out)


def _headline(summary: dict) -> dict:
    return {name: {f: {k: sc[k] for k in ("n", "balanced_accuracy", "balanced_accuracy_ci95", "auc")}
                   for f, sc in s["scores"].items()} for name, s in summary["sets"].items()} | {
        "renders": {f: sc["balanced_accuracy"] for f, sc in (summary.get("renders") or {}).get("scores", {}).items()},
        "kid": {name: r["kid_mean"] for name, r in (summary.get("realism") or {}).items()},
        "zero_shot_auc": {name: {f: r["auc"] for f, r in features.items()}
                          for name, features in (summary.get("zero_shot") or {}).items()},
        "detector_alone_auc": {name: {f: r["detector"].get("auc") for f, r in features.items() if r.get("detector")}
                               for name, features in (summary.get("zero_shot") or {}).items()}}


def format_table(rows: list[dict]) -> str:
    """recipe x (set, feature): balanced accuracy [95% CI]; KID per set; seconds; answers per label of a set."""
    from ..transfer.scores import format_said_by_label

    lines = []
    for r in rows:
        s = r["summary"]
        trained = f"train {r['train_s']} s" if r["train_s"] is not None else "trained elsewhere"
        lines.append(f"{r['recipe']}: {r['made']}  ({trained}, transfer {r['transfer_s']} s)")
        for name, real in s["sets"].items():
            kid = (s.get("realism") or {}).get(name)
            cells = [f"{f} BA {_ci(sc)}" for f, sc in real["scores"].items()]
            kid_text = f"KID {kid['kid_mean']:.4f} ± {kid['kid_std']:.4f}" if kid else "KID -"
            lines.append(f"  real {name:<18} " + "; ".join(cells) + f"; {kid_text}")
            lines += [f"  {line}" for f, sc in real["scores"].items()
                      for line in format_said_by_label(f"{name}, {f}", sc)]
        if s.get("renders"):
            cells = [f"{f} BA {_ci(sc)}" for f, sc in s["renders"]["scores"].items()]
            lines.append(f"  {'own held-out renders':<23} " + "; ".join(cells))
        if s.get("zero_shot"):
            from ..transfer.zero_shot import format_zero_shot
            lines += [f"  {line}" for line in format_zero_shot(s["zero_shot"])]
    return "\n".join(lines)


def _ci(sc: dict) -> str:
    ba, ci = sc["balanced_accuracy"], sc["balanced_accuracy_ci95"]
    if ba is None:
        return "-"
    return f"{ba:.2f} [{ci[0]:.2f}, {ci[1]:.2f}] (n {sc['n']})" if ci else f"{ba:.2f} (n {sc['n']})"
