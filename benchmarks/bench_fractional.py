"""Benchmark of the fractional-elbow protocol (run by `make bench`).

Reports the wall time of the full protocol with its default configuration (as ``armlab run
protocol=fractional_elbow`` composes it: 2 x 40 s trials at 2 kHz with 0.1 ms physics steps, the
Hill elbow with its stretch reflex, all outputs), the simulation speed in simulated seconds per
wall second (the force loop's control periods run compiled and step MuJoCo in C, the trials
concurrently on threads: :mod:`armlab.sim.force_kernel`; the target is checked by
``bench_realtime.py``; the very first run on a machine also compiles the kernel, a few seconds
that later runs read from numba's cache), and the estimation time (Welch, Levy sweeps, five-element fits,
fractional sweep).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from armlab.protocols.compose import compose
from armlab.runner.run import run_protocol


def main() -> None:
    _, cfg = compose(["protocol=fractional_elbow"])
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run_protocol(cfg, Path(tmp) / "run")
        wall = time.perf_counter() - t0
    tim = res["timing"]
    print(
        f"fractional_elbow: {wall:.1f} s wall; simulate {tim['simulate_s']:.1f} s "
        f"({res['simulated_s'] / tim['simulate_s']:.1f} simulated s per wall s), "
        f"estimate {tim['estimate_s']:.2f} s, outputs {tim['outputs_s']:.1f} s"
    )


if __name__ == "__main__":
    main()
