import os
import sys

import pytest

# the independent reference codes live next to the tests
sys.path.insert(0, os.path.dirname(__file__))
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")
#: README's test command runs two pytest-xdist workers, one per core: each computes on one
#: thread (two workers of two threads each would oversubscribe the two cores); a run without
#: workers (``-n 0``) computes on two
THREADS = 1 if os.environ.get("PYTEST_XDIST_WORKER") else 2
if THREADS == 1:
    os.environ.setdefault("PACTO_THREADS", "1")


@pytest.fixture(autouse=True, scope="session")
def _threads():
    from ngsolve import SetNumThreads

    SetNumThreads(THREADS)
    yield


@pytest.fixture(scope="module")
def one_thread():
    """For modules of small systems (a few hundred unknowns): one NGSolve thread.  Measured on
    the loaded 2-core machine, two threads outside a TaskManager made each sparse-Cholesky
    refactorisation 0.2 ms -> 16-30 ms."""
    from ngsolve import SetNumThreads

    SetNumThreads(1)
    yield
    SetNumThreads(THREADS)


@pytest.fixture(scope="module")
def pacto_one_thread():
    """PACTO_THREADS=1 for the commands a module's tests and module fixtures run (``main([...])``,
    ``pacto`` subprocesses, ``optimise_case``), for the modules whose tests run pacto commands
    on small runs (``pytestmark = pytest.mark.usefixtures("pacto_one_thread")``).  Measured on
    the shared, loaded 2-core machine: run + analyse 95 s with two threads instead of 20 s;
    tests/cases/test_rewrite_pins.py 71 s (52 s of CPU) instead of 53 s (21 s); pneunet-3d's
    and the other 3D cases' smoke runs with the iterative route 113 s (67 s) instead of 22 s
    (16 s).  The modules without it, and tests/unit/test_threads.py, keep running on two."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        yield
