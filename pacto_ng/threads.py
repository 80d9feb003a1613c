"""Threads for NGSolve: ``SetNumThreads`` must be called before entering ``TaskManager``.

The number of threads is the number of cores this process may use (:func:`core_count`), or
``PACTO_THREADS`` when set: a whole number from 1 to that count.  Anything else is refused with
one line naming PACTO_THREADS (an :class:`~pacto_ng.params.InputError`, exit code 2 from the
CLI), not capped: more threads than cores only slows NGSolve down, and very many break it.
Measured on this 2-core machine (a VectorH1 order-2 sparse Cholesky factorisation of 20 000
dofs): 0.41 s with 2 threads, 1.4 s with 32, 3.2 s with 64; ``pacto run mbb`` with 64 threads
stopped in a Netgen local-heap error, and 10^5 threads took 13 GB of memory before any work.
``0``, ``-1`` (formerly run silently as 1 thread) and non-integers are refused the same way.
"""
from __future__ import annotations

import contextlib
import math
import os
from pathlib import Path

from .errors import InputError


def core_count() -> int:
    """The cores this process may run on: its CPU affinity (``taskset``, a container's or a
    batch job's cpuset), lowered by a cgroup CPU quota if one is set (``cpu.max`` in cgroup v2,
    ``cpu.cfs_quota_us / cpu.cfs_period_us`` in v1)."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        n = os.cpu_count() or 1
    quota = _cgroup_cpu_quota()
    if quota is not None:
        n = min(n, max(1, math.ceil(quota)))
    return max(1, n)


def _cgroup_cpu_quota() -> float | None:
    """CPUs allowed by the cgroup's quota (None: no quota, or no cgroup file to read)."""
    for path, split in ((Path("/sys/fs/cgroup/cpu.max"), True),
                        (Path("/sys/fs/cgroup/cpu/cpu.cfs_quota_us"), False)):
        try:
            text = path.read_text().split()
            if split:
                quota, period = text[0], text[1]
            else:
                quota = text[0]
                period = (path.parent / "cpu.cfs_period_us").read_text().split()[0]
        except (OSError, IndexError):
            continue
        if quota in ("max", "-1"):
            return None
        try:
            q, p = float(quota), float(period)
        except ValueError:
            return None
        return q / p if q > 0 and p > 0 else None
    return None


def thread_count() -> int:
    """NGSolve's thread count: ``PACTO_THREADS`` if set (1 to :func:`core_count`), else
    :func:`core_count`.  A bad value raises an InputError naming PACTO_THREADS."""
    env = os.environ.get("PACTO_THREADS", "").strip()
    cores = core_count()
    if not env:
        return cores
    allowed = f"give 1 to {cores}, or unset it to use all {cores}"
    shown = env if len(env) <= 12 else f"{env[:9]}..."
    try:
        n = int(env)
    except ValueError:
        raise InputError(f"PACTO_THREADS: expected a whole number of threads, got '{shown}' "
                         f"({allowed})") from None
    if n < 1:
        raise InputError(f"PACTO_THREADS={shown}: the thread count must be at least 1 ({allowed})")
    if n > cores:
        raise InputError(f"PACTO_THREADS={shown}: more threads than the {cores} cores this "
                         f"process may use, which only slows NGSolve down ({allowed})")
    return n


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
