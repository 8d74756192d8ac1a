"""How many CPU cores this process may run on (the one place every thread pool asks), and a
block that keeps the BLAS libraries on one thread (:func:`single_threaded_blas`).

``os.cpu_count()`` counts the machine's cores; a process confined to fewer (``taskset``, a cgroup
cpuset, a SLURM job's ``--cpus-per-task`` through submitit, a container) would then run more
threads than cores, and the rollouts' threads would preempt each other. The affinity mask is
what the scheduler actually grants; where the platform has no such call (macOS, Windows) the
machine's count is used.
"""

from __future__ import annotations

import ctypes
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["single_threaded_blas", "usable_cpus"]


def usable_cpus() -> int:
    """The number of cores this process may run on (at least 1)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity call on this platform
        return os.cpu_count() or 1


# (get, set) thread-count functions of the OpenBLAS builds NumPy and SciPy bundle (scipy-openblas,
# 64-bit and 32-bit integer builds) and of a plain OpenBLAS, tried in this order per library
_OPENBLAS_CALLS = (
    ("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
    ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
    ("openblas_get_num_threads", "openblas_set_num_threads"),
)


def _loaded_openblas() -> list[tuple[Callable[[], int], Callable[[int], None]]]:
    """The (get, set) thread-count calls of every OpenBLAS this process has loaded (Linux:
    ``/proc/self/maps``; none elsewhere)."""
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line and ".so" in line})
    except OSError:
        return []
    calls = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)  # already loaded: the same handle, no second copy
        except OSError:
            continue
        for get, set_ in _OPENBLAS_CALLS:
            if hasattr(lib, get) and hasattr(lib, set_):
                calls.append((getattr(lib, get), getattr(lib, set_)))
                break
    return calls


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Run the block with every loaded OpenBLAS on one thread, then restore their counts.

    For many small dense operations in a row (an L-BFGS fit of a small network: each step a few
    BLAS calls on vectors of a few thousand entries): OpenBLAS wakes its worker threads for each
    call, which costs more than the call itself, and on a loaded machine far more (measured on the
    2-core machine under load: SciPy's L-BFGS-B fit of the EMG network 4.1 s with two threads,
    1.0 s with one). Not for large matrix products, which the threads do speed up.
    """
    calls = _loaded_openblas()
    before = [get() for get, _ in calls]
    for _, set_ in calls:
        set_(1)
    try:
        yield
    finally:
        for (_, set_), n in zip(calls, before, strict=True):
            set_(n)
