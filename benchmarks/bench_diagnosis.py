"""Benchmark of `armlab diagnose` (run by `make bench`).

Targets: one diagnosis with about ten candidates under 60 s on the 2-core CI machine (issue 5);
one diagnosis of the REKLAB ankle folder within 20 s (issue 21). Each is printed as
``<what>: <value> (target <op> <value>) OK|MISSED``. Times the diagnosis alone (import, preparation, noise floor, every candidate fitted in each
greedy step, where/how-far breakdowns; no figures) on

- a referee dataset of the joint_1dof protocol (4 trials x 30 s at 1 kHz, a hidden reflex),
- the six real REKLAB ankle recordings pooled (5 x 60 s + 106 s at 1 kHz), when present, and
- a referee dataset of the conditioning_window protocol (30 trials of 0.85 s, window k = 26, a
  hidden reflex and compliant cuff; 5 identifiable candidates, 2 flagged as absorbed).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from armlab.config.diagnosis import DiagnosisConfig, RefereeConfig
from armlab.data.reklab import DEFAULT_REKLAB_ROOT
from armlab.diagnosis.attribution import select_candidates
from armlab.protocols.conditioning_window.diagnosis.models import COND_SURROGATES
from armlab.protocols.conditioning_window.diagnosis.referee import make_cond_dataset
from armlab.protocols.joint_1dof.diagnosis.diagnose import candidate_names
from armlab.protocols.joint_1dof.diagnosis.referee import make_dataset
from armlab.runner.diagnose import run_diagnoser

TARGET_S = 60.0  # s, issue 5: one diagnosis with about ten candidates
REKLAB_S = 20.0  # s, issue 21: one diagnosis of the REKLAB ankle folder


def _verdict(what: str, wall: float, target: float) -> str:
    return f"{what}: {wall:.1f} s (target <= {target:g} s) {'OK' if wall <= target else 'MISSED'}"


def _time(folder: Path, cfg: DiagnosisConfig, protocol: str = "joint_1dof") -> tuple[float, dict]:
    t0 = time.perf_counter()
    results, _ = run_diagnoser(folder, protocol, cfg)
    return time.perf_counter() - t0, results


def main() -> None:
    cfg = DiagnosisConfig()
    n_cand = len(candidate_names(cfg))
    with tempfile.TemporaryDirectory() as tmp:
        ds = make_dataset("reflex", 0, RefereeConfig(), cfg, Path(tmp) / "trials")
        wall, res = _time(ds.folder, cfg)
    print(
        _verdict(f"diagnose joint_1dof referee dataset (4 x 30 s, {n_cand} candidates)", wall, TARGET_S)
        + f"; verdict {res['verdict']}"
    )
    if DEFAULT_REKLAB_ROOT.is_dir():
        wall, res = _time(DEFAULT_REKLAB_ROOT, cfg)
        what = f"diagnose joint_1dof REKLAB ankle folder ({len(res['trials'])} trials, {n_cand} candidates)"
        print(_verdict(what, wall, REKLAB_S) + f"; verdict {res['verdict']}")
    else:
        print(f"diagnose joint_1dof REKLAB ankle folder: MISSED, no data at {DEFAULT_REKLAB_ROOT}")
    ref = RefereeConfig(protocol="conditioning_window")
    n_cond = len(select_candidates(cfg, COND_SURROGATES, "conditioning_window"))
    with tempfile.TemporaryDirectory() as tmp:
        ds = make_cond_dataset("reflex+cuff_compliance", 0, ref, cfg, Path(tmp) / "trials")
        wall, res = _time(ds.folder / "trials.h5", cfg, "conditioning_window")
    what = f"diagnose conditioning_window referee dataset ({len(res['trials'])} trials, {n_cond} candidates)"
    print(_verdict(what, wall, TARGET_S) + f"; verdict {res['verdict']}")


if __name__ == "__main__":
    main()
