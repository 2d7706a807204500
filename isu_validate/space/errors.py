from ..errors import UserError


class SpaceError(UserError, ValueError):
    """A scene-space file or a scene that breaks the space's rules."""
