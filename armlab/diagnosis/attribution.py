"""Which effect: every candidate added in turn, ranked by penalised held-out gap, greedy selection.

Scores (all on the held-out parts, in the scoring band):

- ``gap`` = residual sum of squares / measured sum of squares (1 − VAF as a fraction);
- ``floor`` = the noise floor in the same units; ``excess`` = gap − floor;
- ``delta_bic`` = ``n_eff·ln(RSS_c / RSS_0) + Δp·ln(n_eff)`` against the current model, with
  ``n_eff`` the held-out samples times the band's share of the Nyquist band (the residual is
  band-limited, so neighbouring samples are not independent) and Δp the added parameters (the
  linear ones once per trial; a surrogate's ``counts_as`` where it re-parametrises the nominal).

A candidate is accepted when ``delta_bic < -bic_margin``, its reduction is at least
``min_step_fraction`` of the nominal excess and ``min_floor_fraction`` of the floor; the first one
must also explain ``min_first_explained`` of the nominal excess. Nothing is accepted while the
nominal excess is within ``none_tolerance`` of the floor (verdict ``none``: the candidates are
still ranked for the report); nothing accepted beyond it: ``unknown``. Accepted effects that
leave more than ``1 − min_explained`` of the nominal excess, and more than ``none_tolerance`` of
the floor, are a partial explanation of something else: the verdict is ``unknown`` too, and they
are kept in ``Selection.partial`` (and the stages) for the report. ``rules`` must have both
tolerances set (:meth:`DiagnosisConfig.with_rules`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from armlab import progress
from armlab.config.diagnosis import DiagnosisConfig
from armlab.config.effects import EFFECTS
from armlab.cpus import single_threaded_blas, usable_cpus
from armlab.diagnosis.families import FittedModel, ModelFamily, Surrogate, active_params, fit_model
from armlab.errors import ConfigError

__all__ = [
    "Selection",
    "delta_bic",
    "effective_samples",
    "explains_enough",
    "held_out_gap",
    "select_candidates",
    "select_effects",
    "step_accepted",
]

_INCOMPATIBLE = {"cuff_compliance": "transmission_compliance", "transmission_compliance": "cuff_compliance"}


def held_out_gap(model: FittedModel, trials, y_band) -> tuple[float, float, list[float]]:
    """(pooled gap, held-out RSS, per-trial gap) of a fitted model."""
    rss = [float(np.sum(r[tr.held] ** 2)) for r, tr in zip(model.residuals, trials, strict=True)]
    tss = [float(np.sum(y[tr.held] ** 2)) for y, tr in zip(y_band, trials, strict=True)]
    return sum(rss) / sum(tss), sum(rss), [a / b for a, b in zip(rss, tss, strict=True)]


def select_candidates(cfg: DiagnosisConfig, surrogates, protocol: str) -> list[str]:
    """The candidate list after ``candidates`` / ``exclude`` (unknown names raise ConfigError).

    ``surrogates``: the protocol's candidates by name; ``protocol``: its name, for the message.
    """
    valid = list(surrogates)
    chosen = list(cfg.candidates) if cfg.candidates is not None else valid
    for name in [*chosen, *cfg.exclude]:
        if name not in valid:
            raise ConfigError(f"unknown candidate effect {name!r} for {protocol}; valid: {valid}")
    out = [n for n in chosen if n not in cfg.exclude]
    if not out:
        raise ConfigError(f"no candidate effects left after exclude={cfg.exclude}; valid: {valid}")
    return out


@dataclass(frozen=True, eq=False)
class Selection:
    """Result of the greedy selection.

    Attributes:
        verdict: selected effect names in order, or ``["none"]`` / ``["unknown"]``.
        stages: fitted models, nominal first, then one per selected effect.
        rankings: per greedy step, the candidates' entries (best first).
        floor: the noise floor as a gap fraction.
        indistinct: pairs that the data cannot tell apart, with the trial that would.
        partial: with verdict ``unknown``, the accepted effects that explained too little.
    """

    verdict: list[str]
    stages: list[FittedModel]
    rankings: list[list[dict]]
    floor: float
    indistinct: list[dict]
    partial: list[str]

    def ranking_steps(self) -> list[list[dict]]:
        """The rankings without their fitted models (what results.json stores per greedy step)."""
        return [[{k: v for k, v in e.items() if k != "model"} for e in r] for r in self.rankings]


def _separating_trial(a: str, b: str) -> str:
    for x, y in ((a, b), (b, a)):
        cls = EFFECTS.get(x)
        if cls is not None and y in cls.CONFUSABLE:
            return cls.CONFUSABLE[y]
    return "a trial that excites the band where their predictions differ (see the 'where' breakdown)"


def effective_samples(trials, band_share: float) -> float:
    """``n_eff`` of the module docstring: the held-out samples times the scoring band's share of
    the Nyquist band (at least 10)."""
    n_h = sum(int(np.sum(tr.held)) for tr in trials)
    return max(n_h * band_share, 10.0)


def delta_bic(rss: float, rss_current: float, added_params: int, n_eff: float) -> float:
    """``n_eff·ln(RSS / RSS_current) + Δp·ln(n_eff)``: negative where a model with ``added_params``
    more parameters earns them on the held-out parts."""
    return float(n_eff * np.log(rss / rss_current) + added_params * np.log(n_eff))


def step_accepted(
    rules: DiagnosisConfig, *, first: bool, excess0: float, floor: float, reduction: float, dbic: float
) -> bool:
    """Whether a greedy step is accepted (the module docstring's rule).

    Args:
        rules: the thresholds (tolerances set).
        first: the first effect named over the nominal model (it must also explain
            ``min_first_explained`` of the excess, so that a minor cause is not named alone).
        excess0: the nominal model's gap above the floor; floor: the noise floor (gap fractions).
        reduction: how far the step lowers the held-out gap; dbic: its :func:`delta_bic`.
    """
    return bool(
        excess0 > rules.none_tolerance * floor  # a nominal within tolerance of the floor needs nothing
        and dbic < -rules.bic_margin
        and reduction >= rules.min_step_fraction * excess0
        and reduction >= rules.min_floor_fraction * floor
        and (not first or reduction >= rules.min_first_explained * excess0)
    )


def explains_enough(rules: DiagnosisConfig, *, left: float, excess0: float, floor: float) -> bool:
    """Whether accepted effects that leave ``left`` above the floor explain the nominal excess
    ``excess0`` (at most ``1 - min_explained`` of it left, or within ``none_tolerance`` of the
    floor); if not, they are a partial explanation and the verdict is ``unknown``."""
    return not left > max(rules.none_tolerance * floor, (1.0 - rules.min_explained) * excess0)


def select_effects(
    trials,
    y_band,
    hp,
    candidates: dict[str, Surrogate],
    floor: float,
    rules: DiagnosisConfig,
    *,
    band_share: float,
    family: ModelFamily,
    nominal: FittedModel | None = None,
) -> Selection:
    """Greedy selection of up to ``rules.max_effects`` effects (see the module docstring).

    Args:
        trials: prepared trials; y_band: their measured torque in the scoring band; hp: the
            scoring high-pass.
        candidates: the surrogates to try, by name.
        floor: noise floor as a gap fraction.
        rules: the diagnosis settings holding the thresholds (``max_effects``, ``bic_margin``,
            ``min_step_fraction``, ``min_floor_fraction``, ``min_first_explained``,
            ``none_tolerance``, ``indistinct_ratio``).
        band_share: (band width) / (Nyquist frequency) of the scoring band, for ``n_eff``.
        family: the protocol's model family.
        nominal: the nominal model of ``family`` already fitted to these trials (a caller that
            needed it first), or None to fit it here.
    """
    if rules.none_tolerance is None or rules.min_explained is None:
        raise ValueError(
            "select_effects needs none_tolerance and min_explained set (DiagnosisConfig.with_rules)"
        )
    if nominal is None:
        nominal = fit_model(trials, y_band, (), hp, family=family)
    stages = [nominal]
    gap0, _, _ = held_out_gap(nominal, trials, y_band)
    excess0 = max(gap0 - floor, 0.0)
    n_eff = effective_samples(trials, band_share)
    rankings: list[list[dict]] = []
    indistinct: list[dict] = []
    selected: list[Surrogate] = []
    current = nominal
    for step in range(rules.max_effects):
        gap_c, rss_c, _ = held_out_gap(current, trials, y_band)
        names = {s.name for s in selected}
        entries = []
        tried = [n for n in candidates if n not in names and _INCOMPATIBLE.get(n) not in names]
        progress.stage(f"try effects (step {step + 1})", len(tried), "candidates")

        # the candidates' fits are independent: on threads (NumPy's FFTs, SciPy's filters and
        # BLAS release the GIL), each the same computation as alone, so the same numbers; BLAS
        # on one thread, as the pool already fills the cores: its products here are small (a
        # few columns by 10^4 samples), and OpenBLAS's own threads, woken for each one, cost more
        # than they gave (REKLAB folder on the 2-core machine: 74 s of CPU, 40 s wall with them;
        # 44 s, 27 s without)
        with single_threaded_blas(), ThreadPoolExecutor(max_workers=usable_cpus()) as pool:
            fits = {
                n: pool.submit(
                    fit_model,
                    trials,
                    y_band,
                    (*selected, candidates[n]),
                    hp,
                    theta0=current.theta,
                    nominal_beta=nominal.beta,
                    family=family,
                )
                for n in tried
                if candidates[n].kind != "absorbed"
            }
            try:
                for name in tried:  # in the candidates' order, as the ranking's ties are broken
                    if name not in fits:
                        entries.append(_entry(name, gap_c, gap_c, 0.0, 0, excess0, None, identifiable=False))
                        progress.advance()
                        continue
                    fm = fits[name].result()
                    gap, rss, _ = held_out_gap(fm, trials, y_band)
                    counted = candidates[name].counts_as
                    dp = fm.n_params - current.n_params if counted is None else counted
                    dbic = delta_bic(rss, rss_c, dp, n_eff)
                    shown = active_params(fm.theta, (*selected, candidates[name]))
                    entries.append(_entry(name, gap_c, gap, dbic, dp, excess0, fm, params=shown))
                    progress.advance()
            except BaseException:  # an interrupt: the fits not started are dropped, not waited for
                pool.shutdown(cancel_futures=True)
                raise
        entries = _by_score(entries)
        rankings.append(entries)
        best = entries[0] if entries else None
        if best is None or best["model"] is None:
            break
        reduction = gap_c - best["held_out_gap"]
        if not step_accepted(
            rules, first=step == 0, excess0=excess0, floor=floor, reduction=reduction, dbic=best["delta_bic"]
        ):
            break
        for other in entries[1:]:
            red_o = gap_c - other["held_out_gap"]
            if other["identifiable"] and red_o >= rules.indistinct_ratio * reduction:
                indistinct.append(
                    {
                        "effects": [best["name"], other["name"]],
                        "reductions": [reduction, red_o],
                        "separating_trial": _separating_trial(best["name"], other["name"]),
                    }
                )
        selected.append(candidates[best["name"]])
        current = best["model"]
        stages.append(current)
    partial: list[str] = []
    if selected:
        verdict = [s.name for s in selected]
        left = held_out_gap(current, trials, y_band)[0] - floor
        if not explains_enough(rules, left=left, excess0=excess0, floor=floor):
            partial, verdict = verdict, ["unknown"]
    else:
        verdict = ["none"] if gap0 - floor <= rules.none_tolerance * floor else ["unknown"]
    for name, sur in candidates.items():
        if sur.kind == "absorbed":
            indistinct.append(
                {
                    "effects": [name, sur.absorbed_by],
                    "reductions": [0.0, 0.0],
                    "separating_trial": _separating_trial(name, sur.absorbed_by),
                }
            )
    return Selection(
        verdict=verdict, stages=stages, rankings=rankings, floor=floor, indistinct=indistinct, partial=partial
    )


def _by_score(entries: list[dict]) -> list[dict]:
    """The ranking's order: by ``delta_bic``, stable (ties keep the candidates' order); a NaN score
    (a zero held-out residual of the current model, a degenerate fit) last, where Python's sort
    would leave it wherever it fell and let a worse candidate ahead of it pass as the best.

    A candidate that cannot be identified (kind ``absorbed``: not fitted, its row scored 0.0)
    follows every fitted one that has a score: at 0.0 it ranked above the fitted candidates that
    did not pay for their parameters, and could push a right effect out of the top two.
    """
    return sorted(
        entries,
        key=lambda e: (bool(np.isnan(e["delta_bic"])), not e.get("identifiable", True), e["delta_bic"]),
    )


def _entry(name, gap_before, gap, dbic, dp, excess0, model, identifiable=True, params=None) -> dict:
    """One ranking row; ``params``: the parameters to show (default: all of ``model``'s)."""
    red = gap_before - gap
    return {
        "name": name,
        "held_out_gap": gap,
        "gap_reduction": red,
        "explained_fraction": red / excess0 if excess0 > 0 else 0.0,
        "delta_bic": dbic,
        "added_params": dp,
        "identifiable": identifiable,
        "params": params if params is not None else (dict(model.theta) if model is not None else {}),
        "model": model,
    }
