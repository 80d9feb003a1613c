"""Threads for NGSolve: ``SetNumThreads`` must be called before entering ``TaskManager``.

The number of threads is the machine's core count, or ``PACTO_THREADS`` when set.
"""
from __future__ import annotations

import contextlib
import os


def thread_count() -> int:
    from .params import InputError

    env = os.environ.get("PACTO_THREADS", "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            raise InputError(f"PACTO_THREADS: expected a positive integer, got '{env}'") from None
    return max(1, os.cpu_count() or 1)


_active = False


@contextlib.contextmanager
def compute():
    """Context for heavy work: NGSolve's TaskManager with :func:`thread_count` threads.

    Re-entrant: inside an active one it does nothing (NGSolve ignores, with a warning, a thread
    count set while a TaskManager runs).  A TaskManager is used even with one thread: outside
    it every sparse Cholesky factorisation starts and stops threads of its own (measured 20–45
    ms per call on a loaded 2-core machine, more than factorising a 3000-dof matrix).
    """
    global _active
    if _active:
        yield
        return
    from ngsolve import SetNumThreads, TaskManager

    SetNumThreads(thread_count())
    _active = True
    try:
        with TaskManager():
            yield
    finally:
        _active = False
