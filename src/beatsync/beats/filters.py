"""Small 1-D filters in numpy (moving mean, moving maximum, Gaussian smoothing).

They match :mod:`scipy.ndimage`'s ``uniform_filter1d``, ``maximum_filter1d`` and
``gaussian_filter1d`` with the default ``mode="reflect"`` (half-sample symmetric
edges) and an ``origin`` shift, without importing scipy (whose import dominated the
start-up time of ``beatsync beats``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["moving_mean", "moving_max", "gaussian_smooth"]


def _padded(x: np.ndarray, size: int, origin: int) -> np.ndarray:
    """Pad the last axis symmetrically for a window of ``size`` shifted by ``origin``."""
    if size < 1:
        raise ValueError(f"size={size!r}: a filter window holds at least one sample")
    left = size // 2 + origin
    right = size - 1 - left
    width = [(0, 0)] * (x.ndim - 1) + [(max(left, 0), max(right, 0))]
    return np.pad(x, width, mode="symmetric")


def moving_mean(x: np.ndarray, size: int, origin: int = 0) -> np.ndarray:
    """Mean over a window of ``size`` samples along the last axis (scipy's uniform_filter1d)."""
    xp = _padded(np.asarray(x, dtype=np.float64), size, origin)
    cs = np.cumsum(np.insert(xp, 0, 0.0, axis=-1), axis=-1)
    n = x.shape[-1]
    return (cs[..., size : size + n] - cs[..., :n]) / size


def moving_max(x: np.ndarray, size: int, origin: int = 0) -> np.ndarray:
    """Maximum over a window of ``size`` samples along the last axis (maximum_filter1d)."""
    xp = _padded(np.asarray(x), size, origin)
    n = x.shape[-1]
    out = xp[..., :n].copy()
    for j in range(1, size):  # a few taps, one pass each: 5x faster than the max of a
        np.maximum(out, xp[..., j : j + n], out=out)  # strided window view
    return out


def gaussian_smooth(x: np.ndarray, sigma: float, truncate: float = 4.0) -> np.ndarray:
    """Gaussian smoothing along the last axis (scipy's gaussian_filter1d)."""
    r = int(truncate * float(sigma) + 0.5)
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    x = np.asarray(x, dtype=np.float64)
    xp = _padded(x, 2 * r + 1, 0)
    n = x.shape[-1]
    out = k[0] * xp[..., :n]
    for j in range(1, 2 * r + 1):  # a few taps: one pass over the whole array each
        out += k[j] * xp[..., j : j + n]
    return out
