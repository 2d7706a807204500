"""The one base class of the problems a user can fix (a bad option, file, camera, scene, SUT spec).

The command line prints a ``UserError`` as one line and exits with status 2; any other exception is
a bug in isu-validate and keeps its traceback. Domain errors (``SpaceError``, ``CameraFileError``,
``PairsError``...) derive from it, and from ``ValueError`` where callers already catch that.
"""


# how a message names an option: as a Python caller passes it, and as the command line spells it
PYTHON_WORDS = {"{resume}": "resume=True", "{overwrite}": "overwrite=True"}
COMMAND_LINE_WORDS = {"{resume}": "--resume", "{overwrite}": "--overwrite", "{out}": "--out"}


class UserError(Exception):
    """A problem the user can fix; its message names the problem and the fix."""

    template: str | None = None   # set by ``naming``: the message with its options still as {names}

    @classmethod
    def naming(cls, template: str, argument: str = "out"):
        """An error whose fix names options in the caller's words: ``{resume}``, ``{overwrite}`` and ``{out}``
        read ``resume=True``, ``overwrite=True`` and ``the ARGUMENT argument`` in Python (``str``), ``--resume``,
        ``--overwrite`` and ``--out`` on the command line (``on_command_line``)."""
        error = cls(in_python_words(template, argument))
        error.template = template
        return error

    def on_command_line(self) -> str:
        """The message as the command line prints it."""
        return _worded(self.template, COMMAND_LINE_WORDS) if self.template else str(self)


class InputError(UserError, ValueError):
    """A value the user gave (an option, an argument, a file's content) that cannot be used. A
    ``ValueError`` too: callers that catch those (argparse types, older code) keep working."""


class InputNotFound(UserError, FileNotFoundError):
    """A file or folder the user named, or one the installation should hold, is not there."""


def in_python_words(template: str, argument: str = "out") -> str:
    """``template`` as ``str`` of a ``naming`` error reads it (for errors with a constructor of their own)."""
    return _worded(template, {**PYTHON_WORDS, "{out}": f"the {argument} argument"})


def _worded(template: str, words: dict[str, str]) -> str:
    for name, word in words.items():
        template = template.replace(name, word)
    return template
