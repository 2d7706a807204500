"""Search over the scene space: NSGA-II and random search, run loop, diversity.

Names load on first use (PEP 562): the command line reads ``algorithm_names`` (the algorithms a
user can name) without loading pymoo or scikit-learn. ``RunConfig`` lives in ``isu_validate.config``.
"""
from __future__ import annotations

from ..lazy import lazy_names

# public name -> the submodule it lives in
_NAMES = {
    "ALGORITHMS": ".algorithm_names", "parse_algorithms": ".algorithm_names",
    "make_algorithm": ".algorithms",
    "RunConfig": ".loop", "RunError": ".loop", "RunSummary": ".loop", "SUTErrorsStop": ".loop", "run_search": ".loop",
}

__all__ = sorted(_NAMES)


__getattr__, __dir__ = lazy_names(__name__, _NAMES)
