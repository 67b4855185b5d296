"""The frame distance of eq. 1: point clouds compared after a floor-plane alignment.

After Kovar, Gleicher and Pighin (2002), each beat frame ``f`` is the point cloud of
all joint positions over frames ``f - h .. f + h`` (:func:`point_clouds`) [position
unit]. The rigid 2-D transform (rotation about the vertical axis ``up``, translation
on the floor) that best aligns two clouds has a closed form: with both centred on the
floor plane, ``D^2 = (S_i + S_j - 2 sqrt(a^2 + b^2) - 2 Y_ij) / M`` where ``S`` are the
summed squared centred coordinates, ``a = sum(x_i x_j + z_i z_j)``,
``b = sum(x_i z_j - z_i x_j)``, ``Y_ij = sum(y_i y_j)`` and ``M`` the number of points;
the optimal angle is ``atan2(-b, a)``. The closed form cancels for nearly identical
clouds, so those entries are recomputed from direct point differences under the
optimal rotation (below :data:`CANCELLATION_RATIO`).

Notebook: ``notebooks/paper_b_tab01_search_speed.ipynb``; paper B eq. 1.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "CANCELLATION_RATIO",
    "point_clouds",
    "center_on_floor",
    "ground_axes",
    "aligned_distance_matrix",
    "aligned_pair_distance",
    "typical_speed",
]


def point_clouds(positions: np.ndarray, frames: np.ndarray, half: int) -> np.ndarray:
    """Clouds ``(len(frames), (2 half + 1) * n_joints, 3)`` of frames ``f - half .. f + half``."""
    n = positions.shape[0]
    idx = np.clip(frames[:, None] + np.arange(-half, half + 1)[None, :], 0, n - 1)
    c = positions[idx]  # (m, w, J, 3)
    return c.reshape(c.shape[0], -1, 3)


def center_on_floor(c: np.ndarray, up: int) -> np.ndarray:
    """Clouds with their mean subtracted on the two floor axes (heights kept)."""
    c = c.copy()
    for ax in ground_axes(up):
        c[:, :, ax] -= c[:, :, ax].mean(axis=1, keepdims=True)
    return c


def ground_axes(up: int) -> tuple[int, int]:
    """The two floor axes for vertical axis ``up``, right-handed: ``(g0, up, g1)`` is cyclic."""
    return {0: (1, 2), 1: (2, 0), 2: (0, 1)}[up]


#: Squared distances below this fraction of ``S_i + S_j`` lose digits to cancellation in
#: the closed form; they are recomputed from direct differences (see
#: :func:`aligned_distance_matrix`).
CANCELLATION_RATIO = 1e-4


def _direct_d2(a: np.ndarray, b: np.ndarray, theta: np.ndarray, up: int) -> np.ndarray:
    """``sum |a - R(theta) b|^2`` over points, row-wise (``a[k]`` vs ``b[k]``): no cancellation."""
    g0, g1 = ground_axes(up)
    c = np.cos(theta)[:, None]
    s = np.sin(theta)[:, None]
    # R(theta) rotates b on the floor plane so that it best matches a
    r0 = c * b[:, :, g0] - s * b[:, :, g1]
    r1 = s * b[:, :, g0] + c * b[:, :, g1]
    return np.sum(
        (a[:, :, g0] - r0) ** 2 + (a[:, :, g1] - r1) ** 2 + (a[:, :, up] - b[:, :, up]) ** 2,
        axis=1,
    )


def aligned_distance_matrix(a: np.ndarray, b: np.ndarray, *, up: int = 1) -> np.ndarray:
    """RMS distance ``(na, nb)`` between clouds after the best floor-plane rigid alignment.

    Entries with ``D^2 < CANCELLATION_RATIO * (S_i + S_j)`` come from direct differences,
    so identical clouds are at distance ~1e-8 of their size.
    """
    a = center_on_floor(a, up)
    b = center_on_floor(b, up)
    g0, g1 = ground_axes(up)
    dot = a[:, :, g0] @ b[:, :, g0].T + a[:, :, g1] @ b[:, :, g1].T
    crs = a[:, :, g0] @ b[:, :, g1].T - a[:, :, g1] @ b[:, :, g0].T
    ss = np.sum(a * a, axis=(1, 2))[:, None] + np.sum(b * b, axis=(1, 2))[None, :]
    d2 = ss - 2.0 * np.sqrt(dot * dot + crs * crs) - 2.0 * (a[:, :, up] @ b[:, :, up].T)
    theta = np.arctan2(-crs, dot)
    ii, jj = np.nonzero(d2 < CANCELLATION_RATIO * ss)
    for s in range(0, ii.size, 256):
        i, j = ii[s : s + 256], jj[s : s + 256]
        d2[i, j] = _direct_d2(a[i], b[j], theta[i, j], up)
    return np.sqrt(np.maximum(d2, 0.0) / a.shape[1])


def aligned_pair_distance(a: np.ndarray, b: np.ndarray, *, up: int = 1) -> np.ndarray:
    """Row-wise :func:`aligned_distance_matrix` (``a[k]`` vs ``b[k]``), from direct differences."""
    a = center_on_floor(a, up)
    b = center_on_floor(b, up)
    g0, g1 = ground_axes(up)
    dot = np.sum(a[:, :, g0] * b[:, :, g0] + a[:, :, g1] * b[:, :, g1], axis=1)
    crs = np.sum(a[:, :, g0] * b[:, :, g1] - a[:, :, g1] * b[:, :, g0], axis=1)
    return np.sqrt(_direct_d2(a, b, np.arctan2(-crs, dot), up) / a.shape[1])


def typical_speed(
    positions_list: Sequence[np.ndarray], fps_list: Sequence[float], *, half: int, up: int = 1
) -> float:
    """Median aligned window distance between consecutive frames, times fps [unit / s]."""
    vals = []
    for pos, fps in zip(positions_list, fps_list, strict=True):
        n = pos.shape[0]
        step = max(1, n // 2000)  # subsample very long clips
        f = np.arange(0, n - 1, step)
        for s in range(0, f.size, 500):
            ff = f[s : s + 500]
            a, b = point_clouds(pos, ff, half), point_clouds(pos, ff + 1, half)
            d = aligned_pair_distance(a, b, up=up)
            vals.append(d * fps)
    return float(np.median(np.concatenate(vals))) if vals else 0.0
