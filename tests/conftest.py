import os

import numpy as np
import pytest
import torch

# Two cores on CI: keep torch from oversubscribing them next to Dr.Jit's own thread pool.
torch.set_num_threads(max(1, min(2, os.cpu_count() or 1)))


@pytest.fixture
def one_torch_thread():
    """Run a test on one torch thread: its tensors are tiny, and two threads on a shared 2-core
    machine can be many times slower than one."""
    old = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(old)


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


@pytest.fixture(scope="session")
def mi():
    """The mitsuba module with roomlight's variant active (LLVM on CPU machines)."""
    from roomlight.core.render.variant import mitsuba

    return mitsuba()


@pytest.fixture
def mi_scalar():
    """Mitsuba in 'scalar_rgb' (needs no LLVM); the previous variant is restored afterwards."""
    mi = pytest.importorskip("mitsuba")
    previous = mi.variant()
    mi.set_variant("scalar_rgb")
    yield mi
    if previous is not None:
        mi.set_variant(previous)
