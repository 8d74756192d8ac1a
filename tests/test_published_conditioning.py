"""armlab.reproduction.conditioning: the paper's window thresholds as measurements.

Simulations run in quick mode (5 windows x 7 trials, about 1 s each); the scoring and ranking
are checked on hand-made results.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from armlab.cli import compose
from armlab.errors import ConfigError, DataError
from armlab.protocols.conditioning_window.experiment import PAPER_THRESHOLDS_S
from armlab.reproduction import conditioning as pc


@pytest.fixture(scope="module")
def cfg():
    return compose(["protocol=conditioning_window"])[1]


@pytest.fixture(scope="module")
def gap(cfg):
    return pc.threshold_gap(cfg, quick=True)


@pytest.fixture(scope="module")
def diagnosis(cfg):
    catalogue = {v.name: v for v in pc.candidate_variants(cfg)}
    variants = [
        # two variants that move the thresholds in opposite directions (quick mode, summed
        # distance to the paper's: 190 ms with reflexes off, 250 nominal, 370 with a rigid cuff)
        catalogue["reflex_off"],
        catalogue["cuff_rigid"],
        # not physical: the protocol is simulated again with the same seed, so must repeat nominal
        pc.Variant(name="repeat", effect="none", description="same physics, no table",
                   set_values=(("output.print_table", False),)),
    ]  # fmt: skip
    return pc.diagnose_thresholds(cfg, variants, quick=True)


def _crit(gap_ms):
    """A hand-made criterion entry of a gap dict."""
    return {"gap_ms": gap_ms}


def test_thresholds_lie_on_the_window_grid(gap):
    windows = gap["windows_s"]
    # quick mode: T_obs = 40 ms + k x 10 ms + 70 ms for k = 2, 8, 14, 20, 26, then the extension windows
    assert windows == pytest.approx([0.13, 0.19, 0.25, 0.31, 0.37, 0.40, 0.45, 0.50])
    for c in pc.CRITERIA:
        sim = gap["criteria"][c]["simulated_s"]
        assert sim is None or min(abs(sim - w) for w in windows) < 1e-9, (c, sim)


def test_threshold_gap_reports_the_published_values(gap):
    paper = {c: gap["criteria"][c]["paper_s"] for c in pc.CRITERIA}
    assert paper == {"K_pd": 0.32, "symmetric": 0.37, "constant": 0.40}
    assert paper["K_pd"] == PAPER_THRESHOLDS_S["K_pd_after_s"]
    for c in pc.CRITERIA:
        g = gap["criteria"][c]
        assert g["reached"], c  # the nominal lab reaches all three within the quick windows
        assert g["gap_ms"] == pytest.approx((g["simulated_s"] - g["paper_s"]) * 1e3)


def test_distance_sums_scored_gaps_and_penalises_unreached():
    gap = {"K_pd": _crit(-130.0), "symmetric": _crit(None), "constant": _crit(50.0)}
    assert pc.distance_ms(gap) == 130.0 + pc.NOT_REACHED_PENALTY_MS
    assert pc.distance_ms(gap, ("K_pd", "constant")) == 180.0
    with pytest.raises(ConfigError, match=r"valid: \['K_pd', 'symmetric', 'constant'\]"):
        pc.distance_ms(gap, ("stiff",))


def test_ranking_puts_the_smallest_distance_first_and_failures_last():
    entries = [
        {"name": "b", "distance_ms": 50.0},
        {"name": "failed", "distance_ms": None},
        {"name": "z", "distance_ms": 10.0},
        {"name": "a", "distance_ms": 10.0},
        {"name": "exact", "distance_ms": 0.0},
    ]
    assert [e["name"] for e in pc.rank_variants(entries)] == ["exact", "a", "z", "b", "failed"]


def test_variants_change_the_config_as_documented(cfg):
    names = [v.name for v in pc.candidate_variants(cfg)]
    assert 0 < len(names) <= 12 and len(set(names)) == len(names)  # names are unique
    variants = {v.name: v for v in pc.candidate_variants(cfg)}
    for v in variants.values():
        assert v.apply(cfg) != cfg, v.name
    gain = variants["reflex_gain_x2"].apply(cfg).reflex
    assert gain.stretch_gain == 2 * cfg.reflex.stretch_gain
    assert gain.spinal_gain == 2 * cfg.reflex.spinal_gain
    assert variants["reflex_latency_25ms"].apply(cfg).reflex.stretch_latency_s == 0.025
    assert (
        variants["cuff_stiffness_x0.5"].apply(cfg).cuff.stiffness_N_per_m == 0.5 * cfg.cuff.stiffness_N_per_m
    )
    # toggles are relative to the nominal: with reflexes off the candidate switches them on
    off = replace(cfg, reflex=replace(cfg.reflex, enabled=False))
    assert "reflex_on" in {v.name for v in pc.candidate_variants(off)}


def test_variant_errors_name_the_valid_choices(cfg):
    bad_group = pc.Variant(name="x", effect="x", description="x", set_values=(("reflexes.enabled", False),))
    with pytest.raises(ConfigError, match="unknown group 'reflexes'; valid: .*'reflex'"):
        bad_group.apply(cfg)
    with pytest.raises(ConfigError, match="unknown field 'gain'; valid: .*'stretch_gain'"):
        pc.Variant(name="x", effect="x", description="x", scale=(("reflex.gain", 2.0),)).apply(cfg)
    with pytest.raises(ConfigError, match=r"cocontraction must lie in \(0, 1\)"):
        pc.Variant(name="x", effect="x", description="x", scale=(("arm.cocontraction", 10.0),)).apply(cfg)


def test_rejects_other_protocols_and_untyped_configs(cfg):
    with pytest.raises(
        ConfigError, match="need the conditioning_window experiment, got FractionalElbowConfig"
    ):
        pc.threshold_gap(compose(["protocol=fractional_elbow"])[1])
    with pytest.raises(ConfigError, match=r"compose\(\['protocol=conditioning_window'\]\)\[1\]"):
        pc.threshold_gap(compose(["protocol=conditioning_window"])[0])


def test_diagnosis_is_paired_and_ranked(diagnosis, gap):
    nominal = diagnosis["nominal"]
    # same seed, same windows as threshold_gap's nominal run: identical thresholds
    assert nominal["criteria"] == gap["criteria"]
    assert nominal["distance_ms"] == pc.distance_ms(nominal["criteria"])
    by_name = {e["name"]: e for e in diagnosis["variants"]}
    assert by_name["repeat"]["criteria"] == nominal["criteria"]  # re-simulated: deterministic
    assert by_name["repeat"]["shrink_ms"] == 0.0
    # ranked by distance: reflexes off closer than the nominal, a rigid cuff farther
    assert [e["name"] for e in diagnosis["variants"]] == ["reflex_off", "repeat", "cuff_rigid"]
    distances = [e["distance_ms"] for e in diagnosis["variants"]]
    assert distances[0] < nominal["distance_ms"] < distances[2]
    for e in diagnosis["variants"]:
        assert e["error"] is None
        assert e["shrink_ms"] == pytest.approx(nominal["distance_ms"] - e["distance_ms"])
    verdict = diagnosis["verdict"]
    assert verdict["best"] == "reflex_off" and verdict["best_distance_ms"] == distances[0]


def test_report_has_every_row_and_the_verdict(diagnosis):
    text = pc.format_report(diagnosis)
    assert text.startswith("# Published conditioning thresholds")
    assert "| K positive definite | 320 |" in text
    for e in diagnosis["variants"]:
        assert f"| {e['name']} |" in text
    assert diagnosis["verdict"]["text"] in text


def test_run_writes_once_and_never_overwrites(cfg, tmp_path):
    one = [pc.Variant(name="lowpass_40hz", effect="filter", description="low-pass 40 Hz",
                      set_values=(("estimator.lowpass_hz", 40.0),))]  # fmt: skip
    result = pc.run_published_conditioning(cfg, tmp_path / "run", quick=True, variants=one)
    assert (tmp_path / "run" / "results.json").is_file()
    assert (tmp_path / "run" / "report.md").read_text() == pc.format_report(result)
    # an existing report alone is enough to refuse, before any simulation, and it stays as it was
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "report.md").write_text("mine")
    with pytest.raises(DataError, match="never overwrites"):
        pc.run_published_conditioning(cfg, tmp_path / "other", quick=True, variants=one)
    assert (tmp_path / "other" / "report.md").read_text() == "mine"
    assert not (tmp_path / "other" / "results.json").exists()
