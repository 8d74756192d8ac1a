"""Real-time factor of every registered protocol (issue 21: each >= 30x; run by `make bench`).

For each protocol that ``armlab run`` runs, its default configuration (as ``armlab run
protocol=<name>`` composes it) is run once through :func:`armlab.runner.run.run_protocol` with
figures, recording and the trial file off (outputs are written after the simulation and do not
change it), and the recorded seconds of all trials are divided by the wall time of the
simulation stage (``timing.simulate_s``; settling before each trial is simulated but not counted).
A protocol without a simulated run (``Protocol.runs`` false) is listed as not applicable.

One line per protocol::

    <protocol>: <x> simulated s per wall s (target >= 30) OK|MISSED

and, for a protocol with a wall-time target of its whole default run (:data:`RUN_WALL_TARGETS_S`),
the wall time of ``armlab run protocol=<name>`` in a new process, imports, figures, recording and
files included::

    <protocol> default run, wall time with outputs: <t> s (target <= 30 s) OK|MISSED

Run on a quiet machine: other load on the cores lowers the figure (the trials use every core).
Usage: ``python benchmarks/bench_realtime.py [protocol ...]`` (default: every registered one).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from armlab.protocols import registry
from armlab.protocols.compose import compose
from armlab.runner.run import run_protocol

# simulated s per wall s: issue 21 ("every protocol >= 30x real time"), so a protocol's default
# run simulates its trials in seconds, not minutes, on the 2-core machine of CI and the README
TARGET_REALTIME = 30.0
_NO_OUTPUTS = (
    "output.figures=false",
    "output.recording=false",
    "output.trials=false",
    "output.print_table=false",
)

#: s, wall time of a protocol's whole default run (``armlab run protocol=<name>``, outputs included):
#: issue 20 ("`armlab run protocol=cartesian_online` (level B default) <= 30 s on this machine")
RUN_WALL_TARGETS_S = {"cartesian_online": 30.0}


def run_wall_time(name: str) -> float:
    """Wall seconds of ``armlab run protocol=<name>`` (defaults, every output) in a new process."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "armlab.cli", "run", f"protocol={name}", f"out={tmp}/run"],
            check=True,
            capture_output=True,
        )
        return time.perf_counter() - t0


def realtime(name: str) -> tuple[float, dict]:
    """(simulated s per wall s of the simulation stage, the run's results) of one default run."""
    _, exp = compose([f"protocol={name}", *_NO_OUTPUTS])
    with tempfile.TemporaryDirectory() as tmp:
        res = run_protocol(exp, Path(tmp) / "run")
    return res["simulated_s"] / res["timing"]["simulate_s"], res


def main(names: list[str]) -> None:
    for protocol in registry.protocols():
        if names and protocol.name not in names:
            continue
        if not protocol.runs:
            print(f"{protocol.name}: no simulated run (`armlab run` refuses it); not applicable")
            continue
        ratio, res = realtime(protocol.name)
        verdict = "OK" if ratio >= TARGET_REALTIME else "MISSED"
        print(
            f"{protocol.name}: {ratio:.1f} simulated s per wall s (target >= {TARGET_REALTIME:g}) {verdict}\n"
            f"    {res['simulated_s']:g} s of trials simulated in {res['timing']['simulate_s']:.2f} s",
            flush=True,
        )
        if protocol.name in RUN_WALL_TARGETS_S:
            wall, target = run_wall_time(protocol.name), RUN_WALL_TARGETS_S[protocol.name]
            print(
                f"{protocol.name} default run, wall time with outputs: {wall:.1f} s (target <= {target:g} s) "
                f"{'OK' if wall <= target else 'MISSED'}",
                flush=True,
            )


if __name__ == "__main__":
    main(sys.argv[1:])
