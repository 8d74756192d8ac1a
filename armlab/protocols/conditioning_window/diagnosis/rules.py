"""The selection thresholds of the ``conditioning_window`` diagnosis (used where a setting is None).

``none_tolerance``: clean tuning datasets (seed 7, 10 replicates) scored 0.79-1.29 x floor (sd
0.14; 0.4 is ~3 sd). ``min_explained``: a left-out reflex was 56-85 % "explained" by a
force-sensor low-pass or a channel delay, where correct single effects remove 85-100 % (friction
91-94 %).
"""

__all__ = ["RULES"]

RULES = {"none_tolerance": 0.4, "min_explained": 0.8}
