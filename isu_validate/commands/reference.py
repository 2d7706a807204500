"""``isu-validate reference train``: render a balanced set, train the reference ISU's heads; with
``--extra DATASET...``, retrain them on a model's own stored features plus the datasets' images."""
from __future__ import annotations

import json
from pathlib import Path

from ..devices import add_device_argument, add_render_device_argument
from ..errors import InputError
from ..dataset.settings import VARIETY
from ..reference.fine_tune import FineTune
from ..reference.windows import WindowSettings
from . import add_overwrite_option, add_variety_arguments


def register(sub) -> None:
    parser = sub.add_parser("reference", help="the embedded reference ISU (train it)")
    ref_sub = parser.add_subparsers(dest="reference_command", metavar="ACTION")
    train = ref_sub.add_parser("train", help="render a balanced training set and train the heads (or retrain "
                                             "with --extra)")
    train.add_argument("--n", type=int, help=f"training scenes (default {DEFAULTS['n']})")
    train.add_argument("--held-out", type=int,
                       help=f"held-out scenes for the model card (default {DEFAULTS['held_out']})")
    train.add_argument("--seed", type=int,
                       help=f"seed of the training and held-out scenes (default {DEFAULTS['seed']})")
    train.add_argument("--space", default="isu-paper",
                       help="scene space name or .toml path whose features the heads answer (default isu-paper)")
    train.add_argument("--preset", help="render preset (default draft, as the demo renders)")
    train.add_argument("--check-preset", action="append", default=[], metavar="PRESET[:N]",
                       help="also render the first N held-out scenes (default all) at PRESET and report the "
                            "accuracy on them, e.g. standard:100 (repeatable)")
    train.add_argument("--camera", help=f"camera rig name or .toml path the scenes are rendered through "
                                        f"(default {DEFAULTS['camera']})")
    add_render_device_argument(train)
    add_device_argument(train)
    train.add_argument("--cabin", help=f"cabin rig name or .toml path (default {DEFAULTS['cabin']})")
    add_variety_arguments(train)   # the training, held-out and checked sets alike; the card records them
    train.add_argument("--fine-tune", type=int, nargs="?", const=FineTune.blocks, metavar="BLOCKS",
                       help=f"train the backbone's last BLOCKS blocks (default {FineTune.blocks} of 16) on "
                            "the training renders before fitting the heads, with crop, colour, blur and noise "
                            "augmentation; its weights go beside the heads (backbone.pt). Off by default: the "
                            "backbone stays ImageNet's, frozen")
    train.add_argument("--windows", metavar="FEATURE[,FEATURE...]",
                       help="also fit window heads for these yes/no features (e.g. phone_position): read from the "
                            "most positive 96-px window of the frame scaled to 480 px high, trained where the render "
                            "labels box the feature's parts; they then answer those features. Off by default")
    train.add_argument("--detector", metavar="yolov4-tiny|FILE.cfg|FILE.onnx",
                       help="with --windows: stack each window head with this photo-trained object detector's best "
                            "score for the feature's class: yolov4-tiny (built in, public domain, COCO), a darknet "
                            "YOLO (FILE.cfg with FILE.weights and its .names beside) or an ONNX export in the "
                            "Ultralytics YOLO layout; copied into the model folder, its licence on the card")
    train.add_argument("--detector-tiles", type=int, choices=(1, 2),
                       help="with --detector: 2 reads the frame and a 2x2 grid of overlapping tiles scaled up to the "
                            "detector's input, its best score counting (a phone is near the smallest a YOLO finds "
                            "in a whole frame); 1 the whole frame only (default 2)")
    train.add_argument("--detector-class", action="append", metavar="FEATURE=CLASS",
                       help="the detector class a window feature reads (default phone_position='cell phone'); "
                            "repeat for more; a window feature without one is calibrated alone")
    train.add_argument("--extra", nargs="+", type=Path, metavar="DATASET",
                       help="retrain on the --base model's own training scenes (its stored features: nothing is "
                            "rendered again) plus these datasets (`isu-validate dataset`); the card compares every "
                            "feature with the base model on its held-out scenes")
    train.add_argument("--base", type=Path,
                       help="with --extra: the model whose scenes, seed and held-out set to keep (default the "
                            "shipped reference ISU)")
    train.add_argument("--out", type=Path,
                       help="model folder (default WORKDIR/model, with --extra WORKDIR/model-extra; the shipped "
                            "model is replaced only when named here: --out data/reference-isu)")
    add_overwrite_option(train, "another model or another command's output")
    train.add_argument("--workdir", type=Path, default=Path("runs/reference-training"),
                       help="where the rendered sets (with --extra: the datasets' features) go; an interrupted "
                            "training resumes from here (default runs/reference-training)")
    train.set_defaults(func=cmd_train)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


DEFAULTS = {"n": 600, "held_out": 200, "seed": 0, "preset": "draft", "camera": "default", "cabin": "default"}
FROM_SCRATCH = ("n", "held_out", "seed", "preset", "check_preset", "camera", "cabin", "fine_tune", "windows",
                "detector", "detector_class", "detector_tiles")
# claimed only when given: a model claimed before they existed resumes as before
OPTIONAL = ("fine_tune", "windows", "detector", "detector_class", "detector_tiles")


def cmd_train(args) -> int:
    if args.extra:
        return cmd_retrain(args)
    if args.base:
        raise InputError("--base names the model that --extra retrains; give --extra DATASET... too")
    for name, value in DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    return cmd_train_new(args)


def cmd_train_new(args) -> int:
    from ..reference.model import default_model_dir
    from ..reference.training import train_reference
    from ..render import RENDERER_VERSION, open_renderer
    from ..render.variety import Variety, vary
    from ..space import load_space

    if args.n < 10 or args.held_out < 1:
        raise InputError("use at least --n 10 training scenes and --held-out 1")
    space = load_space(args.space)
    variety = Variety.parse(args.camera_jitter, args.sensor_effects, args.seed, args.camera_mix)
    out = args.out or args.workdir / "model"  # never the shipped model unless asked for by name
    checks = dict(parse_check(spec, args.held_out) for spec in args.check_preset)
    windows = WindowSettings.parse(args.windows, space)
    detector = _detector(args, windows)
    claimed = {k: getattr(args, k) for k in FROM_SCRATCH if k not in OPTIONAL or getattr(args, k) is not None}
    if detector:   # the file's content, not its name: another file at the same path is another training
        claimed["detector"], claimed["detector_tiles"] = detector.detector.sha256, detector.tiles
    output = _claim(args, out, {"space": space.hash, **claimed,
                                **{k: v for k, v in variety.describe().items() if k in VARIETY}})

    def renderer_for(preset: str):
        return vary(open_renderer(preset=preset, camera=args.camera, cabin=args.cabin, space=space,
                                  cache_dir=args.workdir / "cache", log_dir=args.workdir / "logs",
                                  device=args.render_device), variety)

    renderer = renderer_for(args.preset)
    try:
        card = train_reference(space, renderer, out, args.workdir, args.n, args.held_out, args.seed, args.preset,
                               other_presets=checks, renderer_for=renderer_for, renderer_version=RENDERER_VERSION,
                               device=args.device, variety=variety.describe(),
                               fine_tune=FineTune.optional(args.fine_tune, args.seed), windows=windows,
                               rigs={"camera": args.camera, "cabin": args.cabin}, detector=detector)
    finally:
        renderer.close()
    output.mark()   # the model is written last, so a refused or failed training leaves no folder behind
    print(json.dumps(card["held_out"]["per_feature"], indent=2))
    _print_written(out, default_model_dir())
    return 0



def _detector(args, windows):
    """The detector the window heads stack with (None when not asked for), opened and checked before rendering."""
    from ..reference.detector import open_for_windows

    if args.detector is None and (args.detector_class or args.detector_tiles):
        raise InputError("--detector-class and --detector-tiles say how a --detector reads; give --detector too "
                         "(e.g. --detector yolov4-tiny)")
    return open_for_windows(args.detector, windows, args.detector_class, "--detector stacks with window heads: "
                            "give --windows FEATURE too (e.g. --windows phone_position)", args.detector_tiles)


def cmd_retrain(args) -> int:
    from ..reference.model import default_model_dir
    from ..dataset.folder import open_dataset
    from ..reference.extra_data import extra_set
    from ..reference.retrain import retrain_with_extra
    from ..render import RENDERER_VERSION
    from ..space import load_space

    given = [f"--{name.replace('_', '-')}" for name in FROM_SCRATCH + VARIETY
             if getattr(args, name) not in (None, [])]
    if given:
        raise InputError(f"--extra keeps the --base model's scenes, seed, preset and held-out set: "
                         f"{', '.join(given)} do not apply (train a new base without --extra)")
    space = load_space(args.space)
    out = args.out or args.workdir / "model-extra"
    base = _check_base(args.base) if args.base else default_model_dir()
    output = _claim(args, out, {"space": space.hash, "base": str(Path(base).resolve()),
                                "extra": [str(Path(f).resolve()) for f in args.extra]})
    extra = []
    for folder in args.extra:
        dataset = open_dataset(folder)
        extra.append(extra_set(folder, dataset.info(), dataset.metadata(), space))
    card = retrain_with_extra(space, base, extra, out, RENDERER_VERSION,
                              cache_dir=args.workdir / "extra-features", device=args.device)
    output.mark()
    print((out / "MODEL_CARD.md").read_text())
    _print_written(out, default_model_dir())
    return 0 if card else 1


def _check_base(base: Path) -> Path:
    """``--base`` as a model folder, or an error that says what the path really is."""
    from ..archive.output_dir import holder
    from ..reference.model import default_model_dir

    fix = f"name a model folder (one with heads.npz, e.g. {default_model_dir()} or a `reference train --out`)"
    if not base.exists():
        raise InputError(f"--base {base} does not exist; {fix}")
    if not base.is_dir():
        raise InputError(f"--base {base} is a file; {fix}")
    if not (base / "heads.npz").is_file():
        found = holder(base)
        what = (f"holds the output of `isu-validate {found.command}` ({found.evidence})" if found
                else "holds no heads.npz")
        raise InputError(f"--base {base} {what}, not a reference ISU model; {fix}")
    return base


def _claim(args, out: Path, settings: dict):
    """The model folder: new, or this same training's; another model or command's output needs --overwrite."""
    from ..archive.output_dir import claim_output
    return claim_output(out, "reference train", settings, overwrite=args.overwrite)


def _print_written(out: Path, shipped: Path) -> None:
    print(f"model and card written to {out}")
    if out.resolve() != shipped.resolve():
        print(f"use it with: isu-validate run --sut reference --sut-option model_dir={out}")


def parse_check(spec: str, held_out: int) -> tuple[str, int]:
    """``standard:100`` -> ("standard", 100); ``standard`` -> all held-out scenes."""
    from ..render.presets import get_preset

    name, _, count = spec.partition(":")
    get_preset(name)   # an unknown preset is named before anything renders
    try:
        n = int(count) if count else held_out
    except ValueError:
        raise InputError(f"--check-preset {spec!r}: N must be a whole number (PRESET[:N])") from None
    if not 1 <= n <= held_out:
        raise InputError(f"--check-preset {spec!r}: N must be between 1 and --held-out ({held_out})")
    return name, n
