"""Benchmark of the fractional-elbow protocol (run by `make bench`).

Reports the wall time of the full protocol (2 x 40 s trials at 2 kHz with 0.1 ms physics steps,
all outputs), the simulation speed in simulated seconds per wall second (the force loop steps
MuJoCo from Python once per 0.5 ms control period: the controller reads the sensors every
period, so a batched rollout does not apply), and the estimation time (Welch, Levy sweeps,
five-element fits, fractional sweep).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from armlab.config.schema import ElbowConfig, ScenarioConfig, SensorsConfig, SimConfig
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig
from armlab.runner.run import run_protocol


def main() -> None:
    cfg = FractionalElbowConfig(
        protocol_name="fractional_elbow",
        elbow=ElbowConfig(impedance="fractional"),
        sim=SimConfig(timestep_s=0.0001),  # the protocol's default (configs/protocol/fractional_elbow.yaml)
        sensors=SensorsConfig(fs_hz=2000.0),
        scenario=ScenarioConfig(name="fractional_elbow"),
    )
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
