"""Threads for NGSolve: ``SetNumThreads`` must be called before entering ``TaskManager``.

The number of threads is the machine's core count, or ``PACTO_THREADS`` when set;
``PACTO_THREADS=1`` runs serially without a TaskManager.
"""
from __future__ import annotations

import contextlib
import os


def thread_count() -> int:
    env = os.environ.get("PACTO_THREADS", "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            return 1
    return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def compute():
    """Context for the heavy work of a command: NGSolve's TaskManager with the chosen threads."""
    from ngsolve import SetNumThreads, TaskManager

    n = thread_count()
    SetNumThreads(n)
    if n == 1:
        yield
        return
    with TaskManager():
        yield
