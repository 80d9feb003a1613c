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
