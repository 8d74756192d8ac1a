"""`armlab diagnose data=published protocol=fractional_elbow`: the Fig. 4 / Table I study (quick mode)."""

from __future__ import annotations

import json

import pytest

from armlab.errors import ConfigError, DataError
from armlab.protocols.compose import compose
from armlab.reproduction import STUDIES
from armlab.reproduction import fractional as pf


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("pub")
    cfg = compose(["protocol=fractional_elbow"])[1]
    return out, cfg, pf.run_published_fractional(cfg, out, quick=True)


def test_registered_for_the_cli():
    assert STUDIES["fractional_elbow"] is pf.run_published_fractional


def test_distance_is_zero_inside_the_paper_bands_and_counts_misses_in_units():
    inside = {k: 0.5 * (lo + hi) for k, (lo, hi) in pf.PAPER_FIG4.items()}
    assert pf.fig4_distance(inside) == 0.0
    # 2 dB below the DC band and 20 deg above the phase band: 2 + 20 / 10
    off = {**inside, "dc_db": pf.PAPER_FIG4["dc_db"][0] - 2.0, "phase_15_deg": -114.0}
    assert pf.fig4_distance(off) == pytest.approx(4.0)


def test_the_added_effects_move_the_lab_towards_fig4(quick_run):
    _, _, result = quick_run
    before = next(e for e in result["variants"] if e["name"] == "before")
    # before the effects the lab misses Fig. 4 by far more than after (measured 19 vs 0.9, 2 trials)
    assert before["fig4_distance"] > 5 * max(result["nominal"]["fig4_distance"], 1.0)
    assert before["moves_toward_paper"] > 0
    moves = [e["moves_toward_paper"] for e in result["variants"] if e["moves_toward_paper"] is not None]
    assert moves == sorted(moves, reverse=True)  # ranked, largest move first


def test_outputs_are_written_once_and_bad_configs_are_refused(quick_run):
    out, cfg, result = quick_run
    assert json.loads((out / "results.json").read_text())["nominal"] == result["nominal"]
    assert "Table I" in (out / "report.md").read_text()
    with pytest.raises(DataError, match="not empty"):
        pf.run_published_fractional(cfg, out, quick=True)
    with pytest.raises(ConfigError, match="need the fractional_elbow experiment"):
        pf.diagnose_fractional(compose(["protocol=conditioning_window"])[1], quick=True)
