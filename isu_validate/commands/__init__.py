"""Subcommands of ``isu-validate``; see ``isu_validate.cli.COMMAND_MODULES``."""
