"""Output-path checks and the PNG writer shared by the figure and recording writers."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from armlab.data.atomic import atomic_path
from armlab.errors import DataError

__all__ = ["fresh_path", "preload_rerun", "recording", "save_png"]

DPI = 120  # dots per inch of every written figure


def fresh_path(path: str | Path, suffix: str) -> Path:
    """Return ``path`` as a :class:`Path` after checking that nothing is there yet.

    Creates the parent folder if needed. Output files are never overwritten: every run writes
    into its own fresh run directory.

    Args:
        path: where the file will be written.
        suffix: the expected file suffix, e.g. ``".png"`` or ``".rrd"``.

    Raises:
        DataError: if ``path`` already exists or has another suffix.
    """
    p = Path(path)
    if p.suffix.lower() != suffix:
        raise DataError(f"output path {str(p)!r} must end in {suffix!r}")
    if p.exists():
        raise DataError(f"refusing to overwrite existing file {str(p)!r}; write into a fresh run directory")
    p.parent.mkdir(parents=True, exist_ok=True)
    return p


def save_png(fig, path: str | Path, dpi: int = DPI) -> Path:
    """Write a matplotlib ``Figure`` as a new PNG file (:func:`fresh_path` rules); returns the path.

    The figure is drawn into a temporary file and given its name only when complete
    (:func:`armlab.data.atomic.atomic_path`): never overwritten, never half-written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # plotting only when plotting

    p = fresh_path(path, ".png")
    FigureCanvasAgg(fig)
    with atomic_path(p) as tmp, open(tmp, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    return p


def preload_rerun() -> None:
    """Import rerun and its blueprint module now (~0.3 s of CPU), e.g. on a background thread
    while a run simulates, so the first recording does not wait for the import. Optional: every
    recording writer imports rerun itself."""
    import rerun  # noqa: F401
    import rerun.blueprint  # noqa: F401


@contextmanager
def recording(path: Path, application_id: str, blueprint=None) -> Iterator:
    """A rerun ``RecordingStream`` saving to the new ``.rrd`` file ``path`` (checked by
    :func:`fresh_path`), written under a temporary name and renamed only once the stream is
    flushed and closed: an interrupted writer never leaves a truncated recording under its name.
    """
    import rerun as rr  # recordings only when recording

    with atomic_path(path) as tmp:
        rec = rr.RecordingStream(application_id)
        rec.save(tmp, default_blueprint=blueprint)
        try:
            yield rec
            rec.flush()
        finally:
            rec.disconnect()
