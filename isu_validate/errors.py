"""The one base class of the problems a user can fix (a bad option, file, camera, scene, SUT spec).

The command line prints a ``UserError`` as one line and exits with status 2; any other exception is
a bug in isu-validate and keeps its traceback. Domain errors (``SpaceError``, ``CameraFileError``,
``PairsError``...) derive from it, and from ``ValueError`` where callers already catch that.
"""


class UserError(Exception):
    """A problem the user can fix; its message names the problem and the fix."""


class InputError(UserError, ValueError):
    """A value the user gave (an option, an argument, a file's content) that cannot be used. A
    ``ValueError`` too: callers that catch those (argparse types, older code) keep working."""


class InputNotFound(UserError, FileNotFoundError):
    """A file or folder the user named, or one the installation should hold, is not there."""
