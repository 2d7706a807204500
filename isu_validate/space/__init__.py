"""The scene space: declarative features, activity, constraints, encoding."""
from .errors import SpaceError
from .features import Feature
from .loader import DEFAULT_SPACE, load_space, space_from_dict
from .scene_file import read_scene_file, scene_of
from .space import Constraint, Question, Scene, SceneSpace

__all__ = ["DEFAULT_SPACE", "Constraint", "Feature", "Question", "Scene", "SceneSpace", "SpaceError",
           "load_space", "read_scene_file", "scene_of", "space_from_dict"]
