"""The algorithm registry: a name (``run --algorithm``) -> its class. Each algorithm is a small class
behind the ``SearchAlgorithm`` seam (``base.py``): ``random_search.py``, ``nsga2.py``, ``surrogate_search.py``."""
from __future__ import annotations

from ..space import SceneSpace
from .algorithm_names import check_algorithm
from .base import SearchAlgorithm
from .nsga2 import NSGA2Search
from .random_search import RandomSearch
from .surrogate_search import SurrogateSearch

__all__ = ["NSGA2Search", "RandomSearch", "SearchAlgorithm", "SurrogateSearch", "make_algorithm"]


def make_algorithm(name: str, space: SceneSpace, pop_size: int, seed: int) -> SearchAlgorithm:
    classes = {"surrogate": SurrogateSearch, "nsga2": NSGA2Search, "rs": RandomSearch}
    return classes[check_algorithm(name)](space, pop_size, seed)
