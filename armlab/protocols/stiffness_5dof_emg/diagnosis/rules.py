"""The selection thresholds of the ``stiffness_5dof_emg`` diagnosis (used where a setting is None).

Chosen on the referee's tuning seed 7 (3 replicates per class; evaluation seeds start at 1000):

``none_tolerance``: the clean lab scored 0.99-1.23 x floor (seed 7's three datasets and the test's
seed 3); 0.5 keeps a margin above them, while a reflex of ENR 0.2 already scored 1.67.
``min_explained``: the reflex and base-drift surrogates removed 0.91-1.00 of the nominal excess on
their own datasets (the lab's law is the surrogate's form), the marker surrogate 0.81 at ENR 0.92
and 0.97 at ENR 2.2 (seeds 7, 8).
"""

__all__ = ["RULES"]

RULES = {"none_tolerance": 0.5, "min_explained": 0.8}
