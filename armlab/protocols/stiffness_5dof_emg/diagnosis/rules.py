"""The selection thresholds of the ``stiffness_5dof_emg`` diagnosis (used where a setting is None).

Provisional, set from the clean lab before tuning (see docs/stiffness_5dof_emg.md, Diagnosis).
"""

__all__ = ["RULES"]

RULES = {"none_tolerance": 0.25, "min_explained": 0.8}
