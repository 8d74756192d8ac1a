"""Spec 002's nine acceptance checks, each measured figure beside the thesis's claim (thesis Ch. 3).

:func:`acceptance_checks` reads the results of
:func:`~armlab.protocols.cartesian_online.results.estimate_cartesian` and returns one row per check:
what the thesis says, the spec's limit, what this run measured, whether it passed, and whether
the run's settings are those the check is defined for (``applies``: the checks are defined on
the thesis's noise-free generator with its 20 stops, check 6 on 0.05 N of force noise; a run with
other settings still reports its figures, marked as not applying). A figure that needs more stops
than the run has (the 5th or 20th sequence of a 3-stop run) is left out, and a check without it
has ``passed: None``.
"""

from __future__ import annotations

import numpy as np

from armlab.models.cartesian_field import QuadraticImpedanceField
from armlab.perturbations.reference_paths import CIRCLE_CENTRE_M

__all__ = [
    "CHECK_NOISE_N",
    "NOISE_CHECK_LIMITS",
    "THESIS_CENTRE",
    "THESIS_STOPS",
    "acceptance_checks",
]

#: Thesis Tables 3.1/3.2 evaluated at the circle centre (0.95, 0.1) m (spec 002, checked):
#: K_xx, K_yy N/m and D_xx, D_yy N·s/m
THESIS_CENTRE = {"K_N_per_m": (16109.5, 22985.8), "D_Ns_per_m": (126.9, 151.6)}
#: N, the force noise of spec 002's check 6
CHECK_NOISE_N = 0.05
#: spec 002 check 6: (sequence, largest field error in %): <= 3 % after 5 sequences, <= 0.1 % after 20
NOISE_CHECK_LIMITS: tuple[tuple[int, float], ...] = ((5, 3.0), (20, 0.1))
#: stops (perturbations, or sequences of them) per experiment: thesis §3.1-3.5 (20); the figures of
#: checks 2-6 and 8 are defined on that many
THESIS_STOPS = 20


def _row(n, name, thesis, spec, measured, passed, applies=True, note=""):
    return {
        "id": n,
        "check": name,
        "thesis": thesis,
        "spec": spec,
        "measured": measured,
        "passed": None if passed is None else bool(passed),
        "applies": bool(applies),
        "note": note,
    }


def _after(f: np.ndarray, sequences) -> dict:
    """{``after_<k>``: f[k - 1]} for the sequences k the run has, and its last (``after_<n>``)."""
    ks = sorted({k for k in sequences if k <= len(f)} | {len(f)})
    return {f"after_{k}": float(f[k - 1]) for k in ks}


def acceptance_checks(results: dict, field: QuadraticImpedanceField) -> list[dict]:
    """The nine rows (module docstring); a check whose experiment was not run has ``passed: None``."""
    noise = results["noise_std_N"]
    # the thesis's settings: noise-free and its 20 stops (a run from before n_stops was stored: 20)
    stops = results.get("n_stops", {})
    noise_free = {c: n == 0 for c, n in noise.items()}
    clean = {c: free and stops.get(c, THESIS_STOPS) == THESIS_STOPS for c, free in noise_free.items()}
    s = field.stiffness_scale
    k = field.stiffness(np.asarray(CIRCLE_CENTRE_M))
    d = field.damping(np.asarray(CIRCLE_CENTRE_M))
    k_ref = np.asarray(THESIS_CENTRE["K_N_per_m"]) * s
    d_ref = np.asarray(THESIS_CENTRE["D_Ns_per_m"]) * np.sqrt(s)
    rows = [
        _row(
            1,
            "model values at the circle centre",
            "Tables 3.1/3.2 at (0.95, 0.1) m: K = 16 109.5 / 22 985.8 N/m, D = 126.9 / 151.6 N·s/m",
            "K within 0.1 N/m, D within 0.05 N·s/m (x stiffness_scale, D x its root)",
            {"K_N_per_m": k, "D_Ns_per_m": d},
            np.all(np.abs(k - k_ref) <= 0.1 * s) and np.all(np.abs(d - d_ref) <= 0.05 * np.sqrt(s)),
        )
    ]
    e1 = results.get("exp1")
    if e1 and "trapezoidal" in e1:
        tri, trap = e1["triangular"], e1["trapezoidal"]
        m = {
            "k_error_pct_max": [tri["k_error_pct_max"], trap["k_error_pct_max"]],
            "d_error_pct_max": [tri["d_error_pct_max"], trap["d_error_pct_max"]],
            "waveform_difference_points_max": e1["waveform_difference_points_max"],
        }
        ok = max(m["k_error_pct_max"]) <= 2.5 and max(m["d_error_pct_max"]) <= 1.0
        ok = ok and m["waveform_difference_points_max"] <= 0.5
        applies = clean["exp1_triangular"] and clean["exp1_trapezoidal"]
    else:
        m, ok, applies = None, None, False
    rows.append(
        _row(
            2,
            "Exp. 1 per perturbation, both waveforms",
            "§3.1.3: both waveforms identify K and D; triangular and trapezoidal 'almost identical'",
            "K error <= 2.5 %, D within 1 % of √K, waveforms within 0.5 points",
            m,
            ok,
            applies,
        )
    )
    e2 = results.get("exp2")
    rows.append(
        _row(
            3,
            "Exp. 2 per sequence, linear",
            "§3.2.3: diagonal K tracked along the circle, off-diagonal terms negligible",
            "diagonal error <= 2.5 %, |K_xy|, |K_yx| <= 1 % of the diagonal (√(K_xx K_yy)), D within 1 %",
            None
            if not e2
            else {
                k: e2[k]
                for k in (
                    "diagonal_error_pct_max",
                    "coupling_pct_max",
                    "row_coupling_pct_max",
                    "d_error_pct_max",
                )
            },
            None
            if not e2
            else e2["diagonal_error_pct_max"] <= 2.5
            and e2["coupling_pct_max"] <= 1.0
            and e2["d_error_pct_max"] <= 1.0,
            bool(e2) and clean["exp2"],
        )
    )
    e3 = results.get("exp3")
    rows.append(
        _row(
            4,
            "Exp. 3 cumulative quadratic in x (non-aliased sinusoid)",
            "§3.3.3: k_x0, k_x1, k_x3 converge; the constant D̂ 'does not follow' the model's √K",
            "k̂0, k̂1, k̂3 within 0.2 %; D̂ varies < 1 % while √K varies > 9 %",
            None
            if not e3
            else {k: e3[k] for k in ("final_error_pct_max", "d_hat_variation_pct", "sqrt_k_variation_pct")},
            None
            if not e3
            else e3["final_error_pct_max"] <= 0.2
            and e3["d_hat_variation_pct"] < 1
            and e3["sqrt_k_variation_pct"] > 9,
            bool(e3) and clean["exp3"],
        )
    )
    e4 = results.get("exp4")
    if e4:
        lin, nl = e4.get("linear"), e4.get("sqrt_damping")
        m = {
            "rank_after_1": None if lin is None else np.asarray(lin["rank"])[0].tolist(),
            "linear_field_max_pct": None if lin is None else _after(np.asarray(lin["field_max_pct"]), (2, 5)),
            "linear_force_nrmse": None if lin is None else lin["force_nrmse"],
            "sqrt_damping_coefficient_rel_err_after_2": None
            if nl is None
            else float(nl["coefficient_rel_err_max"][1]),
            "sqrt_damping_force_nrmse": None if nl is None else nl["force_nrmse"],
        }
        ok = None
        if lin is not None and nl is not None:
            ok = (
                np.all(np.asarray(lin["rank"])[0] < 8)
                and m["sqrt_damping_coefficient_rel_err_after_2"] <= 1e-4
                and np.max(nl["force_nrmse"]) < 1e-6
            )
        note = (
            "the thesis's Eq. 3.4.1 has constant damping columns and cannot be exact for D = δ√K; the "
            "model's own 12 + 2 fit (sqrt_damping) is (docs/cartesian_online.md)"
        )
    else:
        m, ok, note = None, None, ""
    rows.append(
        _row(
            5,
            "Exp. 4 noise-free, cumulative quadratic field",
            "§3.4.3: 'converges by the second sequence of perturbations'; force prediction indistinguishable",
            "rank deficient after 1; all 12 coefficients within 0.01 % after 2; force NRMSE < 1e-6",
            m,
            ok,
            bool(e4) and clean["exp4"],
            note,
        )
    )
    e4n = results.get("exp4_noise")
    if e4n:
        f = np.asarray(e4n["linear"]["field_max_pct"])
        m = {"field_max_pct": _after(f, (2, *(k for k, _ in NOISE_CHECK_LIMITS)))}
        # a run with fewer sequences than the check reads has not measured it
        ok = None
        if all(k <= len(f) for k, _ in NOISE_CHECK_LIMITS):
            ok = all(f[k - 1] <= lim for k, lim in NOISE_CHECK_LIMITS)
        n_seq = stops.get("exp4_noise", THESIS_STOPS)
        applies = np.isclose(e4n["noise_std_N"], CHECK_NOISE_N) and n_seq == THESIS_STOPS
    else:
        m, ok, applies = None, None, False
    rows.append(
        _row(
            6,
            "Exp. 4 with 0.05 N force noise",
            "§3.4.3 claims convergence by the second sequence (the thesis is noise-free)",
            ", ".join(f"field error <= {lim:g} % after {k} sequences" for k, lim in NOISE_CHECK_LIMITS)
            + " (the claim holds only without noise)",
            m,
            ok,
            applies,
            "field error = max over the circle's disc of Eq. 3.1.2 on K_xx, K_yy",
        )
    )
    rls = results.get("rls")
    rows.append(
        _row(
            7,
            "recursive LS (λ = 1) equals cumulative LS",
            "future work (Discussion): recursive LS",
            "equal to 1e-9 (the field, relative, where the scaled condition <= 1e7)",
            rls,
            # None when no block was well conditioned: nothing measured, nothing passed
            None
            if not rls or rls["field_rel_diff_max_cond_le_1e7"] is None
            else rls["field_rel_diff_max_cond_le_1e7"] <= 1e-9,
            bool(rls),
            "an algebraic identity: it holds for any stop count and noise",
        )
    )
    e5 = results.get("exp5")
    if e5:
        cart = e5["cartesian"]
        m = {
            "k_r2_adj_11": [cart[f"k{e}"]["r2_adj_11"] for e in ("11", "12", "21", "22")],
            "d12_r2_adj_11_12": [cart["d12"]["r2_adj_11"], cart["d12"]["r2_adj_12"]],
            "thesis_order_counts": [
                e5["parameter_count"]["thesis_orders_cartesian"],
                e5["parameter_count"]["thesis_orders_polar"],
            ],
            "selected_counts": [e5["parameter_count"]["cartesian"], e5["parameter_count"]["polar"]],
        }
        # gated on measured figures only: thesis_order_counts are the thesis's stated orders counted
        # (a constant, reported beside the counts this run selected)
        ok = min(m["k_r2_adj_11"]) >= 0.999 and m["d12_r2_adj_11_12"][1] > m["d12_r2_adj_11_12"][0]
    else:
        m, ok = None, None
    rows.append(
        _row(
            8,
            "Exp. 5 polynomial orders",
            "§3.5.2: Cartesian K first order in x and y; d12 (1, 2); 26 (Cartesian) / 28 (polar) parameters",
            "Cartesian (1, 1) R²_adj >= 0.999 for every K entry; d12 improves (1, 1) -> (1, 2); "
            "counts 26 / 28",
            m,
            ok,
            bool(e5) and clean["exp5"],
            "not gated: d21 and the polar anti-diagonal orders (they depend on unstated choices), and the "
            "counts 26 / 28 (thesis_order_counts: the thesis's own orders counted, not a measurement)",
        )
    )
    a = results.get("appendix_a")
    rows.append(
        _row(
            9,
            "Appendix A frame change",
            "Appendix A: a rigid frame change keeps the quadratic form",
            "transformed coefficients reproduce K at mapped points to 1e-9; re-identification returns them",
            a,
            None
            if not a
            else a["scalar_rel_err_max"] <= 1e-9
            and a["matrix_rel_err_max"] <= 1e-9
            and a["reidentified_rel_err_max"] <= 1e-6,
            bool(a) and noise_free["exp4"],
            "re-identification by the 12 + 2 fit after a shift of origin, within 1e-6 (measured ~1e-10)",
        )
    )
    return rows
