"""The error of a signal recorded on a grid (an encoder's angle, a converter's torque), run by run.

Just after the recorded signal rises across an edge its error ``e = recorded - true`` is ``+q/2``,
just before it does ``-q/2``, and between two crossings the true signal stays in one cell.
:class:`GridRuns` makes ``e`` of each run (samples between two changes) a settling from the edge it
came in at to a position ``u`` in the cell and back to the edge it goes out at, each at the least
speed the crossing allows (a step in the samples of the shorter run it joins; k - 1 steps a sample
where a change spans k), with ``u`` drawn uniform over the step: a run of one sample between fast
changes is a uniform error (white, ``q²/12``), a hold its own constant with the move's bursts at its
ends. Checked against the true error of synthetic grids in ``tests/test_joint_position_sensor.py``
(the angle, :func:`.position_sensor.grid_floor`) and ``tests/test_joint_none.py`` (the torque,
:func:`.data.noise_floor`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["GRID_DRAWS", "GridRuns"]

#: draws of the held signal's positions in their cells averaged by a grid's floor
GRID_DRAWS = 16


class GridRuns:
    """A recorded signal's runs on its grid (samples between two changes) and what the changes say
    of the grid's error ``e = recorded - true`` at each run's ends (module docstring)."""

    def __init__(self, x_raw: np.ndarray, q: float) -> None:
        d = np.diff(x_raw)
        ch = np.flatnonzero(np.abs(d) > 0.5 * q)  # a change between samples i and i + 1
        up = np.sign(d[ch])
        starts = np.concatenate([[0], ch + 1])
        self.length = np.diff(np.concatenate([starts, [x_raw.size]]))  # samples
        self.run = np.repeat(np.arange(starts.size), self.length)
        self.pos = np.arange(x_raw.size) - starts[self.run] + 0.5  # samples since the crossing in
        nan = np.array([np.nan])  # the record's first and last runs have no crossing there
        # e just after the crossing in (+q/2 after a rise), just before the one out (-q/2 before one)
        self.first = np.concatenate([nan, 0.5 * q * up])
        self.last = np.concatenate([-0.5 * q * up, nan])
        # per sample, the least speed at each crossing: a step in the samples of the shorter run
        # it joins, or, where the change spans k > 1 steps, k - 1 steps in one sample
        n = self.length
        speed = np.maximum(q / np.minimum(n[:-1], n[1:]), np.abs(d[ch]) - q)
        self.speed_in = np.concatenate([[q], speed])
        self.speed_out = np.concatenate([speed, [q]])

    def error(self, u: np.ndarray) -> np.ndarray:
        """(n,) the error (the signal's unit) with the signal at ``u`` in its cell in each run (one
        per run, from the cell's centre): it leaves the edge it came in at for ``u`` at the speed it
        came in at and reaches the edge it goes out at likewise (exponentials)."""
        r, pos, n = self.run, self.pos, self.length
        first = np.where(np.isnan(self.first), u, self.first)
        last = np.where(np.isnan(self.last), u, self.last)
        tau_in = np.maximum(np.abs(first - u) / self.speed_in, 1e-9)[r]  # samples
        tau_out = np.maximum(np.abs(last - u) / self.speed_out, 1e-9)[r]
        return u[r] + (first - u)[r] * np.exp(-pos / tau_in) + (last - u)[r] * np.exp(-(n[r] - pos) / tau_out)
