"""Subcommands of ``isu-validate``: one module per command (``isu_validate.cli.COMMANDS`` maps them)."""
from __future__ import annotations


def chosen(argv: list[str] | None, names) -> str | None:
    """The first word of ``argv`` that names one of ``names`` (options before it take no values)."""
    for word in argv or ():
        if not word.startswith("-"):
            return word if word in names else None
    return None


def add_overwrite_option(parser, what: str) -> None:
    """``--overwrite``: the one flag, the same for every command that writes a folder, that lets ``--out`` be a
    folder holding ``what`` (``archive/output_dir.py`` refuses it otherwise)."""
    parser.add_argument("--overwrite", action="store_true",
                        help=f"write into --out even when it holds {what} (files of the same name are replaced)")


def add_variety_arguments(parser) -> None:
    """``--camera-jitter``, ``--sensor-effects`` and ``--camera-mix``: variety per scene for training data
    (``render/variety.py``); the same options for ``dataset`` and ``reference train``. Light: the specs are parsed
    when the command runs."""
    parser.add_argument("--camera-jitter", metavar="SPEC",
                        help="move, turn and zoom the camera per scene, seeded by --seed and the scene: "
                             "pos=METRES,angle=DEGREES,focal=RELATIVE, each the largest either way, drawn uniformly "
                             "(e.g. pos=0.05,angle=5,focal=0.1); labels follow the camera used (default: none)")
    parser.add_argument("--sensor-effects", metavar="SPEC",
                        help="camera effects applied after rendering, strengths seeded per scene: a recipe (mild, "
                             "strong) and/or maxima exposure=STOPS,white_balance=GAIN,vignette=SHARE,blur=SIGMA_PX,"
                             "noise=SIGMA_SHARE,jpeg=0..1 (e.g. mild,jpeg=0.6; default: none)")
    parser.add_argument("--camera-mix", metavar="RIG[,RIG...]",
                        help="see each scene through --camera or one of these camera rigs (names or .toml paths), "
                             "drawn uniformly per scene, seeded by --seed and the scene, before any --camera-jitter: "
                             "training data from more than one viewpoint (e.g. default,passenger-door); labels follow "
                             "the camera used (default: --camera only)")
