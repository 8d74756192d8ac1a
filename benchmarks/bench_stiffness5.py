"""Benchmark of the 5-DoF stiffness protocol (seed paper 001; issue 19; run by `make bench`).

The paper-scale run (the default stages: 30 s of kinematic calibration, 40 inertial holds, 8 pre-load
conditions x 50 disturbances; realistic sensors) as a user starts it, ``armlab run protocol=stiffness_5dof_emg out=<tmp>`` in a fresh Python process, with every
output (trial file, results, figures, recording): its wall time, start-up and imports included,
against issue 19's budget of 60 s on the 2-core machine. Prints::

    <what>: <value> s (target <= 60 s) OK|MISSED

and the run's own stages (simulate, estimate, outputs) beside it. Run on a quiet machine: the
trials' rollout uses every core, so other load lengthens it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TOTAL_S = 60.0  # s, issue 19 ("Done when": the paper-scale protocol in <= 60 s on this machine)
PROTOCOL = "stiffness_5dof_emg"


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "armlab.cli", "run", f"protocol={PROTOCOL}", f"out={out}"]
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        res = json.loads((out / "results.json").read_text())
    t = res["timing"]
    verdict = "OK" if wall <= TOTAL_S else "MISSED"
    print(
        f"{PROTOCOL} paper scale ({res['n_trials']} trials, every output, fresh process): {wall:.1f} s "
        f"(target <= {TOTAL_S:g} s) {verdict}\n"
        f"    simulate {t['simulate_s']:.1f} s, estimate {t['estimate_s']:.1f} s, outputs {t['outputs_s']:.1f} s, "
        f"run total {t['total_s']:.1f} s; 1-min load average before the run {load:.2f}",
        flush=True,
    )


if __name__ == "__main__":
    main()
