"""MuJoCo's C functions called from numba kernels, and a batch of forward evaluations.

A numba kernel cannot call the Python bindings, but it can call MuJoCo's own shared library: the
Python package ships it beside its modules and the bindings load it, so a function's address in
it (:func:`mujoco_function_address`) called on ``MjModel._address`` / ``MjData._address`` runs on
the very structures the bindings wrap. :func:`call` calls such a ``void f(const mjModel*,
mjData*)`` (``mj_step``, ``mj_fwdPosition``, ...); :func:`f64_pointer` turns an array's address
(``arr.ctypes.data``) into a pointer that ``numba.carray`` reads and writes. Addresses are passed
as arguments, never baked into the compiled code, so numba's on-disk cache stays valid across
processes.

:func:`joint_forces` evaluates the actuator and passive forces of chosen joints at a batch of
positions and velocities with the activations as they are in the data (frozen: no ``mj_step``),
the forces the ground truth differentiates (:mod:`armlab.models.ground_truth`).
"""

from __future__ import annotations

import ctypes
from functools import cache
from pathlib import Path

import mujoco
import numpy as np
from llvmlite import ir
from numba import carray, njit, types
from numba.extending import intrinsic

from armlab.errors import SimulationError

__all__ = [
    "call",
    "f64_pointer",
    "joint_forces",
    "mujoco_function_address",
    "mujoco_library_path",
]


def mujoco_library_path() -> Path:
    """MuJoCo's shared library, the one the Python bindings load: the package ships it beside its
    modules (``libmujoco.so.<version>`` on Linux, ``libmujoco.<version>.dylib`` on macOS,
    ``mujoco.dll`` on Windows).

    Raises:
        SimulationError: the library is not found beside the ``mujoco`` package.
    """
    folder = Path(mujoco.__file__).parent
    found = sorted(folder.glob("libmujoco.so*")) + sorted(folder.glob("libmujoco*.dylib"))
    found += sorted(folder.glob("mujoco.dll"))
    if not found:
        raise SimulationError(
            f"MuJoCo's shared library was not found beside its Python bindings in {folder} "
            "(looked for libmujoco.so*, libmujoco*.dylib, mujoco.dll); reinstall mujoco==3.17.*"
        )
    return found[0]


@cache
def mujoco_function_address(name: str) -> int:
    """Address of the MuJoCo C function ``name`` in :func:`mujoco_library_path` (loading it again
    returns the process's one copy)."""
    return int(ctypes.cast(getattr(ctypes.CDLL(str(mujoco_library_path())), name), ctypes.c_void_p).value)


@intrinsic
def f64_pointer(typingctx, address):
    """An ``int64`` address as a ``double*``."""
    sig = types.CPointer(types.float64)(address)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(types.CPointer(types.float64)))

    return sig, codegen


@intrinsic
def call(typingctx, function, model, data):
    """Call ``void f(const mjModel*, mjData*)`` at address ``function``."""
    sig = types.void(function, model, data)

    def codegen(context, builder, signature, args):
        ptr = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [ptr, ptr])
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        builder.call(fn, [builder.inttoptr(args[1], ptr), builder.inttoptr(args[2], ptr)])
        return context.get_dummy_value()

    return sig, codegen


@njit(nogil=True, cache=True)
def _joint_forces(
    functions: np.ndarray,
    model: int,
    data: int,
    addr: np.ndarray,
    sizes: np.ndarray,
    qpos_idx: np.ndarray,
    dof_idx: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    out: np.ndarray,
) -> None:
    qpos = carray(f64_pointer(addr[0]), (sizes[0],))
    qvel = carray(f64_pointer(addr[1]), (sizes[1],))
    actuator = carray(f64_pointer(addr[2]), (sizes[1],))
    passive = carray(f64_pointer(addr[3]), (sizes[1],))
    for i in range(q.shape[0]):
        for j in range(qpos_idx.size):
            qpos[qpos_idx[j]] = q[i, j]
            qvel[dof_idx[j]] = qd[i, j]
        for f in range(functions.size):
            call(functions[f], model, data)
        for j in range(dof_idx.size):
            out[i, j] = actuator[dof_idx[j]] + passive[dof_idx[j]]


def joint_forces(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    qpos_idx: np.ndarray,
    dof_idx: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
) -> np.ndarray:
    """``qfrc_actuator + qfrc_passive`` of joints ``dof_idx`` at each of a batch of states.

    Every other entry of ``data`` (the other joints, the activations ``act``) is left as it is:
    the activations are frozen, as in :func:`armlab.models.ground_truth.impedance_fd`. Each row
    runs MuJoCo's ``mj_fwdPosition``, ``mj_fwdVelocity`` (passive forces) and ``mj_fwdActuation``
    (the actuator forces from the transmissions' lengths and velocities and ``act``), the stages
    of ``mj_forward`` these forces come from; ``data`` is left at the last row.

    Args:
        model, data: the model and a data holding the frozen rest of the state.
        qpos_idx, dof_idx: (k,) the joints' qpos and dof addresses (hinges or slides).
        q, qd: (n, k) positions (rad or m) and velocities.

    Returns:
        (n, k) N·m or N.
    """
    q = np.ascontiguousarray(q, dtype=float)
    qd = np.ascontiguousarray(qd, dtype=float)
    out = np.empty(q.shape)
    functions = np.array(
        [mujoco_function_address(f) for f in ("mj_fwdPosition", "mj_fwdVelocity", "mj_fwdActuation")],
        dtype=np.int64,
    )
    addr = np.array(
        [a.ctypes.data for a in (data.qpos, data.qvel, data.qfrc_actuator, data.qfrc_passive)], dtype=np.int64
    )
    _joint_forces(
        functions,
        model._address,
        data._address,
        addr,
        np.array([model.nq, model.nv], dtype=np.int64),
        np.asarray(qpos_idx, dtype=np.int64),
        np.asarray(dof_idx, dtype=np.int64),
        q,
        qd,
        out,
    )
    return out
