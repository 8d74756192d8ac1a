"""The selection thresholds of the ``joint_1dof`` diagnosis (used where a setting is left at None).

``none_tolerance``: how far above the floor a clean recording's held-out gap may scatter: clean
tuning datasets (seeds 0 and 7, 12 replicates each) scored 0.95-1.06 x floor (sd 0.03; 0.15 is
~5 sd). ``min_explained``: the share of the nominal excess the selected effects must remove, else
the verdict is ``unknown``: the co-contraction surrogate removes only 67-76 % of a strong
variation (tuning seed 0), and no left-out effect here was partly absorbed.
"""

__all__ = ["RULES"]

RULES = {"none_tolerance": 0.15, "min_explained": 0.5}
