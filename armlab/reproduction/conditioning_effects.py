"""The effects issue 17 added to the conditioning-window lab, as variants of the diagnosis.

The default lab of ``conditioning_window`` took three physical effects to reproduce the paper's
thresholds (see armlab/protocols/conditioning_window/config.py for magnitudes and sources): the
soft tissue between cuff and bone (cuff 20 kN/m -> 3 kN/m), the subject's within-trial activation
fluctuation and the trial-to-trial variation of co-contraction. It also reads the paper's reduced
model as the paper does (xi from the full identification) and judges quasi-constancy per second
of T_obs. :data:`BEFORE_SETTINGS` is the lab as it was before; :func:`effect_variants` removes each
effect from the default and adds each to the earlier lab, one at a time.
"""

from __future__ import annotations

from armlab.config.schema import ExperimentConfig
from armlab.reproduction.variants import Variant, variant

__all__ = ["BEFORE_SETTINGS", "effect_variants"]

#: the lab before issue 17: an assumed 20 kN/m cuff, an ideal subject, xi of the reduced model
#: from the model's truth, quasi-constancy per window step
BEFORE_SETTINGS: tuple[tuple[str, object], ...] = (
    ("cuff.stiffness_N_per_m", 2.0e4),
    ("cuff.damping_Ns_per_m", 100.0),
    ("subject.enabled", False),
    ("estimator.xi_source", "truth"),
    ("estimator.constancy_tol_per_s", None),
)


def _without(paths: tuple[str, ...]) -> list[tuple[str, object]]:
    return [(p, v) for p, v in BEFORE_SETTINGS if p not in paths]


def effect_variants(cfg: ExperimentConfig) -> list[Variant]:
    """The lab before issue 17, each added effect removed from ``cfg``, each added to the earlier lab."""
    k, c = cfg.cuff.stiffness_N_per_m, cfg.cuff.damping_Ns_per_m
    s = cfg.subject
    tissue = (("cuff.stiffness_N_per_m", k), ("cuff.damping_Ns_per_m", c))
    fluct = (
        ("subject.enabled", True),
        ("subject.fluctuation_cv", s.fluctuation_cv),
        ("subject.trial_cv", 0.0),
    )
    trial = (("subject.enabled", True), ("subject.trial_cv", s.trial_cv), ("subject.fluctuation_cv", 0.0))
    before = "the lab before issue 17 (all added effects off)"
    return [
        variant("before_issue17", "added", before, BEFORE_SETTINGS),
        variant(
            "remove_soft_tissue", "added", "default minus the soft tissue (cuff 20 kN/m)", BEFORE_SETTINGS[:2]
        ),
        variant(
            "remove_fluctuation",
            "added",
            "default minus the activation fluctuation",
            [("subject.fluctuation_cv", 0.0)],
        ),
        variant(
            "remove_trial_variation",
            "added",
            "default minus the trial-to-trial co-contraction",
            [("subject.trial_cv", 0.0)],
        ),
        variant(
            "remove_xi_full_fit",
            "added",
            "default, reduced model with the model's true xi (not the full fit)",
            [("estimator.xi_source", "truth")],
        ),
        variant(
            "add_soft_tissue",
            "added",
            f"earlier lab + soft tissue (cuff {k:.0f} N/m)",
            [*_without(("cuff.stiffness_N_per_m", "cuff.damping_Ns_per_m")), *tissue],
        ),
        variant(
            "add_fluctuation",
            "added",
            f"earlier lab + activation fluctuation ({100 * s.fluctuation_cv:g} %)",
            [*_without(("subject.enabled",)), *fluct],
        ),
        variant(
            "add_trial_variation",
            "added",
            f"earlier lab + trial-to-trial co-contraction ({100 * s.trial_cv:g} %)",
            [*_without(("subject.enabled",)), *trial],
        ),
    ]
