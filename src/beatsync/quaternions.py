"""Unit quaternions in plain numpy: Euler angles to quaternions, products, rotating vectors.

Quaternions are ``(..., 4)`` arrays with the scalar last, ``(x, y, z, w)``, as in
:class:`scipy.spatial.transform.Rotation`. Forward kinematics and slerp convert one
Euler triple per frame and joint, where scipy's per-rotation objects were the largest
cost; these vectorised forms give the same rotations (checked against scipy in the tests).
"""

from __future__ import annotations

import functools

import numpy as np

from .errors import ParameterError

__all__ = ["quat_from_euler", "quat_multiply", "quat_rotate"]

_AXIS = {"X": 0, "Y": 1, "Z": 2}


def quat_from_euler(angles_deg: np.ndarray, axes: str) -> np.ndarray:
    """Quaternions ``(n, 4)`` of intrinsic rotations about ``axes`` (one to three of X, Y, Z,
    any case) by ``angles_deg`` ``(n, len(axes))`` [deg]: ``R = R_axes[0](a0) @ R_axes[1](a1)
    @ ...``, the BVH convention (scipy's for upper-case axes).

    Examples
    --------
    >>> np.round(quat_from_euler(np.array([[90.0]]), "Z"), 6)
    array([[0.      , 0.      , 0.707107, 0.707107]])
    """
    names = axes.upper()
    if not 1 <= len(names) <= 3 or any(a not in _AXIS for a in names):
        raise ParameterError(f"axes {axes!r} must be one to three of X, Y, Z")
    a = np.asarray(angles_deg, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None] if len(names) == 1 else a[None, :]
    if a.ndim != 2 or a.shape[1] != len(names):
        raise ParameterError(
            f"angles of shape {np.shape(angles_deg)} do not match the {len(names)} axes {axes!r}"
        )
    half = np.radians(a) * 0.5
    factors = np.zeros((len(names), a.shape[0], 4))  # one rotation about each axis
    for k, name in enumerate(names):
        factors[k, :, _AXIS[name]] = np.sin(half[:, k])
        factors[k, :, 3] = np.cos(half[:, k])
    return functools.reduce(quat_multiply, factors)


def quat_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p * q`` (apply ``q`` first, then ``p``), scalar last, broadcast."""
    px, py, pz, pw = np.moveaxis(np.asarray(p, dtype=np.float64), -1, 0)
    qx, qy, qz, qw = np.moveaxis(np.asarray(q, dtype=np.float64), -1, 0)
    return np.stack(
        [
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz,
        ],
        axis=-1,
    )


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (..., 3) by unit quaternions ``q`` (..., 4), broadcast."""
    q = np.asarray(q, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    u = q[..., :3]
    w = q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)
