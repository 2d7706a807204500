"""Fixtures shared by several test modules."""
import pytest


@pytest.fixture(scope="module")
def few_torch_threads():
    """A shared 2-core machine: two torch threads and single-threaded BLAS (which spins under contention)."""
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads()
    torch.set_num_threads(2)
    with threadpool_limits(limits=1):
        yield
    torch.set_num_threads(before)
