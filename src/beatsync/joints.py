"""Joint positions ``(n_frames, n_joints, 3)`` (one length unit) as arrays: bones
(joint-index pairs ``(n_bones, 2)``), bone lengths, gap filling."""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import ParameterError
from .validation import check_finite, check_fps

__all__ = ["check_bones", "infer_bones", "bone_lengths", "fill_joint_gaps"]


def check_bones(bones: Any, n_joints: int) -> np.ndarray:
    """Validate joint-index pairs: shape ``(n_bones, 2)``, integers in ``0..n_joints-1``."""
    arr = np.asarray(bones)
    if arr.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ParameterError(
            f"bones must be joint-index pairs of shape (n_bones, 2), got shape {arr.shape}"
        )
    if not np.issubdtype(arr.dtype, np.integer):
        if not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
            raise ParameterError(f"bones={arr.tolist()} must be integer joint indices")
    arr = arr.astype(np.int64)
    if arr.min() < 0 or arr.max() >= n_joints:
        raise ParameterError(
            f"bones refer to joint {int(arr.max()) if arr.max() >= n_joints else int(arr.min())}"
            f" but the motion has joints 0..{n_joints - 1} (indices, from 0)"
        )
    loops = arr[arr[:, 0] == arr[:, 1]]
    if loops.size:
        raise ParameterError(f"bone {loops[0].tolist()} joins a joint to itself; give two joints")
    return arr


def _distance_stats(pos: np.ndarray, max_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation over frames of every joint-to-joint distance."""
    step = max(1, pos.shape[0] // max_frames)
    p = pos[::step]
    n_j = p.shape[1]
    total = np.zeros((n_j, n_j))
    total_sq = np.zeros((n_j, n_j))
    chunk = max(1, 2_000_000 // (n_j * n_j * 3))
    for i in range(0, p.shape[0], chunk):
        q = p[i : i + chunk]
        d = np.sqrt(np.sum((q[:, :, None, :] - q[:, None, :, :]) ** 2, axis=-1))
        total += d.sum(axis=0)
        total_sq += (d * d).sum(axis=0)
    mean = total / p.shape[0]
    std = np.sqrt(np.maximum(total_sq / p.shape[0] - mean * mean, 0.0))
    return mean, std


def infer_bones(positions: Any, *, max_frames: int = 2000) -> np.ndarray:
    """``(joint, parent)`` bones from joint distances that stay short and constant.

    The minimum spanning tree of the cost ``mean + 2 std`` of each joint-to-joint
    distance (over at most ``max_frames`` evenly spaced frames), rooted at the most
    central joint. Where knees stay close it may join them instead of a thigh: give
    ``bones=`` to the readers when they are known.
    """
    from scipy.sparse.csgraph import breadth_first_order, minimum_spanning_tree

    pos = check_finite(positions, name="joint positions")
    if pos.ndim != 3 or pos.shape[2] != 3:
        raise ParameterError(
            f"joint positions must have shape (n_frames, n_joints, 3), got {pos.shape}"
        )
    n_j = pos.shape[1]
    if n_j < 2:
        raise ParameterError(f"bones need at least 2 joints, got {n_j}")
    mean, std = _distance_stats(pos, max_frames)
    cost = mean + 2.0 * std
    cost = cost + 1e-9 * max(float(cost.max()), 1e-12)  # zero means 'no edge' to scipy
    np.fill_diagonal(cost, 0.0)
    tree = minimum_spanning_tree(cost)
    root = int(np.argmin(mean.sum(axis=1)))
    _, parents = breadth_first_order(tree + tree.T, root, directed=False)
    bones = [(j, int(parents[j])) for j in range(n_j) if j != root and parents[j] >= 0]
    return np.array(bones, dtype=np.int64).reshape(-1, 2)


def bone_lengths(positions: Any, bones: Any) -> np.ndarray:
    """Length of every bone in every frame, ``(n_frames, n_bones)`` [position unit]."""
    pos = np.asarray(positions, dtype=np.float64)
    b = check_bones(bones, pos.shape[1])
    return np.linalg.norm(pos[:, b[:, 0]] - pos[:, b[:, 1]], axis=-1)


def fill_joint_gaps(
    positions: Any,
    fps: float,
    *,
    max_gap: float = 0.25,
    joint_names: list[str] | tuple[str, ...] | None = None,
) -> np.ndarray:
    """Fill gaps (a NaN/inf coordinate) up to ``max_gap`` [s] per joint linearly, refuse
    longer ones; gaps at the ends hold the nearest valid frame."""
    pos = np.array(positions, dtype=np.float64)
    rate = check_fps(fps)
    missing = ~np.all(np.isfinite(pos), axis=2)
    if not missing.any():
        return pos
    names = (
        [str(n) for n in joint_names]
        if joint_names is not None and len(joint_names)
        else [f"joint {j}" for j in range(pos.shape[1])]
    )
    t = np.arange(pos.shape[0])
    limit = int(np.floor(max_gap * rate + 1e-9))
    for j in np.flatnonzero(missing.any(axis=0)):
        miss = missing[:, j]
        if miss.all():
            raise ParameterError(f"{names[j]!r} is missing in every frame (all NaN)")
        edges = np.diff(np.concatenate([[0], miss.astype(np.int8), [0]]))
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        longest = int(np.argmax(stops - starts))
        if stops[longest] - starts[longest] > limit:
            a, b = int(starts[longest]), int(stops[longest])
            raise ParameterError(
                f"{names[j]!r} is missing (NaN) for {b - a} frames ({(b - a) / rate:.2f} s, "
                f"frames {a}-{b - 1}); gaps up to max_gap={max_gap:g} s are filled: fill "
                "this one before reading, raise max_gap (--max-gap), or drop the joint"
            )
        for k in range(3):
            pos[miss, j, k] = np.interp(t[miss], t[~miss], pos[~miss, j, k])
    return pos
