"""``isu-validate reference train``: render a balanced set, train the reference ISU's heads."""
from __future__ import annotations

import json
from pathlib import Path

from ..errors import InputError


def register(sub) -> None:
    parser = sub.add_parser("reference", help="the embedded reference ISU (train it)")
    ref_sub = parser.add_subparsers(dest="reference_command", metavar="ACTION")
    train = ref_sub.add_parser("train", help="render a balanced training set and train the heads")
    train.add_argument("--n", type=int, default=800, help="training scenes (default 800)")
    train.add_argument("--held-out", type=int, default=200, help="held-out scenes for the model card (default 200)")
    train.add_argument("--seed", type=int, default=0)
    train.add_argument("--space", default="isu-paper")
    train.add_argument("--preset", default="draft", help="render preset (default draft, as the demo renders)")
    train.add_argument("--check-preset", action="append", default=[], metavar="PRESET[:N]",
                       help="also render the first N held-out scenes (default all) at PRESET and report the "
                            "accuracy on them, e.g. standard:100 (repeatable)")
    train.add_argument("--camera", default="default")
    train.add_argument("--cabin", default="default")
    train.add_argument("--out", type=Path,
                       help="model folder (default WORKDIR/model; the shipped model is replaced only when "
                            "named here: --out data/reference-isu)")
    train.add_argument("--workdir", type=Path, default=Path("runs/reference-training"),
                       help="where the rendered sets go; an interrupted training resumes from here")
    train.set_defaults(func=cmd_train)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


def cmd_train(args) -> int:
    from ..reference.model import default_model_dir
    from ..reference.training import train_reference
    from ..render import open_renderer
    from ..space import load_space

    if args.n < 10 or args.held_out < 1:
        raise InputError("use at least --n 10 training scenes and --held-out 1")
    space = load_space(args.space)
    out = args.out or args.workdir / "model"  # never the shipped model unless asked for by name
    checks = dict(parse_check(spec, args.held_out) for spec in args.check_preset)

    def renderer_for(preset: str):
        return open_renderer(preset=preset, camera=args.camera, cabin=args.cabin, space=space,
                             cache_dir=args.workdir / "cache", log_dir=args.workdir / "logs")

    renderer = renderer_for(args.preset)
    try:
        card = train_reference(space, renderer, out, args.workdir, args.n, args.held_out, args.seed, args.preset,
                               other_presets=checks, renderer_for=renderer_for)
    finally:
        renderer.close()
    print(json.dumps(card["held_out"]["per_feature"], indent=2))
    print(f"model and card written to {out}")
    if out.resolve() != default_model_dir().resolve():
        print(f"use it with: isu-validate run --sut reference --sut-option model_dir={out}")
    return 0


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
