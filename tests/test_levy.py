"""Checks of Levy's method, the alpha sweep and the indices of the fractional-elbow paper."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armlab.errors import ConfigError, EstimationError
from armlab.estimation.levy import PAPER_STRUCTURES, LevyStructure, fit_indices, levy_fit, levy_sweep
from armlab.models.tf_structures import IDENTIFIED_MODELS, CommensurateTF

# The paper's grid: Welch with nfft = 18000 at 2 kHz (0.111 Hz spacing) on 0.12-15 Hz: 134 points.
F_PAPER = np.arange(1001) * 2000.0 / 18000.0
F_PAPER = F_PAPER[(F_PAPER >= 0.12) & (F_PAPER <= 15.0)]


def _coef_rel_err(fit_model: CommensurateTF, true: CommensurateTF) -> float:
    """Largest relative error over the nonzero coefficients of ``true``."""
    got = np.concatenate([fit_model.b, fit_model.a[1:]])
    want = np.concatenate([true.b, true.a[1:]])
    return float(np.max(np.abs(got - want) / np.abs(want)))


def test_sweep_recovers_model_28_and_its_order():
    true = IDENTIFIED_MODELS["28"]
    sweep = levy_sweep(F_PAPER, true.response(F_PAPER), PAPER_STRUCTURES["28"])
    best = sweep.best
    # exact data: alpha = 1.4 is on the 0.1 grid and the fit there is exact to round-off
    assert best.alpha == pytest.approx(1.4, abs=1e-12)
    assert_allclose(sweep.alphas, np.arange(1, 20) / 10)
    assert _coef_rel_err(best.model, true) < 1e-3  # the brief's 0.1 %; measured ~1e-15
    assert best.indices.r2 == pytest.approx(1.0, abs=1e-12)
    assert best.indices.mse < 1e-20
    assert best.n_params == 4 and best.stable
    # every other order is visibly worse: the sweep is not won by a tie
    others = [ft.indices.mse for ft in sweep.fits if ft is not best]
    assert min(others) > 1e6 * max(best.indices.mse, 1e-30)


def test_levy_recovers_model_27_and_29():
    true = IDENTIFIED_MODELS["27"]
    fit = levy_fit(F_PAPER, true.response(F_PAPER), PAPER_STRUCTURES["27"])
    assert fit.alpha == 1.0
    assert _coef_rel_err(fit.model, true) < 1e-3
    assert fit.n_params == 6  # b0..b2, a1..a3 (Table I prints 5; see the module docs)
    true29 = IDENTIFIED_MODELS["29"]
    sweep = levy_sweep(F_PAPER, true29.response(F_PAPER), PAPER_STRUCTURES["29"])
    assert sweep.best.alpha == pytest.approx(1.1)
    assert _coef_rel_err(sweep.best.model, true29) < 1e-3


def test_structure_parameter_counts_match_table_1():
    counts = {k: s.n_params for k, s in PAPER_STRUCTURES.items()}
    # Table I: (28) 4, (29) 3, A 3, B 4; (27) has six free coefficients in Eq. (27).
    assert counts == {"27": 6, "28": 4, "29": 3, "A": 3, "B": 4}
    assert PAPER_STRUCTURES["A"].alpha == 1.0 and PAPER_STRUCTURES["28"].alpha is None


def test_least_squares_equals_the_papers_normal_equations():
    """The SVD solution solves Eqs. (3)-(17) (with the Im[G] typo of (7), (9) corrected)."""
    rng = np.random.default_rng(3)
    alpha, m, n = 1.4, 1, 2
    G = IDENTIFIED_MODELS["28"].response(F_PAPER) * (1 + 0.05 * rng.standard_normal(F_PAPER.size))
    S = (2j * np.pi * F_PAPER[:, None]) ** (np.arange(max(m, n) + 1) * alpha)
    R, I = S.real, S.imag
    Gr, Gi, G2 = G.real, G.imag, np.abs(G) ** 2
    lb, la = np.arange(m + 1), np.arange(1, n + 1)
    A = -np.einsum("pl,pc->lc", R[:, lb], R[:, lb]) - np.einsum("pl,pc->lc", I[:, lb], I[:, lb])
    B = (
        np.einsum("pl,pc,p->lc", R[:, lb], R[:, la], Gr)
        + np.einsum("pl,pc,p->lc", I[:, lb], R[:, la], Gi)
        - np.einsum("pl,pc,p->lc", R[:, lb], I[:, la], Gi)
        + np.einsum("pl,pc,p->lc", I[:, lb], I[:, la], Gr)
    )
    C = (
        -np.einsum("pl,pc,p->lc", R[:, la], R[:, lb], Gr)
        + np.einsum("pl,pc,p->lc", I[:, la], R[:, lb], Gi)
        - np.einsum("pl,pc,p->lc", R[:, la], I[:, lb], Gi)
        - np.einsum("pl,pc,p->lc", I[:, la], I[:, lb], Gr)
    )
    D = np.einsum("p,pl,pc->lc", G2, R[:, la], R[:, la]) + np.einsum("p,pl,pc->lc", G2, I[:, la], I[:, la])
    e = -R[:, lb].T @ Gr - I[:, lb].T @ Gi
    g = -R[:, la].T @ G2
    H, rhs = np.block([[A, B], [C, D]]), np.concatenate([e, g])
    d = 1 / np.sqrt(np.abs(np.diag(H)))  # Jacobi scaling: the raw system spans ~20 decades
    x = d * np.linalg.solve(H * d[:, None] * d[None, :], rhs * d)
    fit = levy_fit(F_PAPER, G, LevyStructure.full(m, n), alpha=alpha)
    assert_allclose(np.concatenate([fit.model.b, fit.model.a[1:]]), x, rtol=1e-6)


def test_sanathanan_koerner_iterations_lower_the_output_error():
    rng = np.random.default_rng(0)
    true = IDENTIFIED_MODELS["28"]
    noise = 0.05 * (rng.standard_normal(F_PAPER.size) + 1j * rng.standard_normal(F_PAPER.size))
    G = true.response(F_PAPER) * (1 + noise)
    sse = [
        np.sum(
            np.abs(G - levy_fit(F_PAPER, G, PAPER_STRUCTURES["28"], 1.4, iterations=k).response(F_PAPER)) ** 2
        )
        for k in (0, 5)
    ]
    assert sse[1] < sse[0]
    # weights of all ones change nothing
    plain = levy_fit(F_PAPER, G, PAPER_STRUCTURES["28"], 1.4)
    ones = levy_fit(F_PAPER, G, PAPER_STRUCTURES["28"], 1.4, weights=np.ones(F_PAPER.size))
    assert_allclose(plain.model.b, ones.model.b, rtol=1e-12)


def test_fit_indices_by_hand():
    g, g_hat = np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 4.0])
    ind = fit_indices(g, g_hat)
    assert (ind.mse, ind.mad, ind.r2) == pytest.approx((1 / 3, 1 / 3, 1 - 1 / 2))
    # complex: |g - g_hat| = 1 at one point; the magnitudes agree, so the magnitude indices are 0
    gc = np.array([1.0, 1j, -1.0])
    ic = fit_indices(gc, np.array([1.0, 1j, -1j]), on="complex")
    assert ic.mse == pytest.approx(2 / 3) and ic.mad == pytest.approx(np.sqrt(2) / 3)
    assert fit_indices(gc, np.array([1.0, 1j, -1j])).mse == 0.0
    with pytest.raises(ConfigError, match="'magnitude' or 'complex'"):
        fit_indices(g, g_hat, on="dB")


def test_first_order_bandwidth_and_matignon_stability():
    tau = 0.05  # s
    lag = CommensurateTF(b=np.array([2.0]), a=np.array([1.0, tau]))
    # |G| = 10^(-3/20) |G(0)|  <=>  (omega tau)^2 = 10^(3/10) - 1
    assert lag.bandwidth_hz() == pytest.approx(np.sqrt(10**0.3 - 1) / (2 * np.pi * tau), rel=1e-9)
    # roots of 1 + a1 w + a2 w^2 at |arg w| = 3 pi / 4: stable iff alpha pi / 2 < 3 pi / 4
    den = np.array([1.0, np.sqrt(2.0), 1.0])
    assert CommensurateTF(b=np.array([1.0]), a=den, alpha=1.4).is_stable
    assert not CommensurateTF(b=np.array([1.0]), a=den, alpha=1.6).is_stable
    with pytest.raises(EstimationError, match="low-frequency gain"):
        CommensurateTF(b=np.array([0.0, 1.0]), a=np.array([1.0, 1.0])).bandwidth_hz()


@pytest.mark.parametrize("alpha", [0.0, 2.0, -0.5, 2.5, float("nan")])
def test_alpha_outside_open_interval_raises(alpha):
    G = IDENTIFIED_MODELS["28"].response(F_PAPER)
    with pytest.raises(ConfigError, match=r"alpha must lie in the open interval \(0, 2\)"):
        levy_fit(F_PAPER, G, PAPER_STRUCTURES["28"], alpha=alpha)
    with pytest.raises(ConfigError, match=r"open interval \(0, 2\)"):
        levy_sweep(F_PAPER, G, PAPER_STRUCTURES["28"], alphas=[1.0, alpha])


def test_bad_structures_and_too_few_points_raise():
    with pytest.raises(ConfigError, match="orders must be integers m >= 0, n >= 0"):
        LevyStructure.full(2, -1)
    with pytest.raises(ConfigError, match="den_powers must be distinct integers >= 1"):
        LevyStructure(num_powers=(0,), den_powers=(0, 1))
    with pytest.raises(ConfigError, match="alpha is not set"):
        levy_fit(F_PAPER, np.ones(F_PAPER.size), PAPER_STRUCTURES["28"])
    f = F_PAPER[:5]
    with pytest.raises(EstimationError, match="5 frequency points for 6 free coefficients"):
        levy_fit(f, IDENTIFIED_MODELS["27"].response(f), PAPER_STRUCTURES["27"])
    with pytest.raises(EstimationError, match="finite"):
        levy_fit(F_PAPER, np.full(F_PAPER.size, np.nan), PAPER_STRUCTURES["A"])
