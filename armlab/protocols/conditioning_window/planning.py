"""The planning model of issue 23's excitation designer: what the Eq. (9) estimator would read on
a planned excitation in a linear version of the lab.

The robot places the cuff's outer end exactly on the commanded joint displacement (what the
estimator reads, from the encoders); the arm, linearised at q0 with nominal M(q0), D and K, hangs
behind the cuff's spring-damper in series (``K_c = k_c J^T J``); the measured torque is the cuff's.
:func:`planned_estimate` gives the noise-free OLS estimate of Eqs. (11)-(14) on those data (its gap
to the nominal parameters is the bias the series compliance causes) and its covariance under the
torque noise (measured in the lab or the F/T white noise). No reflex, no noise on q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from armlab.errors import ConfigError
from armlab.estimation.joint_ls import regressor
from armlab.models import planar_arm
from armlab.perturbations.segments import SegmentWaveform

__all__ = ["PlanningModel", "planned_estimate", "planned_signals"]


@dataclass(frozen=True, kw_only=True)
class PlanningModel:
    """The linear arm + cuff the design is optimised on.

    Attributes:
        q0: (2,) rad, operating point; l1, l2: m, segment lengths.
        K, D: (2, 2) N·m/rad, N·m·s/rad nominal intrinsic stiffness and damping.
        xi: (3,) kg·m² nominal base inertial parameters (Eq. 10).
        cuff_stiffness_N_per_m, cuff_damping_Ns_per_m: the cuff in series (inf: rigid).
        force_noise_N: N, white noise std of each F/T force axis.
        fs_hz: Hz, sample rate; n_identify: trials identifying per window.
        noise: (n_real, n, 2) N·m, realisations of the processed torque noise after onset
            (:func:`~.design_noise.measure_noise`); None: white F/T noise only.
    """

    q0: np.ndarray
    l1: float
    l2: float
    K: np.ndarray
    D: np.ndarray
    xi: np.ndarray
    cuff_stiffness_N_per_m: float
    cuff_damping_Ns_per_m: float
    force_noise_N: float
    fs_hz: float
    n_identify: int
    noise: np.ndarray | None = None

    @property
    def theta(self) -> np.ndarray:
        """(11,) nominal parameters in the order of Eq. (10)."""
        return np.concatenate([self.xi, self.D.ravel(), self.K.ravel()])


def _plant_step(model: PlanningModel) -> tuple[np.ndarray, ...]:
    """First-order-hold discretisation at fs (Franklin & Powell) of the arm (M(q0), D, K) behind the
    cuff, input the commanded [q_r, qd_r] (linear between samples: a zero-order hold would delay it
    by half a sample, which through a stiff cuff is a torque error of K_c qd / (2 fs)); output the
    cuff torque at the joints, ``K_c (q_r - q) + D_c (qd_r - qd)``.

    Returns:
        ``(Phi, G1, G2, C, Dd)``: ``x[k+1] = Phi x[k] + G1 u[k] + G2 (u[k+1] - u[k])``,
        ``tau[k] = C x[k] + Dd u[k]``.
    """
    J = planar_arm.jacobian(model.q0, model.l1, model.l2)
    Kc = model.cuff_stiffness_N_per_m * J.T @ J
    Dc = model.cuff_damping_Ns_per_m * J.T @ J
    Mi = np.linalg.inv(planar_arm.mass_matrix(model.q0, model.xi))
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ (model.K + Kc), -Mi @ (model.D + Dc)]])
    B = np.block([[np.zeros((2, 4))], [Mi @ Kc, Mi @ Dc]])
    dt = 1.0 / model.fs_hz
    aug = np.zeros((12, 12))
    aug[:4, :4], aug[:4, 4:8], aug[4:8, 8:] = A * dt, B * dt, np.eye(4)
    E = expm(aug)
    return E[:4, :4], E[:4, 4:8], E[:4, 8:], np.hstack([-Kc, -Dc]), np.hstack([Kc, Dc])


def planned_signals(
    model: PlanningModel,
    waveform: SegmentWaveform,
    directions: np.ndarray,
    t_obs_s: float,
    duration_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Regressor rows, measured torque and noise weights the estimator would see on the plan
    (the waveform lasting ``duration_s``, default the window ``t_obs_s``).

    Returns:
        ``X`` (n_dir, n, 2, 11), ``tau`` (n_dir, n, 2) N·m (cuff in series; rigid when its stiffness
        is inf) and ``Wn`` (2, 2) 1/(N·m)², the inverse noise covariance of J^T F.
    """
    n = int(round(t_obs_s * model.fs_hz))
    t = np.arange(n) / model.fs_hz
    w, wd, wdd = waveform.evaluate(t, t_obs_s if duration_s is None else duration_s)
    dq = w[None, :, None] * directions[:, None, :]
    qd, qdd = wd[None, :, None] * directions[:, None, :], wdd[None, :, None] * directions[:, None, :]
    X = regressor(model.q0 + dq, qd, qdd, dq)
    J = planar_arm.jacobian(model.q0, model.l1, model.l2)
    Wn = np.linalg.inv(model.force_noise_N**2 * J.T @ J)
    if np.isinf(model.cuff_stiffness_N_per_m):
        tau = X @ model.theta
    else:  # the linear plant's response: its impulse responses convolved with the input
        u = np.concatenate([dq, qd], axis=-1).reshape(directions.shape[0], -1)  # (n_dir, n * 4)
        tau = (u @ _response_matrix(model, n).T).reshape(dq.shape)
    return X, tau, Wn


def _response_matrix(model: PlanningModel, n: int) -> np.ndarray:
    """(n * 2, n * 4): ``tau`` (sample-major) of the discretised plant from its input
    ``[q_r, qd_r]`` (sample-major), i.e. the block lower-triangular Toeplitz matrix of its impulse
    response under the first-order hold, ``h[0] = Dd + C G2``,
    ``h[k] = C Phi^(k-1) (G1 - G2) + C Phi^k G2`` (cached per model and n)."""
    key = (id(model), n)
    if key not in _RESPONSE_CACHE:
        Phi, G1, G2, C, Dd = _plant_step(model)
        h = np.empty((n, 2, 4))
        h[0], xa, xb = Dd + C @ G2, G1 - G2, Phi @ G2
        for k in range(1, n):
            h[k], xa, xb = C @ (xa + xb), Phi @ xa, Phi @ xb
        lag = np.arange(n)[:, None] - np.arange(n)[None, :]  # t - s
        G = np.where((lag >= 0)[:, :, None, None], h[np.clip(lag, 0, None)], 0.0)  # (t, s, 2, 4)
        _RESPONSE_CACHE.clear()  # one model at a time: a design evaluates one n thousands of times
        _RESPONSE_CACHE[key] = (model, G.transpose(0, 2, 1, 3).reshape(2 * n, 4 * n))
    return _RESPONSE_CACHE[key][1]


_RESPONSE_CACHE: dict = {}


def planned_estimate(
    model: PlanningModel,
    waveform: SegmentWaveform,
    directions: np.ndarray,
    t_obs_s: float,
    duration_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The noise-free ordinary least-squares estimate on the planned data, Eqs. (11)-(14)
    (the waveform lasting ``duration_s``, default ``t_obs_s``: the paper's quintic lasts T_k).

    Returns:
        ``(zeta, info, cov, cond)``: (11,) the estimate (its gap to ``model.theta`` is the bias),
        (11, 11) the information ``cov^-1``, (11, 11) the OLS covariance of ``n_identify`` trials
        spread over the directions (sandwich form ``H^-1 E[W^T e e^T W] H^-1``, the noise e
        measured or the F/T white noise), and cond(W) (Eq. 19).
    """
    X, tau, Wn = planned_signals(model, waveform, directions, t_obs_s, duration_s)
    W = X.reshape(-1, 11)
    reps = model.n_identify / directions.shape[0]
    zeta = np.linalg.solve(W.T @ W, W.T @ tau.reshape(-1))
    Hi = np.linalg.inv(reps * W.T @ W)
    if model.noise is None:
        noise = reps * np.einsum("abki,kl,ablj->ij", X, np.linalg.inv(Wn), X)
    else:  # E[X_d^T e e^T X_d] over the measured realisations, per direction
        if X.shape[1] > model.noise.shape[1]:
            raise ConfigError(
                f"window of {X.shape[1]} samples is longer than the measured noise "
                f"({model.noise.shape[1]} samples); valid: t_obs_s <= "
                f"{model.noise.shape[1] / model.fs_hz:g} s (measure it over the longest window planned)"
            )
        proj = np.einsum("dnki,rnk->dri", X, model.noise[:, : X.shape[1]])
        noise = reps * np.einsum("dri,drj->ij", proj, proj) / model.noise.shape[0]
    cov = Hi @ noise @ Hi
    sv = np.linalg.svd(W, compute_uv=False)
    return zeta, np.linalg.inv(cov), cov, float(sv[0] / sv[-1])
