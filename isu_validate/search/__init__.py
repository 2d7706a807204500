"""Search over the scene space: NSGA-II and random search, run loop, diversity."""
from .algorithm_names import ALGORITHMS, parse_algorithms
from .algorithms import make_algorithm
from .loop import RunConfig, RunError, RunSummary, SUTErrorsStop, run_search

__all__ = ["ALGORITHMS", "RunConfig", "RunError", "RunSummary", "SUTErrorsStop", "make_algorithm", "parse_algorithms",
           "run_search"]
