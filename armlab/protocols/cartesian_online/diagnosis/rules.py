"""The selection thresholds of the ``cartesian_online`` diagnosis (used where a setting is None).

Placeholder values, replaced by those chosen on the referee's tuning seeds.
"""

__all__ = ["RULES"]

RULES = {"none_tolerance": 0.4, "min_explained": 0.8}
