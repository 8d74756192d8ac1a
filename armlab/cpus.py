"""How many CPU cores this process may run on (the one place every thread pool asks).

``os.cpu_count()`` counts the machine's cores; a process confined to fewer (``taskset``, a cgroup
cpuset, a SLURM job's ``--cpus-per-task`` through submitit, a container) would then run more
threads than cores, and the rollouts' threads would preempt each other. The affinity mask is
what the scheduler actually grants; where the platform has no such call (macOS, Windows) the
machine's count is used.
"""

from __future__ import annotations

import os

__all__ = ["usable_cpus"]


def usable_cpus() -> int:
    """The number of cores this process may run on (at least 1)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity call on this platform
        return os.cpu_count() or 1
