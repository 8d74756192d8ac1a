"""Benchmark of issue 23's excitation designer (run by `make bench`; the issue's bound: one design
<= 60 s on the 2-core development machine).

Designs the default excitation (DesignConfig(): 120 ms window, 4 segments, expected-error
criterion, 6 seeded SLSQP starts) on the default realistic lab's planning model and prints the
wall time, the knots (scenarios/designed_window.yaml holds them rounded) and the planned errors.
"""

from __future__ import annotations

import time

from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.design import DesignConfig, design_excitation, planning_model


def main() -> None:
    t0 = time.perf_counter()
    model = planning_model(ConditioningWindowConfig())
    t_model = time.perf_counter() - t0
    design = design_excitation(model, DesignConfig())
    knots = ", ".join(f"{k:.3f}" for k in design.waveform.knots)
    err = ", ".join(f"{k} {100 * v:.0f} %" for k, v in design.planned_err.items())
    print(
        f"design: {design.elapsed_s:.1f} s (planning model {t_model:.1f} s; bound 60 s); knots [{knots}]; "
        f"planned error {err}; cond {design.cond:.3g}"
    )


if __name__ == "__main__":
    main()
