"""Published figures as measurements: the conditioning paper's window thresholds against the lab's.

Section IV-D of the conditioning paper (../shared/seeds/000) reports, for the full 11-parameter
joint-space least squares, three thresholds of the observation window T_obs: K positive definite
beyond 320 ms, K and D quasi-symmetric beyond 370 ms, every parameter quasi-constant beyond
400 ms (:data:`PAPER_THRESHOLDS_S`). The simulated protocol yields the same three numbers
(``results["criteria"]["full"]`` of :func:`estimate_protocol`). :func:`threshold_gap` sets them
side by side; :func:`diagnose_thresholds` changes one documented effect at a time (reflex, cuff,
sensors, muscle model, co-contraction, low-pass), recomputes the thresholds with the same seed
(same trial plan, same noise generator: a paired comparison) and ranks the changes by their
distance to the paper: the sum of |simulated − paper| in ms over the scored criteria (K-PD and
symmetry by default), a criterion never reached counting :data:`NOT_REACHED_PENALTY_MS`.

What can be concluded: which single change, among those tried, brings the simulated thresholds
closest to the published ones, and by how much the distance shrinks. What cannot:

- the thresholds are coarse: windows are 10 ms apart up to 370 ms and 30-50 ms apart in the
  extension windows (400, 450, 500 ms), so a difference of one window per criterion (10 ms) is
  at the resolution limit; the paper's "T_obs > 320 ms" is read as the threshold 320 ms (reading
  it strictly would add one window step to every paper value);
- one seed: a physical change alters every trajectory, so the noise does not cancel exactly
  between variants; differences of a window or two may be chance;
- single changes only: interactions between effects are not explored, and a variant matching the
  paper does not prove that effect is the cause (two numbers cannot single out a mechanism);
- the constancy criterion depends on armlab's ``estimator.constancy_tol`` (the paper gives no
  tolerance) and its 400 ms lies in the coarse extension windows, so it is reported, not scored.

The variant catalogue lives in :mod:`armlab.reproduction.variants`, the Markdown report in
:mod:`armlab.reproduction._conditioning_text` (both re-exported here). Pure computation
except :func:`run_published_conditioning`, which writes results.json and report.md through
:mod:`armlab.protocols._files`.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from armlab.errors import ArmlabError, ConfigError
from armlab.protocols.conditioning_window import PROTOCOL, ConditioningWindowConfig
from armlab.protocols.conditioning_window.experiment import (
    PAPER_THRESHOLDS_S,
    estimate_protocol,
    simulate_protocol,
    window_specs,
)
from armlab.reproduction._conditioning_text import CRITERIA, format_report
from armlab.reproduction.conditioning_effects import effect_variants
from armlab.reproduction.variants import Variant, candidate_variants, write_study

__all__ = [
    "PROTOCOL_NAME",
    "CRITERIA",
    "NOT_REACHED_PENALTY_MS",
    "PAPER_REDUCED_K_PD_S",
    "REDUCED_LEAD_MIN_MS",
    "SCORED_CRITERIA",
    "Variant",
    "candidate_variants",
    "effect_variants",
    "diagnose_thresholds",
    "distance_ms",
    "format_report",
    "rank_variants",
    "run_published_conditioning",
    "threshold_gap",
]

#: the protocol whose published figures this study diagnoses
PROTOCOL_NAME = PROTOCOL.name

_SIM_KEY = {"K_pd": "K_pd_from_s", "symmetric": "symmetric_from_s", "constant": "constant_from_s"}
_PAPER_KEY = {"K_pd": "K_pd_after_s", "symmetric": "symmetric_after_s", "constant": "constant_after_s"}
SCORED_CRITERIA = ("K_pd", "symmetric")
# s, section V: the window "can be reduced to about 300 ms when the inertial parameters are known"
# (Fig. 5, reduced model); a check, never scored
PAPER_REDUCED_K_PD_S = 0.30
# ms, the check: the reduced model positive definite at least this much before the full
REDUCED_LEAD_MIN_MS = 30.0
# ms, score of a criterion never reached: above the largest in-grid gap (windows 120-500 ms against
# paper values 320-400 ms: at most 380 ms), so reaching a criterion always beats missing it
NOT_REACHED_PENALTY_MS = 500.0
# quick mode (tests): 5 of the 26 windows (T_obs 130, 190, 250, 310, 370 ms + extensions) and
# 7 trials per window (6 identify, 1 validates)
QUICK_K_VALUES = (2, 8, 14, 20, 26)
QUICK_N_TRIALS = 7


def _checked(cfg: ConditioningWindowConfig, quick: bool) -> ConditioningWindowConfig:
    if not isinstance(cfg, ConditioningWindowConfig):
        raise ConfigError(
            f"need the {PROTOCOL_NAME} experiment, got {type(cfg).__name__} "
            f"(protocol {getattr(cfg, 'protocol_name', None)!r}); valid: "
            f"armlab.protocols.compose.compose(['protocol={PROTOCOL_NAME}'])[1]"
        )
    if quick:
        cfg = replace(
            cfg, scenario=replace(cfg.scenario, k_values=list(QUICK_K_VALUES), n_trials=QUICK_N_TRIALS)
        )
    return cfg


def _measure(cfg: ConditioningWindowConfig, recorded=None) -> tuple[dict, tuple]:
    """Thresholds of ``cfg`` (s), the window grid and wall time; ``recorded`` reuses a recording."""
    t0 = time.perf_counter()
    rec, scenario = recorded if recorded is not None else simulate_protocol(cfg)
    specs = window_specs(scenario, cfg.estimator)
    results, _ = estimate_protocol(rec.trials, cfg.estimator, specs)
    full, red = results["criteria"]["full"], results["criteria"]["reduced"]
    last = results["windows"][max(i for i, s in enumerate(specs) if not s.extension)]
    out = {
        "thresholds_s": {
            c: None if full[_SIM_KEY[c]] is None else round(full[_SIM_KEY[c]], 6) for c in CRITERIA
        },
        "reduced_s": {c: None if red[_SIM_KEY[c]] is None else round(red[_SIM_KEY[c]], 6) for c in CRITERIA},
        "K_longest_paper_window": last["K"],
        "windows_s": [round(s.t_obs_s, 6) for s in specs],
        "wall_s": round(time.perf_counter() - t0, 2),
    }
    return out, (rec, scenario)


def _gap(thresholds_s: dict, windows_s: list[float]) -> dict:
    """Per criterion: paper, simulated, gap in ms (simulated − paper) and a sentence."""
    out = {}
    for c in CRITERIA:
        paper, sim = PAPER_THRESHOLDS_S[_PAPER_KEY[c]], thresholds_s[c]
        if sim is None:
            text = f"not reached within the windows up to {max(windows_s) * 1e3:.0f} ms"
            out[c] = {"paper_s": paper, "simulated_s": None, "gap_ms": None, "reached": False, "text": text}
            continue
        gap = round((sim - paper) * 1e3, 3)
        word = "earlier" if gap < 0 else "later" if gap > 0 else "as published"
        text = f"from {sim * 1e3:.0f} ms vs paper {paper * 1e3:.0f} ms: {abs(gap):.0f} ms {word}"
        out[c] = {"paper_s": paper, "simulated_s": sim, "gap_ms": gap, "reached": True, "text": text}
    return out


def _reduced(measured: dict) -> dict:
    """Fig. 5 check: the reduced model's thresholds and how much earlier it is positive definite."""
    full, red = measured["thresholds_s"]["K_pd"], measured["reduced_s"]["K_pd"]
    lead = None if full is None or red is None else round((full - red) * 1e3, 3)
    return {
        "thresholds_s": measured["reduced_s"],
        "K_pd_lead_ms": lead,
        "K_longest_paper_window": measured["K_longest_paper_window"],
    }


def distance_ms(gap: dict, scored: tuple[str, ...] = SCORED_CRITERIA) -> float:
    """Sum over ``scored`` criteria of |gap| in ms; :data:`NOT_REACHED_PENALTY_MS` for one not reached."""
    bad = [c for c in scored if c not in CRITERIA]
    if bad:
        raise ConfigError(f"unknown criteria {bad}; valid: {list(CRITERIA)}")
    return float(
        sum(NOT_REACHED_PENALTY_MS if gap[c]["gap_ms"] is None else abs(gap[c]["gap_ms"]) for c in scored)
    )


def rank_variants(entries: list[dict]) -> list[dict]:
    """Entries sorted by ``distance_ms`` (smallest first), failed runs (None) last, ties by name."""
    return sorted(entries, key=lambda e: (e["distance_ms"] is None, e["distance_ms"] or 0.0, e["name"]))


def threshold_gap(cfg: ConditioningWindowConfig, *, quick: bool = False) -> dict:
    """Simulate the protocol of ``cfg`` and set its three thresholds beside the paper's.

    Returns:
        ``{"seed", "quick", "windows_s", "wall_s", "criteria": {K_pd|symmetric|constant:
        {"paper_s", "simulated_s" (None: never reached), "gap_ms", "reached", "text"}}}``.
    """
    cfg = _checked(cfg, quick)
    measured, _ = _measure(cfg)
    return {
        "seed": cfg.seed,
        "quick": quick,
        "windows_s": measured["windows_s"],
        "wall_s": measured["wall_s"],
        "criteria": _gap(measured["thresholds_s"], measured["windows_s"]),
    }


def diagnose_thresholds(
    cfg: ConditioningWindowConfig,
    variants: list[Variant] | None = None,
    *,
    quick: bool = False,
    scored: tuple[str, ...] = SCORED_CRITERIA,
) -> dict:
    """Which single effect brings the simulated thresholds closest to the paper's.

    Args:
        cfg: the nominal configuration (protocol ``conditioning_window``).
        variants: the changes to try; default :func:`candidate_variants` of ``cfg``.
        quick: 5 windows and 7 trials per window instead of the scenario's (for tests).
        scored: the criteria summed into the distance.

    Returns:
        ``{"nominal": threshold_gap-like dict + "distance_ms", "variants": ranked entries
        (name, effect, description, criteria, distance_ms, shrink_ms, wall_s, error), "verdict"}``.
    """
    cfg = _checked(cfg, quick)
    variants = effect_variants(cfg) + candidate_variants(cfg) if variants is None else variants
    configs = [v.apply(cfg) for v in variants]  # config errors surface before any simulation
    t0 = time.perf_counter()
    measured, recorded = _measure(cfg)
    nominal = {
        "criteria": _gap(measured["thresholds_s"], measured["windows_s"]),
        "reduced": _reduced(measured),
        "wall_s": measured["wall_s"],
    }
    nominal["distance_ms"] = distance_ms(nominal["criteria"], scored)
    entries = []
    for v, vcfg in zip(variants, configs, strict=True):
        entry = {
            "name": v.name,
            "effect": v.effect,
            "description": v.description,
            "criteria": None,
            "reduced": None,
            "distance_ms": None,
            "shrink_ms": None,
            "wall_s": None,
            "error": None,
        }
        reuse = recorded if replace(vcfg, estimator=cfg.estimator) == cfg else None  # estimator-only
        try:
            m, _ = _measure(vcfg, reuse)
        except ArmlabError as exc:  # a variant that fails (unstable, ill-posed) is reported, not fatal
            entry["error"] = f"{type(exc).__name__}: {exc}"
        else:
            entry["criteria"] = _gap(m["thresholds_s"], m["windows_s"])
            entry["reduced"] = _reduced(m)
            entry["distance_ms"] = distance_ms(entry["criteria"], scored)
            entry["shrink_ms"] = round(nominal["distance_ms"] - entry["distance_ms"], 3)
            entry["wall_s"] = m["wall_s"]
        entries.append(entry)
    ranked = rank_variants(entries)
    before = next((e for e in entries if e["name"] == "before_issue17"), None)
    added = _added_effects(nominal, before, entries)
    verdict = _verdict(nominal, ranked, measured["windows_s"], len(scored))
    if added is not None:
        verdict["text"] = added["text"] + " " + verdict["text"]
    return {
        "added_effects": added,
        "paper_reduced_K_pd_s": PAPER_REDUCED_K_PD_S,
        "before": before,
        "paper_s": {c: PAPER_THRESHOLDS_S[_PAPER_KEY[c]] for c in CRITERIA},
        "seed": cfg.seed,
        "quick": quick,
        "scored": list(scored),
        "windows_s": measured["windows_s"],
        "not_reached_penalty_ms": NOT_REACHED_PENALTY_MS,
        "nominal": nominal,
        "variants": ranked,
        "verdict": verdict,
        "wall_s": round(time.perf_counter() - t0, 1),
    }


def _added_effects(nominal: dict, before: dict | None, entries: list[dict]) -> dict | None:
    """Issue 17's added effects ranked: how far removing each from the default moves the thresholds
    from the paper's, and how far adding each to the earlier lab brings them closer."""
    if before is None or before["distance_ms"] is None:
        return None
    d0, d_before = nominal["distance_ms"], before["distance_ms"]

    def rows(prefix: str, ref: float) -> list[dict]:
        out = [
            {
                "name": e["name"],
                "distance_ms": e["distance_ms"],
                "change_ms": round(e["distance_ms"] - ref, 3),
            }
            for e in entries
            if e["name"].startswith(prefix) and e["distance_ms"] is not None
        ]
        return sorted(out, key=lambda r: (-abs(r["change_ms"]), r["name"]))

    removed, added = rows("remove_", d0), rows("add_", d_before)
    text = (
        f"The added effects bring the distance to the paper from {d_before:.0f} ms (lab before issue 17) "
        f"to {d0:.0f} ms; removed one at a time from the default: "
        + ", ".join(f"{r['name'][7:]} {r['change_ms']:+.0f} ms" for r in removed)
        + "; added one at a time to the earlier lab: "
        + ", ".join(f"{r['name'][4:]} {r['change_ms']:+.0f} ms" for r in added)
        + "."
    )
    return {
        "before_distance_ms": d_before,
        "after_distance_ms": d0,
        "removed": removed,
        "added": added,
        "text": text,
    }


def _verdict(nominal: dict, ranked: list[dict], windows_s: list[float], n_scored: int) -> dict:
    ok = [e for e in ranked if e["distance_ms"] is not None]
    d0 = nominal["distance_ms"]
    step_ms = round(min(b - a for a, b in zip(windows_s, windows_s[1:], strict=False)) * 1e3, 3)
    if not ok or ok[0]["distance_ms"] >= d0:
        text = (
            f"No single change brings the thresholds closer to the paper's (nominal distance {d0:.0f} ms); "
            "the gap is not explained by any one of the effects tried."
        )
        return {"best": None, "nominal_distance_ms": d0, "best_distance_ms": d0, "text": text}
    best = ok[0]
    ties = [e["name"] for e in ok[1:] if e["distance_ms"] == best["distance_ms"]]
    text = (
        f"Closest to the paper: {best['name']} ({best['description']}); distance {d0:.0f} ms -> "
        f"{best['distance_ms']:.0f} ms (shrinks by {best['shrink_ms']:.0f} ms, "
        f"{100 * best['shrink_ms'] / d0:.0f} %)."
    )
    if ties:
        text += f" Tied with {', '.join(ties)}."
    if best["shrink_ms"] <= step_ms * n_scored:
        text += (
            f" The improvement is within one window step ({step_ms:.0f} ms) per criterion: not significant."
        )
    return {
        "best": best["name"],
        "nominal_distance_ms": d0,
        "best_distance_ms": best["distance_ms"],
        "window_step_ms": step_ms,
        "tied_with": ties,
        "text": text,
    }


def run_published_conditioning(
    cfg: ConditioningWindowConfig,
    out_dir: Path,
    *,
    quick: bool = False,
    variants: list[Variant] | None = None,
) -> dict:
    """Run :func:`diagnose_thresholds` and write ``results.json`` and ``report.md`` into ``out_dir``.

    Raises:
        DataError: ``out_dir`` is not empty (checked before simulating; nothing is overwritten).
    """
    return write_study(out_dir, lambda: diagnose_thresholds(cfg, variants, quick=quick), format_report)
