"""The ``isu-validate`` command: one entry point, one module per subcommand in ``commands/``.

Starting must be quick (``--version``, ``--help`` and a mistyped option answer in well under a second),
so only the module of the command being run is imported; the others appear in ``--help`` through the
one-line summaries below. A command imports its heavy libraries when it runs.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import traceback

from .commands import chosen
from .errors import UserError

# command -> (module in isu_validate/commands/ that registers it, its one-line summary in --help).
# Each module defines `register(subparsers)`, which adds its subcommand(s) and sets `func` (called with
# the parsed args, returns an exit code); a test checks that these summaries are the modules' own.
COMMANDS = {
    "run": ("run", "search the scene space for scenes the SUT gets wrong"),
    "export": ("run", "write a run's tests table"),
    "bench": ("bench", "benchmarks: speed against error"),
    "render": ("render", "render scenes with Blender (one scene file, or --random N)"),
    "people": ("people", "the anny people of the renders: warm their cache, check their poses"),
    "report": ("report", "compare runs: failure rates, statistics, failure analysis and diversity"),
    "sut": ("sut", "systems under test: check that one answers"),
    "reference": ("reference", "the embedded reference ISU (train it)"),
    "realism": ("realism", "FID/KID between image sets (renders, stylised renders, real photos)"),
    "recognise": ("recognise", "how recognisable renders are to photo-trained models (faces, expression, objects)"),
    "stylize": ("stylize", "neural style transfer of renders towards a real photo (or: stylize train)"),
    "capture": ("capture", "camera capture: list devices, shoot frames with exposure metadata"),
    "calibrate": ("calibrate", "calibrate a camera from ChArUco images (also: diff, register)"),
    "recreate": ("recreate", "pick tests to recreate in a real car; write pairs and recreation sheets"),
    "agree": ("agree", "per-feature sim/real agreement report (or: agree votes, validity votes)"),
    "replay": ("replay", "ask a new SUT about a run's stored images; fixed and new failures"),
    "exposure": ("exposure", "camera exposure, response, noise and colour: fit, apply, check"),
    "dataset": ("dataset", "render a training dataset: images, truth, COCO masks, VQA chats"),
    "transfer": ("transfer", "what renders taught: a SUT on labelled real photos beside renders"),
}

__all__ = ["COMMANDS", "UserError", "build_parser", "main"]


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser; with ``argv``, only the command it names is built in full (the others are summaries).
    Without ``argv`` every command is built, as the docs' tests walk them all."""
    parser = argparse.ArgumentParser(
        prog="isu-validate",
        description="Search-based testing of VLM in-car scene understanding, validated against the real world.")
    parser.add_argument("--version", action=_VersionAction)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    wanted = chosen(argv, COMMANDS) if argv is not None else None
    registered = set()
    for name, (module, summary) in COMMANDS.items():
        if argv is None or name == wanted or COMMANDS.get(wanted, ("",))[0] == module:
            if module not in registered:
                registered.add(module)
                register = importlib.import_module(f"isu_validate.commands.{module}").register
                register(sub, argv) if module == "bench" else register(sub)   # bench builds only the one run
        else:
            sub.add_parser(name, help=summary, add_help=False)
    return parser


class _VersionAction(argparse.Action):
    """``--version``: prints the installed version and exits. Looked up only when asked (importlib.metadata
    would cost every other command a tenth of a second)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help="show program's version number and exit"):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_version())
        parser.exit()


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("isu-validate")
    except PackageNotFoundError:
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:  # e.g. `isu-validate export RUN | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print(getattr(args, "interrupted", "interrupted; everything evaluated so far is saved "
                                           "(resume with --resume)"), file=sys.stderr)
        return 130
    except UserError as exc:
        print(f"isu-validate {args.command}: error: {exc.on_command_line()}", file=sys.stderr)
        return 2
    except Exception:
        traceback.print_exc()
        print(f"isu-validate {args.command}: internal error (a bug in isu-validate, not in your input): please "
              "report it with the traceback above and the command you ran", file=sys.stderr)
        return 70   # EX_SOFTWARE


if __name__ == "__main__":
    sys.exit(main())
