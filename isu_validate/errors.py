"""The one base class of the problems a user can fix (a bad option, file, camera, scene, SUT spec).

The command line prints a ``UserError`` as one line and exits with status 2; any other exception is
a bug in isu-validate and keeps its traceback. Domain errors (``SpaceError``, ``CameraFileError``,
``PairsError``...) derive from it, and from ``ValueError`` where callers already catch that.
"""


class UserError(Exception):
    """A problem the user can fix; its message names the problem and the fix."""
