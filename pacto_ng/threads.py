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
def compute(threads: int | None = None):
    """Context for heavy work: NGSolve's TaskManager with ``threads`` (default
    :func:`thread_count`) threads, and numpy's BLAS limited to one thread meanwhile.

    Re-entrant: inside an active one it does nothing (NGSolve ignores, with a warning, a thread
    count set while a TaskManager runs).  A TaskManager is used even with one thread: outside
    it every sparse Cholesky factorisation starts and stops threads of its own (measured 20–45
    ms per call on a loaded 2-core machine, more than factorising a 3000-dof matrix).

    The BLAS limit (threadpoolctl): NGSolve's idle workers keep their cores (they yield, they do
    not sleep), and OpenBLAS's threads, started by the vector operations between NGSolve calls,
    then compete with them for the same cores.  Measured on this 2-core machine, one linear
    pa-inverter analysis with sensitivities at 120 x 80 (29 403 dofs) with two NGSolve threads:
    247 ms with OpenBLAS's default two threads, 74 ms with one (one NGSolve thread: 105 and
    106 ms).
    """
    global _active
    if _active:
        yield
        return
    from ngsolve import SetNumThreads, TaskManager
    from threadpoolctl import threadpool_limits

    SetNumThreads(int(threads) if threads else thread_count())
    _active = True
    try:
        with threadpool_limits(limits=1, user_api="blas"), TaskManager():
            yield
    finally:
        _active = False
