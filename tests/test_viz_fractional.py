"""Figures, table and Rerun recording of the fractional_elbow protocol, from small synthetic inputs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import assert_png

from armlab.data.trial import TrialSet
from armlab.errors import ConfigError, DataError
from armlab.viz import (
    format_fractional_table,
    plot_bode_fits,
    plot_bode_literature,
    plot_time_overlay,
    write_fractional_recording,
)

L_M = 0.35
FS_HZ = 2000.0
PAPER_TABLE_I = {
    "27": {"alpha": 1.0, "mse": 2.70e-7, "mad": 3.52e-4, "r2": 0.94, "n_params": 5},
    "28": {"alpha": 1.4, "mse": 5.14e-7, "mad": 5.01e-4, "r2": 0.89, "n_params": 4},
    "29": {"alpha": 1.1, "mse": 8.4e-7, "mad": 6.37e-4, "r2": 0.82, "n_params": 3},
    "A": {"alpha": 1.0, "mse": 11.52e-7, "mad": 6.71e-4, "r2": 0.8, "n_params": 3},
    "B": {"alpha": 1.0, "mse": 11.59e-7, "mad": 6.72e-4, "r2": 0.8, "n_params": 4},
}


def _second_order(f_hz: np.ndarray, gain: float = 5e-3, fn_hz: float = 5.0, zeta: float = 0.3) -> np.ndarray:
    """θ/F (rad/N) of a mass-spring-damper arm: gain / ((s/ωn)² + 2ζ s/ωn + 1)."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float) / (2 * np.pi * fn_hz)
    return gain / (s**2 + 2 * zeta * s + 1)


def _series(with_truth: bool = True) -> dict:
    """A series dict in the protocol's schema: measured, fitted and literature responses, overlay."""
    rng = np.random.default_rng(3)
    f = np.geomspace(0.12, 15.0, 80)
    g_true = _second_order(f)
    G = g_true * (1 + 0.03 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)))
    fits = {
        "27": _second_order(f, 5.1e-3, 5.1, 0.28),
        "28": _second_order(f, 4.8e-3, 5.3, 0.35),
        "29": _second_order(f, 4.0e-3, 6.0, 0.5),
        "A": _second_order(f, 3.0e-3, 6.5, 0.6),
        "B": _second_order(f, 3.2e-3, 6.2, 0.55),
        "fractional_five_element": _second_order(f, 5.0e-3, 5.0, 0.31),
    }
    literature = {
        name: _second_order(f, gain, fn, 0.7)
        for name, gain, fn in (
            ("Diaz", 1.0e-2, 3.0),
            ("Speich", 1.1e-2, 2.8),
            ("Vlugt", 1.4e-3, 3.8),
            ("Fu", 5.0e-3, 2.8),
            ("Tejado", 3.7e-3, 8.3),
        )
    }
    t = 5.0 + np.arange(3000) / 200.0
    force = sum(np.sin(2 * np.pi * fk * t + k) for k, fk in enumerate((0.3, 1.1, 2.7, 4.9, 7.3)))
    theta = 5e-3 * np.convolve(force, np.exp(-np.arange(40) / 8.0) / 8.0, mode="same")
    models = {k: theta * (1 + 0.05 * j) for j, k in enumerate(fits)}
    vaf = {k: 100.0 * (1 - np.var(theta - m) / np.var(theta)) for k, m in models.items()}
    return {
        "f_hz": f,
        "G": G,
        "coherence": np.full(f.size, 0.97),
        "G_true": g_true if with_truth else None,
        "fits": fits,
        "literature": literature,
        "time": {"t_s": t, "force_N": force, "theta_rad": theta, "models": models, "vaf_pct": vaf},
    }


def _model_entry(alpha: float, r2: float, n_params: int, truth: bool) -> dict:
    entry = {"alpha": alpha, "mse": 3e-7 / r2, "mad": 4e-4 / r2, "r2": r2, "n_params": n_params}
    entry["bandwidth_hz"] = 7.0 + r2
    if truth:
        entry["rel_rms_error_vs_truth"] = 1.0 - r2
    return entry


def _results(truth: bool = True) -> dict:
    """A results dict in the protocol's schema; ``truth=False`` drops what only a simulation has."""
    models = {
        "27": _model_entry(1.0, 0.99, 6, truth),
        "28": _model_entry(1.7, 0.96, 4, truth),
        "29": _model_entry(0.6, 0.75, 3, truth),
        "A": _model_entry(1.0, 0.44, 3, truth),
        "B": _model_entry(1.0, 0.59, 4, truth),
    }
    orders = np.round(np.arange(1, 20) * 0.1, 10)
    frac = {
        "best_order": 0.5,
        "orders": orders.tolist(),
        "cost": (0.01 + (orders - 0.5) ** 2).tolist(),
        "mse": (1.4e-7 + 1e-6 * (orders - 0.5) ** 2).tolist(),
        "best": {"M": 0.59, "k1": 2015.0, "k2": 478.6, "d1": 9.41, "d2": 68.7},
    }
    results = {
        "protocol": "fractional_elbow",
        "models": models,
        "paper_table_I": PAPER_TABLE_I,
        "time_vaf_pct": {
            "27": 99.1,
            "28": 95.9,
            "29": 84.0,
            "A": 71.7,
            "B": 78.7,
            "fractional_five_element": 99.3,
        },
        "tracking_error": [0.137, 0.142],
        "literature_bandwidth_hz": {"Diaz": 3.14, "Speich": 2.86, "Vlugt": 3.87, "Fu": 2.81, "Tejado": 8.27},
        "five_element_fit": {"M": 0.53, "k1": 2088.6, "k2": 675.0, "d1": 7.58, "d2": 7.85},
        "fractional_five_element": frac,
    }
    if truth:
        frac["true_order"] = 0.5
        frac["rel_err"] = {"M": 0.013, "k1": 0.008, "k2": 0.023, "d1": 0.059, "d2": 0.052}
        results["five_element_rel_err"] = {"M": 0.02, "k1": 0.01, "k2": 0.03, "d1": 0.04, "d2": 0.05}
    return results


def _trials(n_trials: int = 2, n_samples: int = 4000, with_link: bool = True) -> TrialSet:
    """Two short trials with every channel the protocol records."""
    rng = np.random.default_rng(4)
    t = np.arange(n_samples) / FS_HZ
    f_ref = np.stack(
        [2.0 * np.sin(2 * np.pi * 1.3 * t + k) + np.sin(2 * np.pi * 6.1 * t) for k in range(n_trials)]
    )
    f_meas = f_ref + 0.02 * rng.standard_normal(f_ref.shape)
    theta = 5e-3 * np.roll(f_ref, 20, axis=1)
    phi = 0.95 * np.roll(theta, 10, axis=1)
    chans = {
        "f_ref": f_ref,
        "f_measured": f_meas,
        "f_true": f_ref,
        "theta_measured": theta + 1e-5 * rng.standard_normal(theta.shape),
        "theta_true": theta,
        "phi_true": phi,
        "current": 0.4 * f_ref,
        "tau_motor": L_M * f_ref,
    }
    units = {"f_ref": "N", "f_measured": "N", "f_true": "N", "current": "A", "tau_motor": "N*m"}
    units.update({k: "rad" for k in ("theta_measured", "theta_true", "phi_true")})
    return TrialSet(
        fs_hz=FS_HZ,
        onset_index=np.ones(n_trials, dtype=int),
        channels={k: v[..., None] for k, v in chans.items()},
        units=units,
        trial_meta={"tracking_error": np.full(n_trials, 0.14)},
        attrs={"protocol": "fractional_elbow", "link_length_m": L_M} if with_link else {},
    )


@pytest.mark.parametrize(
    "plot",
    [
        lambda s, r, p: plot_bode_fits(s, r, p),
        lambda s, r, p: plot_bode_literature(s, p, results=r),
        lambda s, r, p: plot_time_overlay(s, p, seconds=5.0),
    ],
    ids=["bode_fits", "bode_literature", "time_overlay"],
)
def test_plots_write_png_and_refuse_overwrite(tmp_path, plot):
    series, results = _series(), _results()
    path = plot(series, results, tmp_path / "fig.png")
    assert path == tmp_path / "fig.png"
    assert_png(path)
    before = path.read_bytes()
    with pytest.raises(DataError, match="fig.png"):
        plot(series, results, path)
    assert path.read_bytes() == before
    with pytest.raises(DataError, match=r"\.png"):
        plot(series, results, tmp_path / "fig.jpg")


def test_plots_handle_real_data_without_truth(tmp_path):
    series = _series(with_truth=False)
    del series["literature"]
    series["fits"] = {"27": series["fits"]["27"], "28": None}
    del series["time"]["models"]["A"]
    results = _results(truth=False)
    assert_png(plot_bode_fits(series, results, tmp_path / "a.png"))
    assert_png(plot_bode_fits(series, None, tmp_path / "b.png"))
    assert_png(plot_bode_literature(series, tmp_path / "c.png"))
    assert_png(plot_time_overlay(series, tmp_path / "d.png", models=["27", "28"]))


def test_plots_reject_bad_input(tmp_path):
    series = _series()
    with pytest.raises(DataError, match="'G'"):
        plot_bode_fits({"f_hz": series["f_hz"]}, None, tmp_path / "a.png")
    with pytest.raises(DataError, match="shape"):
        plot_bode_fits({**series, "G_true": series["G_true"][:-1]}, None, tmp_path / "b.png")
    with pytest.raises(DataError, match="Fu"):
        plot_bode_literature({**series, "literature": {"Fu": series["G"][:3]}}, tmp_path / "b.png")
    with pytest.raises(DataError, match="'time'"):
        plot_time_overlay({k: v for k, v in series.items() if k != "time"}, tmp_path / "c.png")
    with pytest.raises(ConfigError, match="seconds"):
        plot_time_overlay(series, tmp_path / "d.png", seconds=0.0)
    assert not any(tmp_path.iterdir())


def test_table_lists_every_model_and_the_paper():
    text = format_fractional_table(_results())
    lines = text.splitlines()
    for label in ("(27)", "(28)", "(29)", "A", "B", "frac. five-element"):
        assert any(line.startswith(label) for line in lines), label
    paper_cells = {  # Table I of seeds/004 beside each model: alpha, MSE x1e7, MAD x1e4, R²
        "(27)": ("1.0", "2.70", "3.52", "0.94"),
        "(28)": ("1.4", "5.14", "5.01", "0.89"),
        "(29)": ("1.1", "8.40", "6.37", "0.82"),
        "A ": ("1.0", "11.52", "6.71", "0.80"),
        "B ": ("1.0", "11.59", "6.72", "0.80"),
    }
    for label, cells in paper_cells.items():
        row = next(line for line in lines if line.startswith(label))
        assert row.split("|")[-1].split()[:4] == list(cells), (label, row)
    assert "best fractional order β = 0.5 (true 0.5)" in text
    assert "13.7 %" in text and "14.2 %" in text
    assert "k1 = 2089 N/m" in text
    assert "rel. error vs the intrinsic truth" in text
    assert "99.3" in text  # the time-domain VAF of the fractional five-element model


def test_table_without_truth_keys():
    results = _results(truth=False)
    text = format_fractional_table(results)
    assert "(27)" in text and "true" not in text and "rel. error" not in text
    minimal = {"models": {"27": {"alpha": 1.0, "mse": 1e-7}}, "paper_table_I": PAPER_TABLE_I}
    text = format_fractional_table(minimal)
    assert "(27)" in text and "—" in text and "2.70" in text
    assert isinstance(format_fractional_table({}), str)


def _entity_paths(path: Path) -> list[str] | None:
    """Entity paths of the first recording in ``path``, or ``None`` if rerun cannot read it back."""
    try:
        from rerun.chunk import RrdReader
    except ImportError:
        return None
    return list(RrdReader(str(path)).store().schema().entity_paths())


def test_recording_written_and_readable(tmp_path):
    path = write_fractional_recording(tmp_path / "run.rrd", _trials(), _results())
    assert path == tmp_path / "run.rrd"
    assert path.stat().st_size > 10_000
    entities = _entity_paths(path)
    if entities is None:
        pytest.skip("this rerun has no rerun.chunk.RrdReader; size checked only")
    for i in range(2):
        for name in ("f_ref", "f_measured", "theta_measured", "phi_true", "current"):
            assert f"/trials/t{i:03d}/{name}" in entities
        for name in ("link", "forearm", "force"):
            assert f"/trials/t{i:03d}/pose/{name}" in entities
    assert "/results/summary" in entities


def test_recording_without_results_or_link_length(tmp_path):
    path = write_fractional_recording(
        tmp_path / "bare.rrd", _trials(with_link=False), None, max_scalar_hz=None, blueprint=False
    )
    assert path.stat().st_size > 0
    entities = _entity_paths(path)
    if entities is not None:
        assert "/trials/t000/f_ref" in entities
        assert not any("/pose/" in e or e.startswith("/results") for e in entities)


def test_recording_rejects_bad_paths_and_input(tmp_path):
    trials = _trials()
    with pytest.raises(DataError, match=r"\.rrd"):
        write_fractional_recording(tmp_path / "run.txt", trials)
    existing = tmp_path / "run.rrd"
    existing.write_bytes(b"keep")
    with pytest.raises(DataError, match="run.rrd"):
        write_fractional_recording(existing, trials)
    assert existing.read_bytes() == b"keep"
    with pytest.raises(ConfigError, match="max_3d_hz"):
        write_fractional_recording(tmp_path / "a.rrd", trials, max_3d_hz=0.0)
    with pytest.raises(DataError, match="available"):
        write_fractional_recording(tmp_path / "b.rrd", trials, scalar_channels=("nope",))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.rrd"]
