"""Large arrays without transparent-huge-page stalls while a run computes.

NumPy advises the kernel to back every array of 4 MiB or more with 2 MiB transparent huge pages
(``madvise(MADV_HUGEPAGE)``, on by default on Linux). Where the kernel answers that advice by
compacting memory at the moment of the page fault (``/sys/kernel/mm/transparent_hugepage/defrag``
set to ``madvise`` or ``always``, the kernel's default), the first write into each new large array
stalls while 2 MiB blocks are assembled. A run writes hundreds of MB of fresh arrays (the
conditioning protocol's 780 trials x 850 samples x 73 sensor values alone are 387 MB): measured on
the 2-core CI machine (`make bench`, session 15), its simulate stage took 10.2-10.8 s with the
advice and 8.7 s without, and the first touch of a fresh 387 MB array 1.1 s against 0.18 s. The
arrays are streamed through once, so the larger pages buy no measurable speed back.

:func:`small_pages` turns the advice off for the duration of a run and restores what was set
before (a notebook's other work keeps NumPy's default). It changes where memory comes from, never
a value: trial data and results are bit-identical with and without it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

__all__ = ["small_pages"]


def _setter():
    """NumPy's switch of the huge-page advice (``_set_madvise_hugepage``; it returns the value set
    before), or None on a NumPy without it."""
    core = getattr(np, "_core", None) or getattr(np, "core", None)
    return getattr(getattr(core, "multiarray", None), "_set_madvise_hugepage", None)


@contextmanager
def small_pages() -> Iterator[None]:
    """NumPy's new arrays without the huge-page advice inside the block (see the module's text)."""
    setter = _setter()
    if setter is None:
        yield
        return
    before = setter(False)
    try:
        yield
    finally:
        setter(before)
