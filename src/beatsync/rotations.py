"""Rotation-aware sampling and blending of motion.

Joint rotations are interpolated as quaternions (slerp), never as Euler angles (which
fail across the +-180 deg wrap). Of the equivalent Euler triples a rotation has,
``(a, b, c)`` and ``(a + 180, 180 - b, c + 180)`` each up to multiples of 360 deg,
the one nearest a reference (the source frame's own angles) is returned, so a motion
sampled at its own frame times comes back unchanged and curves stay continuous.
Times are seconds of the source motion's timeline; rotations are degrees.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import ParameterError
from .motion import Motion
from .quaternions import quat_from_euler
from .validation import check_finite, time_to_frames

__all__ = [
    "euler_to_rotation",
    "rotation_to_euler",
    "nearest_euler",
    "continuous_euler",
    "wrap_degrees",
    "sample_motion",
    "blend_values",
    "slerp",
]


def wrap_degrees(angle: np.ndarray) -> np.ndarray:
    """Wrap angles [deg] into [-180, 180)."""
    return (np.asarray(angle, dtype=np.float64) + 180.0) % 360.0 - 180.0


def nearest_euler(euler: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Row by row, of the equivalent Euler triples ``(n, 3)`` [deg], the one nearest
    ``reference`` (smallest squared distance)."""
    e = np.atleast_2d(np.asarray(euler, dtype=np.float64))
    ref = np.asarray(reference, dtype=np.float64).reshape(e.shape)
    alt = np.stack([e[:, 0] + 180.0, 180.0 - e[:, 1], e[:, 2] + 180.0], axis=1)
    a, b = (c + 360.0 * np.round((ref - c) / 360.0) for c in (e, alt))
    take_b = np.sum((b - ref) ** 2, axis=1) < np.sum((a - ref) ** 2, axis=1)
    return np.where(take_b[:, None], b, a)


def continuous_euler(euler: np.ndarray) -> np.ndarray:
    """An Euler-triple curve ``(n, 3)`` [deg] without 360 deg jumps or gimbal flips: each
    frame's triple nearest the previous one."""
    e = np.asarray(euler, dtype=np.float64)
    out = e.copy()
    for i in range(1, e.shape[0]):
        out[i] = nearest_euler(e[i : i + 1], out[i - 1 : i])[0]
    return out


def euler_to_rotation(angles_deg: np.ndarray, order: str) -> Rotation:
    """Rotations from intrinsic Euler angles [deg] in BVH channel ``order`` (e.g. ``"ZXY"``)."""
    return Rotation.from_quat(quat_from_euler(angles_deg, order))


def rotation_to_euler(rot: Rotation, order: str, reference: np.ndarray | None = None) -> np.ndarray:
    """Intrinsic Euler angles ``(n, 3)`` [deg] of ``rot``; nearest ``reference`` if given."""
    with warnings.catch_warnings():
        # at gimbal lock scipy warns and sets the third angle to 0: the same rotation
        warnings.filterwarnings("ignore", message="Gimbal lock detected", category=UserWarning)
        e = rot.as_euler(order.upper(), degrees=True)
    e = np.atleast_2d(e)
    if reference is None:
        return e
    return nearest_euler(e, reference)


def slerp(q0: np.ndarray, q1: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation of unit quaternions ``(n, 4)`` with weights ``w`` (n,)."""
    dot = np.sum(q0 * q1, axis=1)
    q1 = np.where(dot[:, None] < 0, -q1, q1)
    dot = np.abs(dot)
    w = np.asarray(w, dtype=np.float64)[:, None]
    theta = np.arccos(np.clip(dot, -1.0, 1.0))[:, None]
    sin_t = np.sin(theta)
    small = sin_t < 1e-9  # (nearly) the same rotation: linear weights
    safe = np.where(small, 1.0, sin_t)
    s0 = np.where(small, 1.0 - w, np.sin((1.0 - w) * theta) / safe)
    s1 = np.where(small, w, np.sin(w * theta) / safe)
    q = s0 * q0 + s1 * q1
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _interp_values(motion: Motion, v0: np.ndarray, v1: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Per-row interpolation from ``v0`` (w=0) to ``v1`` (w=1): slerp on rotation triples,
    the shortest way round on lone rotation channels, linear on the rest."""
    out = v0 * (1.0 - w[:, None]) + v1 * w[:, None]
    partial = motion.partial_rotation_columns()
    if partial:
        d = wrap_degrees(v1[:, partial] - v0[:, partial])
        out[:, partial] = v0[:, partial] + w[:, None] * d
    for _joint, idx, order in motion.rotation_triples():
        cols = list(idx)
        q = slerp(quat_from_euler(v0[:, cols], order), quat_from_euler(v1[:, cols], order), w)
        ref = np.where(w[:, None] < 0.5, v0[:, cols], v1[:, cols])
        out[:, cols] = rotation_to_euler(Rotation.from_quat(q), order, reference=ref)
    return out


def sample_motion(motion: Motion, times: np.ndarray) -> np.ndarray:
    """Values ``(m, n_channels)`` of ``motion`` at any times [s], clipped to its span.

    Rotation triples are slerped between the neighbouring frames, other channels
    interpolated linearly.

    Examples
    --------
    >>> import numpy as np
    >>> m = Motion(np.array([[0.0], [10.0]]), fps=10.0, channels=("a",))
    >>> sample_motion(m, np.array([0.05]))
    array([[5.]])
    """
    t = check_finite(times, name="times")
    if t.ndim != 1:
        raise ParameterError(f"times must be 1-D [s], got shape {t.shape}")
    f = np.clip(time_to_frames(t, fps=motion.fps, round_to_int=False), 0.0, motion.n_frames - 1)
    i0 = np.floor(f).astype(np.int64)
    i1 = np.minimum(i0 + 1, motion.n_frames - 1)
    w = f - i0
    return _interp_values(motion, motion.values[i0], motion.values[i1], w)


def blend_values(motion: Motion, a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Blend pose sequences ``a``, ``b`` ``(n, n_channels)`` of ``motion``'s channel layout
    frame by frame; ``w`` ``(n,)`` is the weight of ``b`` in [0, 1]."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    if w.ndim != 1 or a.shape != b.shape or a.shape != (w.size, motion.n_channels):
        raise ParameterError(
            f"blend_values needs a, b of shape (n, {motion.n_channels}) and w of shape (n,); "
            f"got {a.shape}, {b.shape}, {w.shape}"
        )
    if np.any((w < 0) | (w > 1)):
        raise ParameterError(f"blend weights w must lie in [0, 1], got {w.min():g} to {w.max():g}")
    return _interp_values(motion, a, b, w)
