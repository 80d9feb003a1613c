"""pacto_ng.threads.compute: NGSolve's thread count, and numpy's BLAS held at one thread inside
(its threads otherwise compete with NGSolve's idle workers for the cores; see the docstring)."""
import pytest

from pacto_ng.params import InputError
from pacto_ng.threads import compute, core_count, thread_count


def _blas_threads():
    from threadpoolctl import threadpool_info

    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_blas_is_one_thread_inside_and_restored_after():
    import numpy  # noqa: F401  (loads numpy's BLAS)

    before = _blas_threads()
    assert before, "numpy's BLAS is not visible to threadpoolctl"
    with compute(threads=1):
        assert _blas_threads() == [1] * len(before)
        with compute():  # re-entrant: nothing changes inside
            assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


def test_thread_count_from_the_environment(monkeypatch):
    monkeypatch.setenv("PACTO_THREADS", "1")
    assert thread_count() == 1
    monkeypatch.setenv("PACTO_THREADS", str(core_count()))
    assert thread_count() == core_count()
    monkeypatch.delenv("PACTO_THREADS")
    assert thread_count() == core_count()
    monkeypatch.setenv("PACTO_THREADS", "two")
    with pytest.raises(InputError, match="PACTO_THREADS"):
        thread_count()
