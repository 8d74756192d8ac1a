"""The cores armlab's thread pools use: the process's affinity, not the machine's count."""

from __future__ import annotations

import os

import pytest

from armlab.cpus import usable_cpus


def test_usable_cpus_is_the_affinity_mask():
    if not hasattr(os, "sched_getaffinity"):
        pytest.skip("no affinity call on this platform")
    assert usable_cpus() == len(os.sched_getaffinity(0))


def test_usable_cpus_follows_a_narrower_mask(monkeypatch):
    # a process confined to one core (taskset, a SLURM job's cpus) gets one thread per pool even
    # on a machine with more cores
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 64)
    assert usable_cpus() == 1


def test_usable_cpus_without_affinity_call_counts_the_machine(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 3)
    assert usable_cpus() == 3
    monkeypatch.setattr(os, "cpu_count", lambda: None)  # undeterminable: one core
    assert usable_cpus() == 1


def test_single_threaded_blas_sets_one_thread_and_restores():
    import numpy  # noqa: F401  (loads NumPy's OpenBLAS)
    import scipy.optimize  # noqa: F401  (loads SciPy's)

    from armlab.cpus import _loaded_openblas, single_threaded_blas

    calls = _loaded_openblas()
    if not calls:
        pytest.skip("no OpenBLAS found loaded (not Linux, or another BLAS)")
    before = [get() for get, _ in calls]
    with single_threaded_blas():
        assert [get() for get, _ in calls] == [1] * len(calls)
    assert [get() for get, _ in calls] == before
