"""Search over the scene space: NSGA-II and random search, run loop, diversity."""
from .algorithms import ALGORITHMS, make_algorithm
from .loop import RunConfig, RunError, RunSummary, SUTErrorsStop, run_search

__all__ = ["ALGORITHMS", "RunConfig", "RunError", "RunSummary", "SUTErrorsStop", "make_algorithm", "run_search"]
