import os
import sys

import pytest

# the independent reference codes live next to the tests
sys.path.insert(0, os.path.dirname(__file__))
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(autouse=True, scope="session")
def _threads():
    from ngsolve import SetNumThreads

    SetNumThreads(2)
    yield


@pytest.fixture(scope="module")
def one_thread():
    """For modules of small systems (a few hundred unknowns): one NGSolve thread.  Measured on
    the loaded 2-core machine, two threads outside a TaskManager made each sparse-Cholesky
    refactorisation 0.2 ms -> 16-30 ms."""
    from ngsolve import SetNumThreads

    SetNumThreads(1)
    yield
    SetNumThreads(2)
