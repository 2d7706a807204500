"""Fixtures shared by several test modules."""
from contextlib import contextmanager

import pytest


@contextmanager
def few_threads():
    """A shared 2-core machine: two torch threads and single-threaded BLAS (which spins under contention)."""
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        with threadpool_limits(limits=1):
            yield
    finally:
        torch.set_num_threads(before)


@pytest.fixture(scope="module")
def few_torch_threads():
    with few_threads():
        yield
