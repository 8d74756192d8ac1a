"""Protocol ``fractional_elbow``: fractional-order identification of the elbow (seeds/004).

The direct-drive motor applies a random-phase multisine force (0.12-15 Hz, <= 5 N, 40 s, 2 kHz)
to the hand while the elbow holds the pointer at zero; per trial the angle is low-passed by the
zero-phase FIR of Sec. III-B, ``G = theta / F_measured`` (Eq. (22)) is estimated by Welch's method,
the trials' responses are averaged, and Levy's method fits the paper's structures (27), (28),
(29), A and B (the fractional ones by an alpha sweep) plus, for a known fractional answer, the
inertia-springpot-spring family ``b0 / (1 + a s^beta + a2 s²)`` swept over beta. Indices MSE, MAD
and R² (Eqs. (24)-(26)), bandwidths, and the five-element reading of the integer third-order
model are scored against the simulated ground truth. Pure computation: files are written by
:mod:`armlab.runner.run`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from armlab import progress
from armlab.config.schema import FrfConfig
from armlab.data.trial import TrialSet
from armlab.errors import DataError, EstimationError
from armlab.estimation.criteria import relative_error
from armlab.estimation.five_element_fit import (
    best_five_element,
    five_element_guesses,
    five_element_response,
    fractional_five_element_sweep,
)
from armlab.estimation.frf import FirLowpassSpec, average_responses, design_fir_lowpass, estimate_frf
from armlab.estimation.levy import PAPER_STRUCTURES, LevyFit, alpha_grid, levy_fit, levy_sweep
from armlab.models.direct_drive_scene import DirectDriveScene, build_direct_drive_scene
from armlab.models.elbow_truth import ElbowTruth, elbow_truth
from armlab.models.tf_structures import (
    LITERATURE_MODELS,
    CommensurateTF,
    FiveElement,
    bandwidth_hz,
    five_element_from_tf,
)
from armlab.perturbations.multisine import ForceScenario, load_force_scenario, multisine
from armlab.protocols.fractional_elbow.config import FractionalElbowConfig
from armlab.protocols.fractional_elbow.preflight import validate
from armlab.sensors.channel import ChannelSpec
from armlab.sensors.presets import DD_ENCODER, JR3_FORCE
from armlab.sim.force_control import FORCE_LOOP_HINT, simulate_force_trial
from armlab.sim.stability import TrialLabels
from armlab.sim.subject import activation_commands
from armlab.sim.threads import run_trials

__all__ = [
    "FractionalRecording",
    "PAPER_FIG4",
    "PAPER_TABLE_I",
    "STABILITY_RULE",
    "bode_features",
    "effective_arm",
    "estimate_fractional",
    "simulate_fractional",
    "time_overlay",
]

_FIVE = ("M", "k1", "k2", "d1", "d2")
# Table I of seeds/004: alpha, MSE (x1e-7), MAD (x1e-4), R², number of parameters
PAPER_TABLE_I = {
    "27": {"alpha": 1.0, "mse": 2.70e-7, "mad": 3.52e-4, "r2": 0.94, "n_params": 5},
    "28": {"alpha": 1.4, "mse": 5.14e-7, "mad": 5.01e-4, "r2": 0.89, "n_params": 4},
    "29": {"alpha": 1.1, "mse": 8.4e-7, "mad": 6.37e-4, "r2": 0.82, "n_params": 3},
    "A": {"alpha": 1.0, "mse": 11.52e-7, "mad": 6.71e-4, "r2": 0.8, "n_params": 3},
    "B": {"alpha": 1.0, "mse": 11.59e-7, "mad": 6.72e-4, "r2": 0.8, "n_params": 4},
}
# Fig. 4 of seeds/004, read from the printed models (27), (28), (29) on 0.12-15 Hz (the figure's
# curves; computed by armlab.reproduction.fractional): DC gain (dB re 1 rad/N), resonance peak above
# DC (dB) and its frequency, level (dB) and phase (deg) at 15 Hz, as [low, high] over the three
PAPER_FIG4 = {
    "dc_db": (-49.1, -46.0),
    "peak_db": (0.74, 3.69),
    "peak_hz": (4.99, 5.28),
    "level_15_db": (-72.2, -65.2),
    "phase_15_deg": (-176.0, -134.0),
}
#: How a Table I row is chosen when some fits are unstable (issue 17: never silently skipped).
STABILITY_RULE = (
    "alpha sweeps keep the smallest-MSE stable fit (Matignon's condition); a smaller-MSE unstable "
    "fit is rejected and named; a fixed-order fit that is unstable is reported and marked unstable"
)
# m/s² rms, noise of the JR3's built-in accelerometer used by the inertia compensation
# (assumption: strain-gauge sensor accelerometers resolve of order 0.1 m/s²) -> /L rad/s²
_ACCEL_NOISE_M_S2 = 0.1
_SKIP_S = 5.0  # s, start-up transient left out of the time-domain comparison (Fig. 5)
_NFFT = 18000  # FFT length of the paper's Welch estimate ("18000 samples", Sec. III-B)


@dataclass(frozen=True, kw_only=True, eq=False)
class FractionalRecording:
    """What :func:`simulate_fractional` returns: the trials and how they were made."""

    trials: TrialSet
    scenario: ForceScenario
    truth: ElbowTruth
    scene: DirectDriveScene


def simulate_fractional(cfg: FractionalElbowConfig) -> FractionalRecording:
    """Simulate every trial of the protocol (``cfg.scenario.n_trials`` of them, or the scenario's)."""
    validate(cfg)  # refused up front by compose already; here for Python callers
    scenario = load_force_scenario(cfg.scenario.name, cfg.scenario.n_trials)
    scene = build_direct_drive_scene(cfg.elbow, cfg.sim)
    truth = elbow_truth(scene, cfg.elbow, scenario.fs_hz, cfg.motor.sensed_mass_kg)
    ideal = cfg.sensors.preset == "ideal"
    force_spec, enc_spec = (ChannelSpec(), ChannelSpec()) if ideal else (JR3_FORCE, DD_ENCODER)
    accel_noise = 0.0 if ideal else _ACCEL_NOISE_M_S2 / scene.link_length
    rngs = np.random.default_rng(cfg.seed).spawn(scenario.n_trials)
    fluctuating = cfg.subject.active and scene.muscle_act.size > 0
    n_settle = int(round(scenario.settle_s * scenario.fs_hz))
    who = TrialLabels(
        protocol=cfg.protocol_name,
        labels=tuple(
            f"random-phase multisine {i + 1} of {len(rngs)}, seed {cfg.seed}" for i in range(len(rngs))
        ),
        hint=FORCE_LOOP_HINT,
    )
    plans = []
    for rng in rngs:
        # the third child feeds the subject's fluctuation; the first two are those of a 2-way
        # spawn, so a steady subject draws exactly the force and sensor noise it always did
        plan_rng, noise_rng, subject_rng = rng.spawn(3)
        f_ref = multisine(scenario, plan_rng)
        base = None
        if fluctuating:
            n_total = n_settle + f_ref.size
            base = activation_commands(
                np.full(scene.muscle_act.size, cfg.elbow.cocontraction),
                cfg.subject,
                1,
                n_total,
                1,
                scenario.fs_hz,
                subject_rng,
            )[0]
        plans.append((f_ref, noise_rng, base))

    def one(i: int):
        f_ref, noise_rng, base = plans[i]
        return simulate_force_trial(
            scene,
            f_ref,
            scenario.fs_hz,
            scenario.settle_s,
            cfg.elbow,
            cfg.reflex,
            cfg.motor,
            force_spec,
            enc_spec,
            noise_rng,
            accel_noise_rad_s2=accel_noise,
            muscle_base=base,
            who=who,
            trial=i,
        )

    # one thread per trial (MuJoCo steps without the GIL): the same trials as a serial loop
    progress.stage("simulate", len(plans), "trials")
    trials = run_trials(one, len(plans), done=progress.advance)
    names = {
        "f_ref": "N",
        "f_measured": "N",
        "theta_measured": "rad",
        "current": "A",
        "tau_motor": "N*m",
        "f_true": "N",
        "theta_true": "rad",
        "phi_true": "rad",
    }
    channels = {k: np.stack([getattr(t, k) for t in trials])[..., None] for k in names}
    channels["true_activation"] = np.stack([t.activation for t in trials])
    reflex_on = bool(cfg.reflex.enabled and scene.muscle_act.size)
    units = {**names, "true_activation": "1"}
    trial_set = TrialSet(
        fs_hz=scenario.fs_hz,
        onset_index=np.full(len(trials), 1, dtype=np.int64),  # the force starts at the first sample
        channels=channels,
        units=units,
        trial_meta={"tracking_error": np.array([t.tracking_error for t in trials])},
        attrs={
            "protocol": "fractional_elbow",
            "seed": cfg.seed,
            "link_length_m": scene.link_length,
            "reflex_enabled": reflex_on,
            "ground_truth": truth.as_dict(),
        },
    )
    return FractionalRecording(trials=trial_set, scenario=scenario, truth=truth, scene=scene)


def _ffe_bandwidth(element: FiveElement, beta: float) -> float | None:
    """-3 dB bandwidth of the fractional five-element model (None if |G| never falls 3 dB)."""
    try:
        return bandwidth_hz(
            lambda ff: five_element_response(element, ff, beta), 1.0 / element.k1 + 1.0 / element.k2
        )
    except EstimationError:
        return None


def bode_features(f_hz: np.ndarray, G: np.ndarray) -> dict:
    """The Fig. 4 features of a response on its band: DC gain (dB re 1 rad/N, at the lowest
    frequency), resonance peak above DC (dB, 0 when |G| never rises) and its frequency (Hz), level
    (dB) and unwrapped phase (deg) at the highest frequency, and the lowest phase (deg)."""
    db = 20.0 * np.log10(np.abs(G))
    ph = np.degrees(np.unwrap(np.angle(G)))
    i = int(np.argmax(db))
    return {
        "dc_db": float(db[0]),
        "peak_db": float(db[i] - db[0]),
        "peak_hz": float(f_hz[i]),
        "level_15_db": float(db[-1]),
        "phase_15_deg": float(ph[-1]),
        "min_phase_deg": float(ph.min()),
        "f_top_hz": float(f_hz[-1]),
    }


def effective_arm(f_hz: np.ndarray, Y: np.ndarray, inertia: float) -> tuple[float, float]:
    """Effective arm stiffness K (N·m/rad) and damping D (N·m·s/rad), reflex included.

    ``Y`` is the arm's noise-free admittance ``phi / (F L)`` (rad/(N·m)) measured on the band;
    with the inertia known, ``K`` and ``D`` minimise the relative impedance error
    ``sum |1/Y - (K - I w² + j D w)|² / |1/Y|²`` (linear least squares, real and imaginary parts
    separate).
    """
    w = 2.0 * np.pi * np.asarray(f_hz, dtype=float)
    Z = 1.0 / np.asarray(Y)
    wt = 1.0 / np.abs(Z) ** 2
    K = float(np.sum(wt * (Z.real + inertia * w**2)) / np.sum(wt))
    D = float(np.sum(wt * w * Z.imag) / np.sum(wt * w**2))
    return K, D


def _fit_entry(fit: LevyFit, truth_g: np.ndarray | None, f: np.ndarray) -> dict:
    out = fit.summary()
    if truth_g is not None:  # |fit| against |truth| on the same band, relative RMS
        out["rel_rms_error_vs_truth"] = relative_error(np.abs(fit.response(f)), np.abs(truth_g))
    return out


def estimate_fractional(
    trials: TrialSet, frf_cfg: FrfConfig, truth: ElbowTruth | None = None
) -> tuple[dict, dict]:
    """Frequency response, Levy fits and scores (Sec. II-IV of seeds/004).

    Args:
        trials: recorded trials with channels ``f_measured`` (N) and ``theta_measured`` (rad) and
            attr ``link_length_m``.
        frf_cfg: processing and fitting settings.
        truth: the simulated ground truth, or None for real data.

    Returns:
        (results dict, series for the figures: frequency grid, measured and fitted responses).
    """
    for key in ("f_measured", "theta_measured"):
        if key not in trials.channels:
            raise DataError(f"trials lack channel {key!r}; have {sorted(trials.channels)}")
    if "link_length_m" not in trials.attrs:
        raise DataError(
            "trials lack attr 'link_length_m' (m, motor axis to handle): it converts theta/F into the "
            "five-element model's m/N; add it to the trial file's attrs"
        )
    fs = trials.fs_hz
    frf_cfg.check_recording(fs, trials.n_samples, "trial")
    lo, hi = frf_cfg.band_hz
    fir = design_fir_lowpass(
        FirLowpassSpec(
            pass_hz=frf_cfg.fir_pass_hz,
            stop_hz=frf_cfg.fir_stop_hz,
            ripple_db=frf_cfg.fir_ripple_db,
            attenuation_db=frf_cfg.fir_attenuation_db,
            fs_hz=fs,
        )
    )
    force = trials.channel("f_measured")[..., 0]
    if frf_cfg.filter_force:  # same zero-phase filter on both: its pass-band ripple cancels in G
        force = fir.apply(force, axis=-1)
    theta = fir.apply(trials.channel("theta_measured")[..., 0], axis=-1)
    nfft = max(_NFFT, frf_cfg.welch_window)
    per_trial = [
        estimate_frf(u, y, fs, window_len=frf_cfg.welch_window, overlap=frf_cfg.welch_overlap, nfft=nfft)
        for u, y in zip(force, theta, strict=True)
    ]
    frf = average_responses(per_trial).band(lo, hi)
    f, G = frf.f_hz, frf.G
    truth_g = truth.response(f) if truth is not None else None

    fits, rejected = {}, {}
    for key, structure in PAPER_STRUCTURES.items():
        if structure.alpha is not None:
            fit = levy_fit(f, G, structure)
        else:
            sweep = levy_sweep(f, G, structure, alphas=alpha_grid(frf_cfg.alpha_step), stable_only=False)
            fit, worse = sweep.stable_choice()  # STABILITY_RULE
            rejected[key] = None
            if worse is not None:
                rejected[key] = {"alpha": float(worse.alpha), "mse": worse.indices.mse, "stable": False}
        fits[key] = fit
    entries = {k: _fit_entry(v, truth_g, f) for k, v in fits.items()}
    for key, rej in rejected.items():
        entries[key]["rejected_unstable"] = rej

    results = {
        "protocol": trials.attrs.get("protocol", "fractional_elbow"),
        "seed": trials.attrs.get("seed"),
        "ground_truth": trials.attrs.get("ground_truth"),
        "n_trials": trials.n_trials,
        "tracking_error": np.asarray(trials.trial_meta.get("tracking_error", [])).tolist(),
        "frf": {
            "n_freq": int(f.size),
            "band_hz": [lo, hi],
            "mean_coherence": float(np.mean(frf.coherence)),
            "settings": dataclasses.asdict(frf_cfg),
        },
        "fir": {"taps": int(fir.taps.size), "ripple_db": fir.ripple_db, "attenuation_db": fir.attenuation_db},
        "models": entries,
        "stability_rule": STABILITY_RULE,
        "fig4_features": {
            "measured": bode_features(f, G),
            "truth": None if truth_g is None else bode_features(f, truth_g),
            "paper": {k: list(v) for k, v in PAPER_FIG4.items()},
        },
        "paper_table_I": PAPER_TABLE_I,
        "literature_bandwidth_hz": {name: tf.bandwidth_hz() for name, tf in LITERATURE_MODELS.items()},
    }
    L = float(trials.attrs["link_length_m"])
    m27 = fits["27"].model
    # theta/F (rad/N) -> handle displacement per force (m/N): multiply by L
    t27 = CommensurateTF(b=m27.b * L, a=m27.a, name="(27)", units="m/N")
    G_m = G * L
    try:  # the reading of model (27) is the paper's start; a shape-based guess when it has none
        start = five_element_from_tf(t27)
        reading = {k: getattr(start.element, k) for k in _FIVE}
        starts, mismatch = [start.element], start.mismatch
    except EstimationError:
        reading, mismatch, starts = None, None, []
    fe = best_five_element(f, G_m, starts + five_element_guesses(f, G_m))
    sweep = fractional_five_element_sweep(f, G_m, fe, step=frf_cfg.alpha_step)
    results["five_element_fit"] = {
        "M": fe.M,
        "k1": fe.k1,
        "k2": fe.k2,
        "d1": fe.d1,
        "d2": fe.d2,
        "from_model_27": reading,
        "mismatch_27": mismatch,
    }
    results["fractional_five_element"] = {
        "best_order": sweep.best_beta,
        "orders": sweep.betas,
        "cost": sweep.cost,
        "mse": [ix.mse / L**2 for ix in sweep.indices],  # (rad/N)², comparable with Table I
        "best_indices": {  # Eqs. (24)-(26) on |G| in rad/N, as Table I
            "mse": sweep.indices[sweep.best_index].mse / L**2,
            "mad": sweep.indices[sweep.best_index].mad / L,
            "r2": sweep.indices[sweep.best_index].r2,
            "n_params": 5,  # M, k1, k2, d1, d2 (the order excluded, as alpha in Table I)
            "bandwidth_hz": _ffe_bandwidth(sweep.best, sweep.best_beta),
        },
        "best": {k: getattr(sweep.best, k) for k in ("M", "k1", "k2", "d1", "d2")},
    }
    if truth is not None:
        names = _FIVE
        tf = truth.five_element
        if truth.fractional_order is None:
            results["five_element_rel_err"] = {n: abs(getattr(fe, n) / getattr(tf, n) - 1) for n in names}
            if trials.attrs.get("reflex_enabled") and {"f_true", "phi_true"} <= set(trials.channels):
                eff = _effective_truth(trials, frf_cfg, truth, nfft)
                results["effective_truth"] = eff
                results["five_element_rel_err_effective"] = {
                    n: abs(getattr(fe, n) / eff["five_element"][n] - 1) for n in names
                }
        else:
            frac = results["fractional_five_element"]
            frac["true_order"] = truth.fractional_order
            frac["order_error"] = abs(sweep.best_beta - truth.fractional_order)
            frac["rel_err"] = {n: abs(getattr(sweep.best, n) / getattr(tf, n) - 1) for n in names}
    models = {k: v.response for k, v in fits.items()}
    models["fractional_five_element"] = lambda ff: five_element_response(sweep.best, ff, sweep.best_beta) / L
    overlay = time_overlay(force[0], theta[0], fs, models, (lo, hi))
    results["time_vaf_pct"] = overlay["vaf_pct"]
    series = {
        "f_hz": f,
        "G": G,
        "coherence": frf.coherence,
        "G_true": truth_g,
        "fits": {k: model(f) for k, model in models.items()},
        "literature": {
            name: tf.response(f) / (L if tf.units == "m/N" else 1.0) for name, tf in LITERATURE_MODELS.items()
        },
        "time": overlay,
    }
    return results, series


def _effective_truth(trials: TrialSet, frf_cfg: FrfConfig, truth: ElbowTruth, nfft: int) -> dict:
    """The effective truth (reflex included): the arm's admittance from the run's noise-free
    channels (true grasp force ``f_true`` and elbow angle ``phi_true`` of the same trials), read as
    K and D by :func:`effective_arm`; M and the grasp are the intrinsic ones."""
    fs, L = trials.fs_hz, truth.L
    lo, hi = frf_cfg.band_hz
    force = trials.channel("f_true")[..., 0] * L  # N·m about the elbow
    phi = trials.channel("phi_true")[..., 0]
    per_trial = [
        estimate_frf(u, y, fs, window_len=frf_cfg.welch_window, overlap=frf_cfg.welch_overlap, nfft=nfft)
        for u, y in zip(force, phi, strict=True)
    ]
    frf = average_responses(per_trial).band(lo, hi)
    K, D = effective_arm(frf.f_hz, frf.G, truth.I)
    fe = truth.five_element
    L2 = L**2
    return {
        "label": "effective (reflex included; noise-free f_true, phi_true of the same trials)",
        "K_Nm_per_rad": K,
        "D_Nms_per_rad": D,
        "five_element": {"M": fe.M, "k1": fe.k1, "k2": K / L2, "d1": fe.d1, "d2": D / L2},
    }


def time_overlay(
    force: np.ndarray,
    theta: np.ndarray,
    fs: float,
    models: dict,
    band_hz: tuple[float, float],
    skip_s: float = _SKIP_S,
) -> dict:
    """Each model's angle for the measured force of one trial, beside the measured angle (Fig. 5).

    The multisine repeats every trial length (its lines lie on the ``1 / T`` grid), so the
    steady-state response is the periodic convolution ``irfft(G(f) rfft(F))``. Model and measured
    angle are both limited to the fitting band ``band_hz`` (the models are not fitted, and the
    force holds no lines, outside it); ``skip_s`` of start-up transient (the arm starts at rest)
    are left out of the VAF and of the returned series. Means are removed.

    Returns:
        dict with ``t_s``, ``force_N``, ``theta_rad`` and ``models`` ({name: angle}) from
        ``skip_s`` on, and ``vaf_pct`` ({name: VAF %}).
    """
    n = force.size
    fk = np.fft.rfftfreq(n, 1.0 / fs)
    keep = (fk >= band_hz[0]) & (fk <= band_hz[1])
    spectrum = np.fft.rfft(force - force.mean())
    i0 = int(round(skip_s * fs))
    y = np.fft.irfft(np.where(keep, np.fft.rfft(theta), 0.0), n)[i0:]
    y = y - y.mean()
    out = {"t_s": np.arange(i0, n) / fs, "force_N": force[i0:], "theta_rad": y, "models": {}, "vaf_pct": {}}
    for name, response in models.items():
        g = np.zeros(fk.size, dtype=complex)
        g[keep] = response(fk[keep])
        yh = np.fft.irfft(g * spectrum, n)[i0:]
        yh = yh - yh.mean()
        out["models"][name] = yh
        out["vaf_pct"][name] = float(100.0 * (1.0 - np.var(y - yh) / np.var(y)))
    return out
