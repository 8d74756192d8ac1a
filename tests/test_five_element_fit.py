"""Five-element fits, integer and with a fractional arm damper, recover known parameters."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.errors import ConfigError, EstimationError
from armlab.estimation.five_element_fit import (
    best_five_element,
    five_element_guesses,
    five_element_response,
    fractional_five_element_sweep,
    refine_five_element,
)
from armlab.models.tf_structures import FiveElement

F = np.linspace(0.12, 15.0, 134)  # Hz, the protocol's band and number of Welch points
# translational values at L = 0.35 m of the default elbow (I 0.0735 kg m², K 60, c 8, grasp 2000/10)
TRUE = FiveElement(M=0.6, k1=2000.0, k2=490.0, d1=10.0, d2=65.3)
NAMES = ("M", "k1", "k2", "d1", "d2")


def _rel_err(a: FiveElement, b: FiveElement) -> float:
    return max(abs(getattr(a, n) / getattr(b, n) - 1) for n in NAMES)


def test_response_at_beta_one_is_the_papers_third_order_model():
    np.testing.assert_allclose(five_element_response(TRUE, F), TRUE.to_tf().response(F), rtol=1e-10)


@pytest.mark.parametrize("beta", [0.3, 0.5, 1.0, 1.4])
def test_shape_based_starts_reach_the_exact_parameters(beta):
    G = five_element_response(TRUE, F, beta)
    fit = best_five_element(F, G, five_element_guesses(F, G), beta=beta)
    assert _rel_err(fit, TRUE) < 1e-8  # exact data: measured <= 7e-16


@pytest.mark.parametrize("beta", [0.2, 0.5, 0.7, 1.0])
def test_sweep_finds_the_true_order_on_exact_data(beta):
    G = five_element_response(TRUE, F, beta)
    start = best_five_element(F, G, five_element_guesses(F, G))
    sweep = fractional_five_element_sweep(F, G, start, step=0.1)
    assert sweep.betas.size == 19 and sweep.betas[0] == pytest.approx(0.1)
    assert sweep.best_beta == pytest.approx(beta)
    assert _rel_err(sweep.best, TRUE) < 1e-8  # exact data
    # a wrong order costs: the neighbours of the true order fit worse by a clear margin
    i = sweep.best_index
    assert np.all(np.delete(sweep.cost, i) > 10 * sweep.cost[i] + 1e-20)


def test_noisy_data_still_pick_the_order_within_one_step():
    rng = np.random.default_rng(3)
    G = five_element_response(TRUE, F, 0.5)
    G = G * (1 + 0.05 * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)))  # 5 % noise
    start = refine_five_element(F, G, five_element_guesses(F, G)[2])
    sweep = fractional_five_element_sweep(F, G, start)
    assert abs(sweep.best_beta - 0.5) <= 0.1 + 1e-9


def test_bad_input_is_rejected():
    G = five_element_response(TRUE, F)
    with pytest.raises(EstimationError, match="step must divide 1"):
        fractional_five_element_sweep(F, G, TRUE, step=0.3)
    with pytest.raises(EstimationError, match="matching 1-D"):
        refine_five_element(F[:-1], G, TRUE)
    with pytest.raises(EstimationError, match="finite and non-zero"):
        refine_five_element(F, np.where(F > 5, np.nan, G), TRUE)
    with pytest.raises(ConfigError, match=r"alpha must lie in the open interval \(0, 2\)"):
        refine_five_element(F, G, TRUE, beta=2.0)
    with pytest.raises(EstimationError, match="at least one start"):
        best_five_element(F, G, [])
