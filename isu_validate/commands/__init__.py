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
