"""The published figures treated as measurements, per paper (``armlab diagnose data=published``).

Each study runs the protocol's simulated lab, compares its outputs with the paper's published
figures and says which single-effect variant closes the gap. :data:`STUDIES` maps a protocol's
name (taken from its registered :class:`~armlab.protocols.Protocol`) to its study.
"""

from armlab.reproduction.conditioning import PROTOCOL_NAME as _CONDITIONING
from armlab.reproduction.conditioning import run_published_conditioning
from armlab.reproduction.fractional import PROTOCOL_NAME as _FRACTIONAL
from armlab.reproduction.fractional import run_published_fractional
from armlab.reproduction.vfs import PROTOCOL_NAME as _VFS
from armlab.reproduction.vfs import run_published_vfs

__all__ = [
    "STUDIES",
    "run_published_conditioning",
    "run_published_fractional",
    "run_published_vfs",
]

#: protocol name -> ``(cfg, out_dir) -> results`` (writes its report and figures into out_dir)
STUDIES = {
    _CONDITIONING: run_published_conditioning,
    _VFS: run_published_vfs,
    _FRACTIONAL: run_published_fractional,
}
