"""The published Table III of seeds/003 as a measurement: does the simulated lab reproduce its pattern?

Table III gives the stiffness (k_xx, k_yy, k_s per spring array K1-K5, averaged over the payloads)
and the mass (m per payload M1-M5, averaged over the arrays) identified by Method 1 (virtual
force sensor, Eq. (2)) and Method 2 (F/T sensor), beside Table I's truth. Its *pattern* is what
the two methods' errors do across the rows: :func:`pattern` summarises any such table (the
paper's, :func:`paper_table`, or a simulated one, :func:`simulated_table`) by per-method relative
error (median, mean, max, share positive), the Method 1 - Method 2 difference and least-squares
slopes / Spearman correlations of the errors against the true stiffness and payload.

:func:`diagnose_pattern` simulates the nominal lab and one documented variant per candidate effect
(:data:`VARIANTS`) with the same seed, and ranks the variants by :func:`pattern_distance` to the
paper. Only :func:`run_published_vfs` writes files.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import stats

from armlab.errors import ConfigError
from armlab.models.spring_array import TABLE_I_PAYLOADS_KG, TABLE_I_STIFFNESS
from armlab.protocols.virtual_force_sensor import PROTOCOL, VirtualForceSensorConfig
from armlab.protocols.virtual_force_sensor.experiment import simulate_vfs
from armlab.protocols.virtual_force_sensor.results import METHODS, PAPER_TABLE_III, estimate_vfs
from armlab.reproduction._vfs_text import format_report
from armlab.reproduction.variants import variant, write_study
from armlab.reproduction.vfs_headlines import PAPER, ROLE, check, headlines

__all__ = [
    "BEFORE",
    "PROTOCOL_NAME",
    "DIFF_FEATURES",
    "FEATURES",
    "VARIANTS",
    "diagnose_pattern",
    "format_report",
    "paper_table",
    "pattern",
    "pattern_distance",
    "run_published_vfs",
    "simulated_table",
]

#: the protocol whose published figures this study diagnoses
PROTOCOL_NAME = PROTOCOL.name

STIFFNESS_UNIT_N_PER_M = 100.0  # N/m: stiffness-error slopes are per 100 N/m of true stiffness
FEATURES = {  # what pattern_distance compares, all dimensionless (k_s left out: K4's is -2 N/m)
    "method1_k_median": "Method 1 stiffness error, median",
    "method2_k_median": "Method 2 stiffness error, median",
    "method1_m_median": "Method 1 mass error, median",
    "method2_m_median": "Method 2 mass error, median",
    "diff_k_xx_median": "Method 1 - Method 2, k_xx (rel. to truth), median",
    "diff_k_yy_median": "Method 1 - Method 2, k_yy (rel. to truth), median",
    "diff_m_median": "Method 1 - Method 2, m (rel. to truth), median",
    "method1_k_slope": "Method 1 stiffness error per 100 N/m of stiffness",
    "method2_k_slope": "Method 2 stiffness error per 100 N/m of stiffness",
    "method1_m_slope": "Method 1 mass error per kg of payload",
    "method2_m_slope": "Method 2 mass error per kg of payload",
}
# Method 1 - Method 2 only: blind to an error of Table I's truth, which both methods share
DIFF_FEATURES = ("diff_k_xx_median", "diff_k_yy_median", "diff_m_median")
# the diagnosis's protocol: one trial per configuration (Table III rows average 5 trials, not 15),
# at most two robot-identification trials, one arm trial (Table V from it)
_REDUCED = {"trials_per_config": 1, "arm_trials": 1}
_QUICK = {  # tests: 2 arrays x 2 payloads, 12 s trials (9 s least squares, 3 s VAF), 1 robot trial
    "stiffness": ["K1", "K4"],
    "payloads": ["M1", "M5"],
    **{"trial_s": 12.0, "id_s": 9.0, "val_s": 3.0, "settle_s": 1.0, "robot_id_trials": 1},
}


# m: the rest point of the lab's drag before issue 17 (a 0.25 m spring from the shoulder axis)
_OLD_DRAG_NEUTRAL_M = (0.25, 0.0)

#: single-effect variants of the lab (armlab/config/capstan.py, config/schema.py)
VARIANTS = (
    variant(
        "drag_off",
        "drag",
        "no cabling drag (Sec. IV-A: F/T and accelerometer cables)",
        [("capstan.drag", False)],
    ),
    variant("drag_x2", "drag", "cabling drag stiffness x2", scale=[("capstan.drag_stiffness_N_per_m", 2.0)]),
    variant(
        "drag_neutral_old",
        "drag",
        "drag neutral point 0.25 m out on the x axis (the pre-issue-17 spring's rest point)",
        [("capstan.drag_neutral_m", _OLD_DRAG_NEUTRAL_M)],
    ),
    variant(
        "cable_rigid", "cable", "rigid capstan cables (no drive compliance)", [("capstan.cable", "rigid")]
    ),
    variant(
        "cable_soft",
        "cable",
        "capstan cables half as stiff",
        scale=[("capstan.cable_stiffness_Nm_per_rad", 0.5)],
    ),
    variant(
        "model_inertia_off",
        "robot model",
        "no inertia error in the identified robot model (added for issue 17)",
        [("capstan.id_ee_mass_kg", 0.0)],
    ),
    variant(
        "hysteresis_off",
        "drag",
        "no hysteresis of the cable harness (added for issue 17)",
        [("capstan.drag_hysteresis_m", 0.0)],
    ),
    variant(
        "subject_steady",
        "subject",
        "the arm's activations held exactly (no fluctuation; added for issue 17 from paper 000)",
        [("subject.enabled", False)],
    ),
    variant("coulomb_off", "friction", "no Coulomb friction", [("capstan.coulomb_Nm", 0.0)]),
    variant("coulomb_x3", "friction", "Coulomb friction x3", scale=[("capstan.coulomb_Nm", 3.0)]),
    variant(
        "robot_table_vi", "robot model", "Method 1 uses Table VI's alphas", [("vfs.robot_model", "table_vi")]
    ),
    variant(
        "id_with_drag",
        "identification",
        "robot identified with the cabling attached",
        [("vfs.id_drag", True)],
    ),
    variant(
        "sensors_ideal", "sensors", "no sensor noise, bias or bandwidth at all", [("sensors.preset", "ideal")]
    ),
)


#: the lab before issue 17 (approximately): neither added effect, the drag pulling towards its old
#: rest point (its stiffnesses stay the new ones): the "before" of the report
BEFORE = variant(
    "before",
    "issue 17",
    "the lab without the effects added for issue 17",
    [
        ("capstan.id_ee_mass_kg", 0.0),
        ("capstan.drag_hysteresis_m", 0.0),
        ("capstan.drag_neutral_m", _OLD_DRAG_NEUTRAL_M),
        ("subject.enabled", False),
    ],
)


def _row(label: str, param: str, truth: float, m1: float, m2: float) -> dict:
    return {"label": label, "param": param, "truth": float(truth), "method1": float(m1), "method2": float(m2)}


def paper_table(labels: list[str] | None = None) -> list[dict]:
    """Rows ``{label, param, truth, method1, method2}`` of the paper's Table III beside Table I."""
    labels = list(PAPER_TABLE_III) if labels is None else labels
    if bad := [lab for lab in labels if lab not in PAPER_TABLE_III]:
        raise ConfigError(f"unknown Table III label(s) {bad}; valid: {list(PAPER_TABLE_III)}")
    rows = []
    for label in labels:
        e = PAPER_TABLE_III[label]
        if label.startswith("K"):
            f = TABLE_I_STIFFNESS[label]
            rows += [
                _row(label, n, getattr(f, n), e[0][i], e[1][i]) for i, n in enumerate(("k_xx", "k_yy", "k_s"))
            ]
        else:
            rows.append(_row(label, "m", TABLE_I_PAYLOADS_KG[label], *e))
    return rows


def simulated_table(table3: dict) -> list[dict]:
    """The same rows from ``results["fixture"]["table_III"]`` of :func:`estimate_vfs`."""
    return [
        _row(lab, n, c["method1"][n]["truth"], c["method1"][n]["mean"], c["method2"][n]["mean"])
        for lab, c in table3.items()
        for n in ("k_xx", "k_yy", "k_s", "m")
        if n in c["method1"]
    ]


def _fit(x: np.ndarray, y: np.ndarray) -> dict:
    """Least-squares slope and Spearman rho of y on x (NaN where under-determined)."""
    ok = len(x) >= 2 and np.ptp(x) > 0
    slope = float(stats.linregress(x, y).slope) if ok else float("nan")
    rho = float(stats.spearmanr(x, y).statistic) if ok and len(x) >= 3 and np.ptp(y) > 0 else float("nan")
    return {"slope": slope, "spearman_rho": rho, "n": len(x)}


def _summary(e: np.ndarray) -> dict:
    if not e.size:
        return dict.fromkeys(("median", "mean", "max_abs", "frac_positive"), float("nan"))
    med, mean, mx, pos = np.median(e), e.mean(), np.abs(e).max(), (e > 0).mean()
    return {"median": float(med), "mean": float(mean), "max_abs": float(mx), "frac_positive": float(pos)}


def pattern(table: list[dict]) -> dict:
    """Summary statistics of a Table III (rows of :func:`paper_table` / :func:`simulated_table`).

    Relative errors ``(value - truth) / |truth|``; ``k`` pools k_xx and k_yy, ``m`` the masses;
    ``diff`` is ``(method1 - method2) / |truth|``; slopes (and Spearman rho) of the relative error
    on true stiffness per 100 N/m, on payload per kg (Table III averages k over the payloads, so
    a payload trend shows only in m); k_s by its median absolute error, N/m.

    Returns:
        ``{method: {"k", "m", "k_s_median_abs_err_N_per_m", "frac_closer"}, "diff", "trend",
        "features"}``; ``features`` holds the :data:`FEATURES` of :func:`pattern_distance`.
    """
    sel = {p: [r for r in table if r["param"] == p] for p in ("k_xx", "k_yy", "k_s", "m")}
    groups = {"k": sel["k_xx"] + sel["k_yy"], "m": sel["m"]}
    scale = {"k": STIFFNESS_UNIT_N_PER_M, "m": 1.0}
    out: dict = {"labels": sorted({r["label"] for r in table}), "trend": {}, "diff": {}}
    feats: dict = {}
    abs_err = {}
    for me in METHODS:
        rel = {
            g: np.array([(r[me] - r["truth"]) / abs(r["truth"]) for r in rows]) for g, rows in groups.items()
        }
        ks = [abs(r[me] - r["truth"]) for r in sel["k_s"]]
        out[me] = {g: _summary(rel[g]) for g in groups}
        out[me]["k_s_median_abs_err_N_per_m"] = float(np.median(ks)) if ks else float("nan")
        out["trend"][me] = {
            g: _fit(np.array([r["truth"] for r in rows]) / scale[g], rel[g]) for g, rows in groups.items()
        }
        for g in groups:
            feats[f"{me}_{g}_median"] = out[me][g]["median"]
            feats[f"{me}_{g}_slope"] = out["trend"][me][g]["slope"]
        abs_err[me] = np.abs(np.concatenate([rel[g] for g in groups]))
    for me, other in (METHODS, METHODS[::-1]):
        n = abs_err[me].size
        out[me]["frac_closer"] = float((abs_err[me] < abs_err[other]).mean()) if n else float("nan")
    for p in ("k_xx", "k_yy", "m"):
        out["diff"][p] = _summary(np.array([(r["method1"] - r["method2"]) / abs(r["truth"]) for r in sel[p]]))
        feats[f"diff_{p}_median"] = out["diff"][p]["median"]
    out["features"] = {f: feats[f] for f in FEATURES}
    return out


def pattern_distance(a: dict, b: dict, features: tuple[str, ...] = tuple(FEATURES)) -> float:
    """RMS difference of the ``features`` both patterns define, in percentage points."""
    d = np.array([a["features"][f] - b["features"][f] for f in features])
    d = d[np.isfinite(d)]
    return float(100.0 * np.sqrt(np.mean(d**2))) if d.size else float("nan")


def _simulate(cfg: VirtualForceSensorConfig) -> tuple[list[dict], dict, float]:
    t0 = time.perf_counter()
    rec = simulate_vfs(cfg)
    results, _ = estimate_vfs(rec.trials, cfg.vfs, rec.truth)
    rows = simulated_table(results["fixture"]["table_III"])
    return rows, headlines(results), time.perf_counter() - t0


def diagnose_pattern(
    cfg: VirtualForceSensorConfig, variants: list[str] | None = None, *, quick: bool = False
) -> dict:
    """Gap between the paper's Table III pattern and the simulated one, and which effect closes it.

    Args:
        cfg: the virtual_force_sensor experiment; its capstan/sensors/vfs settings are the nominal
            lab (run with one trial per configuration, no arm trials, <= 2 robot-id trials).
        variants: names from :data:`VARIANTS` (default: all), each simulated with ``cfg.seed``.
        quick: 2 arrays x 2 payloads, 12 s trials (tests); the paper's rows are matched.

    Returns:
        JSON-ready: ``paper`` / ``nominal`` patterns, ``gap`` per feature, ``variants`` sorted by
        ``distance`` (percentage points to the paper, smallest first) and the ``verdict``.

    Raises:
        ConfigError: an unknown variant name (the message lists the valid ones).
    """
    catalog = {v.name: v for v in VARIANTS}
    names = list(catalog) if variants is None else list(variants)
    if bad := [n for n in names if n not in catalog]:
        raise ConfigError(f"unknown published-VFS variant(s) {bad}; valid: {list(catalog)}")
    v = cfg.vfs
    base = replace(
        cfg,
        vfs=replace(v, **_REDUCED, **(_QUICK if quick else {"robot_id_trials": min(v.robot_id_trials, 2)})),
    )
    nominal_rows, nominal_h, nominal_s = _simulate(base)
    before_rows, before_h, _ = _simulate(BEFORE.apply(base))
    paper_rows = paper_table(sorted({r["label"] for r in nominal_rows}))
    paper, nominal = pattern(paper_rows), pattern(nominal_rows)
    d_nom = pattern_distance(nominal, paper)
    d_nom_diff = pattern_distance(nominal, paper, DIFF_FEATURES)
    ranked = []
    for name in names:
        rows, h, wall = _simulate(catalog[name].apply(base))
        p = pattern(rows)
        var = catalog[name]
        ranked.append(
            {
                "name": name,
                "description": var.description,
                "change": var.change,
                "wall_s": wall,
                "distance": pattern_distance(p, paper),
                "distance_diff_only": pattern_distance(p, paper, DIFF_FEATURES),
                "pattern": p,
                "table": rows,
                "headlines": h,
                "meets": check(h),
            }
        )
    ranked.sort(key=lambda r: r["distance"])
    best = ranked[0] if ranked else None
    shrink = (d_nom - best["distance"]) / d_nom if best and d_nom > 0 else float("nan")
    if best is None or not best["distance"] < d_nom:
        text = f"no single variant brings the pattern closer to the paper's than nominal ({d_nom:.2f} pp)"
    else:
        text = (
            f"{best['name']} ({best['description']}) brings the pattern closest: {d_nom:.2f} -> "
            f"{best['distance']:.2f} pp from the paper ({100 * shrink:.0f} % of the gap closed)"
        )
    s = base.vfs
    return {
        "settings": {
            "quick": quick,
            "seed": base.seed,
            "stiffness": list(s.stiffness),
            "payloads": list(s.payloads),
            "trials_per_config": s.trials_per_config,
            "robot_id_trials": s.robot_id_trials,
            "trial_s": s.trial_s,
            "robot_model": s.robot_model,
        },
        "paper": paper,
        "paper_table": paper_rows,
        "headlines": {
            "paper": PAPER,
            "role": ROLE,
            "before": {
                "values": before_h,
                "meets": check(before_h),
                "distance": pattern_distance(pattern(before_rows), paper),
            },
            "after": {"values": nominal_h, "meets": check(nominal_h)},
        },
        "nominal": {
            "distance": d_nom,
            "distance_diff_only": d_nom_diff,
            "pattern": nominal,
            "table": nominal_rows,
            "wall_s": nominal_s,
        },
        "gap": {
            f: {
                "what": FEATURES[f],
                "paper": paper["features"][f],
                "nominal": nominal["features"][f],
                "gap": nominal["features"][f] - paper["features"][f],
            }
            for f in FEATURES
        },
        "variants": ranked,
        "verdict": {
            "best": best and best["name"],
            "nominal_distance": d_nom,
            "shrink_fraction": shrink,
            "best_distance": best["distance"] if best else float("nan"),
            "text": text,
        },
    }


def run_published_vfs(
    cfg: VirtualForceSensorConfig, out_dir: Path, *, variants: list[str] | None = None, quick: bool = False
) -> dict:
    """Run :func:`diagnose_pattern` and write ``results.json`` and ``report.md`` into ``out_dir``.

    Raises:
        DataError: ``out_dir`` is not empty (checked before simulating; nothing is overwritten).
    """

    def run() -> dict:
        t0 = time.perf_counter()
        result = diagnose_pattern(cfg, variants, quick=quick)
        return {**result, "wall_s": time.perf_counter() - t0}

    return write_study(out_dir, run, format_report)
