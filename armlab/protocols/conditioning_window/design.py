"""Excitation design for a short observation window (issue 23): the waveform, not the window.

The paper's quintic (seeds/000, Eq. 16) is one monotone move per trial. Here each of the paper's
six directions follows the same designed chain of quintic segments
(:class:`~armlab.perturbations.segments.SegmentWaveform`) over ``t_obs_s``, its knots chosen by
``scipy.optimize.minimize`` (SLSQP, seeded starts, deterministic) to optimise a criterion of the
Eq. (9) regression on a **planning model**: the robot places the cuff's outer end exactly on the
commanded joint displacement (what the estimator reads, from the encoders), and the arm, linearised
at q0 with its nominal M(q0), D, K (the lab's intrinsic truth: a locally optimal design; a real lab
would use a pilot estimate), hangs behind the cuff's spring-damper in series, mapped to the joints
by the hand Jacobian (``K_c = k_c J^T J``). No reflex is in the planning model.

Criteria (``DesignConfig.criterion``), all on parameters scaled by their nominal values:
``d_optimal`` maximises log det of the Fisher information ``F = sum X^T Sigma^-1 X`` (X of Eq. 13,
Sigma the F/T noise mapped by J^T); ``e_optimal`` its smallest eigenvalue; ``expected_error``
minimises the planned relative squared error of K, D and xi, bias (the cuff's series compliance,
which Eq. 9 cannot represent) plus variance (``F^-1``). Limits: |dq_j| <= amplitude by
construction; every segment's peak joint velocity and acceleration at most the paper's fastest
move (0.05 rad in T_1 = 50 ms, section IV-B), which the real LWR performed; the robot's own joint
velocities, accelerations and torques are checked afterwards (:mod:`.design_limits`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.linalg import expm
from scipy.optimize import minimize

from armlab.config.validate import check, choice
from armlab.errors import ConfigError
from armlab.estimation.joint_ls import regressor
from armlab.models import planar_arm
from armlab.models.ground_truth import ground_truth
from armlab.models.scene import build_scene
from armlab.perturbations.quintic import PAPER_DIRECTIONS
from armlab.perturbations.segments import QUINTIC_PEAK_ACC, QUINTIC_PEAK_VEL, SegmentWaveform
from armlab.protocols.conditioning_window.config import ConditioningWindowConfig
from armlab.protocols.conditioning_window.design_noise import measure_noise
from armlab.sensors.presets import SensorSuite
from armlab.sim.hold import settle

__all__ = [
    "Criterion",
    "Design",
    "MIN_FRACTION",
    "DesignConfig",
    "PAPER_PEAK_ACC_RAD_S2",
    "PAPER_PEAK_VEL_RAD_S",
    "PlanningModel",
    "design_excitation",
    "planned_estimate",
    "planning_model",
]

Criterion = Literal["d_optimal", "e_optimal", "expected_error"]
_CRITERIA = ("d_optimal", "e_optimal", "expected_error")
NoiseModel = Literal["measured", "sensor"]
Ending = Literal["hold", "free"]
_ENDINGS = ("hold", "free")
_NOISE = ("measured", "sensor")
# rad/s and rad/s^2, the arm-joint peaks of the paper's fastest perturbation: the quintic of Eq. (16)
# over 0.05 rad in T_1 = 50 ms (section IV-B: amplitude 0.05 rad, T_k = 40 + 10 k ms), performed by
# the real LWR in the experiment; 1.875 x 0.05 / 0.05 and (10 / sqrt 3) x 0.05 / 0.05^2.
PAPER_PEAK_VEL_RAD_S = QUINTIC_PEAK_VEL * 0.05 / 0.05
PAPER_PEAK_ACC_RAD_S2 = QUINTIC_PEAK_ACC * 0.05 / 0.05**2
#: Shortest part of the window the waveform may move in (then it holds): 10 %.
MIN_FRACTION = 0.1


@dataclass(kw_only=True)
class DesignConfig:
    """What to design: window, shape freedom, criterion, and the optimiser's seeded starts."""

    t_obs_s: float = 0.12  # s, the window the waveform fills (issue 23's target: <= 120 ms)
    n_segments: int = 4  # quintic segments of the waveform (knots optimised)
    criterion: Criterion = "expected_error"
    # the estimator's noise: "measured" in the lab with the robot still (design_noise: sensors,
    # the subject's fluctuation, the estimator's filter and baseline) or only the F/T "sensor"'s
    # white noise
    noise: NoiseModel = "measured"
    noise_trials: int = 60  # realisations measured (2.5 s of lab time for 60)
    amplitude_rad: float = 0.05  # rad, per-joint bound of every direction (paper, section IV-B)
    # "hold": the last knot is the full amplitude, held to the window's end (a displacement held,
    # as in the paper, is what shows the stiffness); "free": any last knot
    ending: Ending = "hold"
    # planned peaks at most this part of the paper's (the robot's joints map the arm's nonlinearly
    # through IK: the 120 ms design planned at 100 % reached 101-102 % of the robot's bound)
    limit_margin: float = 0.95
    n_starts: int = 6  # seeded random feasible starts of SLSQP; the best is kept
    seed: int = 0
    max_iter: int = 200  # SLSQP iterations per start

    def __post_init__(self) -> None:
        choice("design.criterion", self.criterion, _CRITERIA)
        choice("design.noise", self.noise, _NOISE)
        choice("design.ending", self.ending, _ENDINGS)
        check(self.noise_trials >= 2, f"design.noise_trials must be >= 2, got {self.noise_trials}")
        check(0.02 <= self.t_obs_s <= 1.0, f"design.t_obs_s must lie in [0.02, 1.0] s, got {self.t_obs_s}")
        check(1 <= self.n_segments <= 12, f"design.n_segments must lie in 1..12, got {self.n_segments}")
        check(
            0 < self.amplitude_rad <= 0.05,
            f"design.amplitude_rad must lie in (0, 0.05] rad (the paper's subject-safety bound), "
            f"got {self.amplitude_rad}",
        )
        check(0 < self.limit_margin <= 1, f"design.limit_margin must lie in (0, 1], got {self.limit_margin}")
        check(self.n_starts >= 1, f"design.n_starts must be >= 1, got {self.n_starts}")
        check(self.max_iter >= 1, f"design.max_iter must be >= 1, got {self.max_iter}")


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


@dataclass(frozen=True, kw_only=True)
class Design:
    """A designed excitation and what the planning model predicts for it.

    Attributes:
        waveform: the knots every direction follows over ``t_obs_s``.
        directions_rad: (6, 2) rad, the paper's directions (per-joint amplitude ``amplitude_rad``).
        t_obs_s: s, the window the waveform fills.
        criterion, objective: the criterion and its value at the optimum.
        logdet_info: log det of the scaled Fisher information.
        cond: condition number of the unscaled regressor W (Eq. 19), planned data.
        planned_err: relative (Frobenius) error of K, D, xi planned: bias and noise, ``{"K": .., ..}``.
        peak_vel_rad_s, peak_acc_rad_s2: arm-joint peaks of the design.
        elapsed_s: s, wall time of the optimisation.
    """

    waveform: SegmentWaveform
    directions_rad: np.ndarray
    t_obs_s: float
    criterion: str
    objective: float
    logdet_info: float
    cond: float
    planned_err: dict[str, float]
    peak_vel_rad_s: float
    peak_acc_rad_s2: float
    elapsed_s: float


def planning_model(
    cfg: ConditioningWindowConfig, design: DesignConfig | None = None, n_identify: int = 29
) -> PlanningModel:
    """The planning model of ``cfg``'s lab: its settled operating point and intrinsic truth, its
    cuff (inf when rigid), its F/T force noise (the sensor preset's white noise) and, with
    ``design.noise == "measured"``, the torque noise measured in the lab over ``design.t_obs_s``
    (its generator: the second child of ``default_rng(design.seed)``)."""
    design = DesignConfig() if design is None else design
    scene = build_scene(cfg.arm, cfg.cuff, cfg.robot, cfg.sim)
    hold = settle(scene, cfg.arm, cfg.sim.settle_s, protocol=cfg.protocol_name)
    truth = ground_truth(scene, hold.state, cfg.cuff.rigid)
    suite = SensorSuite.realistic() if cfg.sensors.preset == "realistic" else SensorSuite.ideal()
    noise = float(suite.ft_force.noise_std)
    return PlanningModel(
        q0=np.asarray(truth.q_op, float),
        l1=scene.l1,
        l2=scene.l2,
        K=np.asarray(truth.K),
        D=np.asarray(truth.D),
        xi=np.asarray(truth.xi),
        cuff_stiffness_N_per_m=np.inf if cfg.cuff.rigid else cfg.cuff.stiffness_N_per_m,
        cuff_damping_Ns_per_m=0.0 if cfg.cuff.rigid else cfg.cuff.damping_Ns_per_m,
        # an ideal sensor has no noise; a tiny floor keeps the information finite (N)
        force_noise_N=max(noise, 1e-6),
        fs_hz=cfg.sensors.fs_hz,
        n_identify=n_identify,
        noise=None
        if design.noise == "sensor"
        else measure_noise(
            cfg, design.noise_trials, design.t_obs_s, np.random.default_rng(design.seed).spawn(2)[1]
        ),
    )


def _plant_step(model: PlanningModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation at fs of arm (M(q0), D, K) behind the cuff, input the
    commanded [q_r, qd_r]; output the cuff torque at the joints, ``K_c (q_r - q) + D_c (qd_r - qd)``."""
    J = planar_arm.jacobian(model.q0, model.l1, model.l2)
    Kc = model.cuff_stiffness_N_per_m * J.T @ J
    Dc = model.cuff_damping_Ns_per_m * J.T @ J
    Mi = np.linalg.inv(planar_arm.mass_matrix(model.q0, model.xi))
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ (model.K + Kc), -Mi @ (model.D + Dc)]])
    B = np.block([[np.zeros((2, 4))], [Mi @ Kc, Mi @ Dc]])
    aug = np.zeros((8, 8))
    aug[:4, :4], aug[:4, 4:] = A, B
    E = expm(aug / model.fs_hz)
    return E[:4, :4], E[:4, 4:], np.hstack([-Kc, -Dc]), np.hstack([Kc, Dc])


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
    response ``h[0] = D_d``, ``h[k] = C A_d^(k-1) B_d`` (cached per model and n)."""
    key = (id(model), n)
    if key not in _RESPONSE_CACHE:
        Ad, Bd, C, Dd = _plant_step(model)
        h = np.empty((n, 2, 4))
        h[0], x = Dd, Bd
        for k in range(1, n):
            h[k], x = C @ x, Ad @ x
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


_BLOCKS = {"xi": slice(0, 3), "D": slice(3, 7), "K": slice(7, 11)}


def _waveform(x: np.ndarray) -> SegmentWaveform:
    """The design vector ``[knots..., fraction]`` as a waveform (clipped into its bounds)."""
    return SegmentWaveform(
        knots=tuple(float(v) for v in np.clip(x[:-1], -1.0, 1.0)), fraction=float(np.clip(x[-1], 1e-3, 1.0))
    )


def _score(model, x, directions, cfg: DesignConfig) -> tuple[float, float, dict[str, float], float]:
    waveform = _waveform(x)
    zeta, info, cov, cond = planned_estimate(model, waveform, directions, cfg.t_obs_s)
    theta = model.theta
    scaled = info * np.outer(theta, theta)
    sign, logdet = np.linalg.slogdet(scaled)
    logdet = logdet if sign > 0 else -np.inf
    err = {}
    for name, b in _BLOCKS.items():
        bias2 = float(np.sum((zeta[b] - theta[b]) ** 2))
        err[name] = float(np.sqrt((bias2 + np.trace(cov[b, b])) / np.sum(theta[b] ** 2)))
    if cfg.criterion == "d_optimal":
        obj = -logdet
    elif cfg.criterion == "e_optimal":
        obj = -float(np.linalg.eigvalsh(scaled)[0])
    else:
        obj = float(sum(e**2 for e in err.values()))
    return obj, logdet, err, cond


def design_excitation(model: PlanningModel, cfg: DesignConfig) -> Design:
    """Optimise the knots of the waveform the six paper directions follow, and the fraction of the
    window it moves in before holding (module docstring).

    Bounds: knots in [-1, 1], fraction in [:data:`MIN_FRACTION`, 1]; each segment's knot step at
    most what keeps its peak joint velocity and acceleration within the paper's fastest move
    (:data:`PAPER_PEAK_VEL_RAD_S`, :data:`PAPER_PEAK_ACC_RAD_S2`) at the segment's duration
    ``fraction * t_obs_s / n_segments``. The family holds the paper's quintic (one segment,
    fraction T_k / T_obs). Starts drawn from ``default_rng(cfg.seed)``; the best local optimum.
    """
    t0 = time.perf_counter()
    directions = np.asarray(PAPER_DIRECTIONS, float) * (cfg.amplitude_rad / 0.05)
    m = cfg.n_segments
    A = cfg.amplitude_rad

    def cap(f: float) -> float:
        seg = f * cfg.t_obs_s / m
        return cfg.limit_margin * min(
            PAPER_PEAK_VEL_RAD_S * seg / (QUINTIC_PEAK_VEL * A),
            PAPER_PEAK_ACC_RAD_S2 * seg**2 / (QUINTIC_PEAK_ACC * A),
        )

    D = np.eye(m) - np.eye(m, k=-1)  # knot steps: D @ knots (the first from 0)
    cons = [
        {"type": "ineq", "fun": lambda x: cap(x[-1]) - D @ x[:-1]},
        {"type": "ineq", "fun": lambda x: cap(x[-1]) + D @ x[:-1]},
    ]
    last = (1.0, 1.0) if cfg.ending == "hold" else (-1.0, 1.0)
    rng = np.random.default_rng(cfg.seed)
    best = None
    for _ in range(cfg.n_starts):
        f0 = rng.uniform(MIN_FRACTION, 1.0)
        x0 = np.append(np.clip(np.cumsum(rng.uniform(-cap(f0), cap(f0), m)), -1.0, 1.0), f0)
        res = minimize(
            lambda x: _score(model, x, directions, cfg)[0],
            x0,
            method="SLSQP",
            bounds=[(-1.0, 1.0)] * (m - 1) + [last] + [(MIN_FRACTION, 1.0)],
            constraints=cons,
            options={"maxiter": cfg.max_iter, "ftol": 1e-10},
        )
        x = np.append(np.clip(res.x[:-1], -1.0, 1.0), np.clip(res.x[-1], MIN_FRACTION, 1.0))
        steps = np.abs(D @ x[:-1])
        x[:-1] *= min(1.0, cap(x[-1]) / max(float(steps.max()), 1e-300))  # SLSQP may overstep by round-off
        if cfg.ending == "hold":
            x[m - 1] = 1.0
        obj = _score(model, x, directions, cfg)[0]
        if np.isfinite(obj) and (best is None or obj < best[0]):
            best = (obj, x)
    if best is None:
        raise RuntimeError("no start gave a finite criterion (regressor rank deficient on every start)")
    obj, x = best
    waveform = _waveform(x)
    _, logdet, err, cond = _score(model, x, directions, cfg)
    vel, acc = waveform.peaks(cfg.t_obs_s)
    return Design(
        waveform=waveform,
        directions_rad=directions,
        t_obs_s=cfg.t_obs_s,
        criterion=cfg.criterion,
        objective=float(obj),
        logdet_info=float(logdet),
        cond=cond,
        planned_err=err,
        peak_vel_rad_s=vel * A,
        peak_acc_rad_s2=acc * A,
        elapsed_s=time.perf_counter() - t0,
    )
