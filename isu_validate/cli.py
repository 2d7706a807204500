"""The ``isu-validate`` command: one entry point, one module per subcommand in ``commands/``."""
from __future__ import annotations

import argparse
import importlib
import sys

# Each module in isu_validate/commands/ defines `register(subparsers)`, which adds its
# subcommand(s) and sets `func` (called with the parsed args, returns an exit code).
COMMAND_MODULES = [
    "run",        # run, export (search + crash-safe archive)
    "bench",      # bench search|render|...
    "render",     # render one scene or N random ones (Blender)
    "people",     # people warm|check (the anny bodies of the renders)
    "report",     # report RUN...: RQ1/RQ2 analysis, statistics, HTML
    "sut",        # sut check
    "reference",  # reference train (the embedded reference ISU)
    "realism",    # realism A B: FID/KID
    "stylize",    # stylize (gatys|fast), stylize train
    "capture",    # capture list|shoot (V4L2, DepthAI, replay)
    "calibrate",  # calibrate IMAGES..., calibrate diff|register
    "recreate",   # recreate RUN...: pairs and printable recreation sheets for a lab
    "agree",      # agree PAIRS: sim/real agreement report; agree votes: validity votes
    "exposure",   # exposure fit|apply|chart|colour|check (the camera's imaging model)
]


class UserError(Exception):
    """A problem the user can fix; printed without a traceback."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="isu-validate",
        description="Search-based testing of VLM in-car scene understanding, validated against the real world.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"isu_validate.commands.{name}").register(sub)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("isu-validate")
    except PackageNotFoundError:
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
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
        print("interrupted; everything evaluated so far is saved (resume with --resume)", file=sys.stderr)
        return 130
    except (UserError, FileNotFoundError, ValueError) as exc:  # SpaceError, PairsError are ValueErrors
        print(f"isu-validate {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
