"""The robot chain of :class:`~armlab.models.robot_fk.RobotKinematics`, compiled (numba).

One sample at a time, in registers: the NumPy chain it replaced wrote nine (n, 3, 3) products per
link through memory (about 1.5 CPU-s for the 663 000 samples of the default conditioning run; this
kernel takes about 0.25 s, and it runs without the GIL, so two threads split the trials).

The operations are those of the NumPy chain, in its order: every entry of a 3×3 product sums its
three terms from k = 0 with fused multiply-adds (``fastmath={"contract"}`` on the products only),
as the BLAS behind NumPy's ``matmul`` does on a CPU with FMA; the joint rotations
``I + sin(a) K + (1 - cos(a)) K²`` are computed without fusing, as NumPy's ufuncs do. On this
project's machine the outputs are bit-identical to the NumPy chain (checked on the 663 000
samples of a default run); where a BLAS sums otherwise they differ by rounding (~1e-16 m).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["chain"]


@njit(fastmath={"contract"}, nogil=True, cache=True)
def _matmul(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    for r in range(3):
        for c in range(3):
            acc = 0.0
            for k in range(3):
                acc += a[r, k] * b[k, c]
            out[r, c] = acc


@njit(fastmath={"contract"}, nogil=True, cache=True)
def _matvec(a: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
    for r in range(3):
        acc = 0.0
        for k in range(3):
            acc += a[r, k] * v[k]
        out[r] = acc


@njit(nogil=True, cache=True)
def chain(
    base_pos: np.ndarray,
    base_rot: np.ndarray,
    link_pos: np.ndarray,
    link_rot: np.ndarray,
    k: np.ndarray,
    kk: np.ndarray,
    used: np.ndarray,
    contact_pos: np.ndarray,
    ft_rot: np.ndarray,
    q: np.ndarray,
    contact: np.ndarray,
    rot_out: np.ndarray,
) -> None:
    """Forward kinematics of every row of ``q`` (n, 7) rad into ``contact`` (n, 3) m and
    ``rot_out`` (n, 3, 3).

    ``k``, ``kk``: (7, 3, 3) each joint axis's cross-product matrix K and K²; ``used``: (7, 3, 3)
    bool, the entries where K or K² is non-zero (elsewhere the rotation's entry is the identity's);
    the other arguments as the attributes of ``RobotKinematics``.
    """
    pos = np.empty(3)
    offset = np.empty(3)
    rot = np.empty((3, 3))
    fixed = np.empty((3, 3))
    joint = np.empty((3, 3))
    for n in range(q.shape[0]):
        pos[:] = base_pos
        rot[:, :] = base_rot
        for i in range(7):
            _matvec(rot, link_pos[i], offset)
            for r in range(3):
                pos[r] = pos[r] + offset[r]
            _matmul(rot, link_rot[i], fixed)
            s = np.sin(q[n, i])
            omc = 1.0 - np.cos(q[n, i])
            for r in range(3):
                for c in range(3):
                    eye = 1.0 if r == c else 0.0
                    if used[i, r, c]:
                        joint[r, c] = eye + s * k[i, r, c] + omc * kk[i, r, c]
                    else:
                        joint[r, c] = eye
            _matmul(fixed, joint, rot)
        _matvec(rot, contact_pos, offset)
        for r in range(3):
            contact[n, r] = pos[r] + offset[r]
        _matmul(rot, ft_rot, rot_out[n])
