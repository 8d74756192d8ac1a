"""Rerun logging of a short-trial diagnosis: each trial's measured, nominal and corrected signal
and the two residuals, per channel, on the time-after-onset timeline (shared by the conditioning
and cartesian diagnosis recordings)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["TIMELINE", "log_trial_stages"]

TIMELINE = "time_after_onset"


def log_trial_stages(
    rec,
    trial: int,
    channels: Sequence[str],
    t_s: np.ndarray,
    measured: np.ndarray,
    nominal: np.ndarray,
    corrected: np.ndarray,
    held_out_text: str | None,
) -> None:
    """Log one trial into ``rec``.

    Entity paths ``trials/<trial>/<channel>/{measured,nominal,corrected,residual_nominal,
    residual_corrected}``; a held-out trial (``held_out_text`` not None) gets that text logged at
    onset under ``trials/<trial>/events``.

    Args:
        rec: an open rerun recording stream.
        channels: the channel names (last axis of the signals).
        t_s: (n,) s, time after onset of the samples.
        measured, nominal, corrected: (n, len(channels)) signals.
    """
    import rerun as rr

    index = [rr.TimeColumn(TIMELINE, duration=t_s)]
    for j, channel in enumerate(channels):
        base = f"trials/{trial:03d}/{channel}"
        for name, values in (
            ("measured", measured[:, j]),
            ("nominal", nominal[:, j]),
            ("corrected", corrected[:, j]),
            ("residual_nominal", measured[:, j] - nominal[:, j]),
            ("residual_corrected", measured[:, j] - corrected[:, j]),
        ):
            rec.send_columns(
                f"{base}/{name}", indexes=index, columns=rr.Scalars.columns(scalars=values.astype(np.float64))
            )
    if held_out_text is not None:
        rec.send_columns(
            f"trials/{trial:03d}/events",
            indexes=[rr.TimeColumn(TIMELINE, duration=[0.0])],
            columns=rr.TextLog.columns(text=[held_out_text], level=["INFO"]),
        )
