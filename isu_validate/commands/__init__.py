"""Subcommands of ``isu-validate``: one module per command (``isu_validate.cli.COMMANDS`` maps them)."""
from __future__ import annotations


def chosen(argv: list[str] | None, names) -> str | None:
    """The first word of ``argv`` that names one of ``names`` (options before it take no values)."""
    for word in argv or ():
        if not word.startswith("-"):
            return word if word in names else None
    return None
