"""Output-path checks and the PNG writer shared by the figure and recording writers."""

from __future__ import annotations

from pathlib import Path

from armlab.errors import DataError

__all__ = ["fresh_path", "save_png"]

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

    The file is opened ``"xb"``: never overwritten, even if one appeared since the check.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # plotting only when plotting

    p = fresh_path(path, ".png")
    FigureCanvasAgg(fig)
    with open(p, "xb") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    return p
