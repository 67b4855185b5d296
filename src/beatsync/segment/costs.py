"""Edge costs of the segmentation: Pearson distances between consecutive periods (eqs. 1-2).

The cost of an earlier period ``x[a..b]`` and the later ``x[b..c]`` is ``sum_c 1 - r_c``
with the later period linearly resampled onto the earlier one's ``b - a + 1`` samples
(end points aligned); ``x`` is standardised, channels first. Every sum in a Pearson
correlation is a fixed linear combination of lagged products ``X[s] X[s + l]`` in a
window around the middle boundary, so :func:`edge_costs` gets each as one matrix
product of windowed products with a constant kernel. A period whose variance is below
:data:`FLAT_REL_VAR` of its channel's is flat: correlation ~0, cost ~1.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

__all__ = [
    "FLAT_REL_VAR",
    "CHUNK_ELEMENTS",
    "resample_weights",
    "pair_costs",
    "edge_costs",
    "segmentation_energy",
]

FLAT_REL_VAR = 1e-6
"""Period variance floor, relative to the channel's variance (z-scored: 1e-6 per sample)."""

CHUNK_ELEMENTS = 3e5
"""Window-matrix elements per block of middle boundaries (sized for the cache)."""


def resample_weights(d0: int, d1: Any) -> tuple[np.ndarray, np.ndarray]:
    """Linear resampling of ``d1 + 1`` samples onto ``d0 + 1`` (end points aligned).

    Output sample ``k`` is ``(1 - w_k) B[j_k] + w_k B[j_k + 1]`` with ``j_k + w_k = k d1 / d0``
    (exact integer arithmetic); ``d1`` an int or an array of ints (then shape
    ``d1.shape + (d0 + 1,)``).
    """
    d1 = np.asarray(d1, dtype=np.int64)
    d1 = d1[..., None] if d1.ndim else d1
    k = np.arange(d0 + 1)
    j = (k * d1) // d0
    w = (k * d1 - j * d0) / d0
    last = j >= d1
    j = np.where(last, d1 - 1, j)
    w = np.where(last, 1.0, w)
    return j, w


def pair_costs(x: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``sum_c 1 - r_c`` of periods ``x[a..b]``, ``x[b..c]`` for triples ``a < b < c`` [frames]."""
    a, b, c = (np.asarray(v, dtype=np.int64) for v in (a, b, c))
    out = np.empty(a.size)
    d0_all, d1_all = b - a, c - b
    n_ch = x.shape[0]
    # group by earlier length so the sample grid is rectangular
    for d0 in np.unique(d0_all):
        sel = np.nonzero(d0_all == d0)[0]
        for start in range(0, sel.size, 4096):
            s = sel[start : start + 4096]
            k = np.arange(d0 + 1)
            j, w = resample_weights(int(d0), d1_all[s])  # (T, d0+1)
            pos = b[s][:, None] + j
            A = x[:, a[s][:, None] + k[None, :]]  # (C, T, d0+1)
            B = x[:, pos] * (1 - w) + x[:, pos + 1] * w
            A = A - A.mean(axis=-1, keepdims=True)  # Pearson r with the flat-period floor
            B = B - B.mean(axis=-1, keepdims=True)
            floor = FLAT_REL_VAR * (d0 + 1)
            num = np.sum(A * B, axis=-1)
            ss = (np.sum(A * A, axis=-1) + floor) * (np.sum(B * B, axis=-1) + floor)
            out[s] = n_ch - (num / np.sqrt(ss)).sum(axis=0)
    return out


@lru_cache(maxsize=32)
def _kernels(lo: int, hi: int) -> tuple[Any, ...]:
    """Constant kernels turning windowed lagged products into the Pearson sums.

    For middle boundary ``b``, earlier length ``d0`` and later length ``d1`` (combo
    ``q = (d0-lo)*band + (d1-lo)``), the resampled later period is
    ``B_k = (1-w_k) X[b+j_k] + w_k X[b+j_k+1]``. Then

    - ``sum_k B_k = sum_m U[m, q] X[b+m]``,
    - ``sum_k B_k^2 = sum_m G0[m, q] X[b+m]^2 + G1[m, q] X[b+m] X[b+m+1]``,
    - ``sum_k A_k B_k = sum_l sum_s H_l[s, q] X[b+s] X[b+s+l]`` with ``A_k = X[b-d0+k]``.
    """
    band = hi - lo + 1
    nq = band * band
    width_b = hi + 1  # offsets m = 0..hi (j+1 <= d1 <= hi)
    U = np.zeros((width_b, nq))
    G0 = np.zeros((width_b, nq))
    G1 = np.zeros((width_b, nq))
    # lag l = d0 + j - k (or +1): within [lo, hi] wherever the weight is non-zero;
    # zero-weight end terms may touch lo-1 or hi+1, so those slots exist (and stay 0)
    lags = np.arange(lo - 1, hi + 2)
    H = np.zeros((lags.size, hi + 1, nq))  # offset s = -hi..0 -> row s + hi
    for i0, d0 in enumerate(range(lo, hi + 1)):
        for i1, d1 in enumerate(range(lo, hi + 1)):
            q = i0 * band + i1
            j, w = resample_weights(d0, d1)
            k = np.arange(d0 + 1)
            np.add.at(U[:, q], j, 1 - w)
            np.add.at(U[:, q], j + 1, w)
            np.add.at(G0[:, q], j, (1 - w) ** 2)
            np.add.at(G0[:, q], j + 1, w**2)
            np.add.at(G1[:, q], j, 2 * w * (1 - w))
            s = k - d0 + hi
            np.add.at(H, (d0 + j - k - lo + 1, s, np.full_like(k, q)), 1 - w)
            np.add.at(H, (d0 + j + 1 - k - lo + 1, s, np.full_like(k, q)), w)
    # keep only the rows each lag uses, stacked into one kernel for a single product
    rows = [np.nonzero(np.any(H[i] != 0, axis=1))[0] for i in range(lags.size)]
    used = [i for i in range(lags.size) if rows[i].size]
    H_stack = np.concatenate([H[i][rows[i]] for i in used], axis=0)
    spans = [(int(lags[i]), int(rows[i][0]) - hi, int(rows[i][-1]) - hi) for i in used]
    for (lag, s0, s1), i in zip(spans, used, strict=True):
        if rows[i].size != s1 - s0 + 1:
            raise RuntimeError(f"kernel rows of lag {lag} are not contiguous")
    return U, np.concatenate([G0, G1], axis=0), H_stack, spans


def edge_costs(x: np.ndarray, lo: int, hi: int, *, dtype: type = np.float64) -> np.ndarray:
    """All DAG edge costs ``cost[b, i0, i1]``: middle boundary ``b``, lengths ``lo + i0, lo + i1``.

    Earlier period ``x[b-d0 .. b]``, later ``x[b .. b+d1]``; ``inf`` where a period leaves
    the clip. Computed in blocks of middle boundaries that fit in cache;
    ``dtype=np.float32`` halves the memory traffic (costs then differ by ~1e-5).
    """
    n_ch, n = x.shape
    band = hi - lo + 1
    U, G, H, spans = (k.astype(dtype) if isinstance(k, np.ndarray) else k for k in _kernels(lo, hi))
    pad = hi + 2
    xp = np.zeros((n_ch, n + 2 * pad), dtype=dtype)
    xp[:, pad : pad + n] = x
    wb = hi + 1
    # signals whose windows feed each product: offsets relative to the middle boundary
    q1 = np.zeros_like(xp)
    q1[:, :-1] = xp[:, :-1] * xp[:, 1:]
    b_sigs = [(xp * xp, 0, wb), (q1, 0, wb)]
    ab_sigs = []
    for lag, s0, s1 in spans:
        q = np.zeros_like(xp)
        q[:, :-lag] = xp[:, :-lag] * xp[:, lag:]
        ab_sigs.append((q, s0, s1 - s0 + 1))
    cs = np.concatenate([np.zeros((n_ch, 1)), np.cumsum(x, axis=1)], axis=1)
    cs2 = np.concatenate([np.zeros((n_ch, 1)), np.cumsum(x * x, axis=1)], axis=1)
    d0s = np.arange(lo, hi + 1)
    n0 = (d0s + 1.0)[:, None]  # samples per (resampled) period, by earlier length
    floor = FLAT_REL_VAR * n0
    cost = np.full((n, band, band), np.inf)
    b_all = np.arange(lo, n - lo)  # middle boundaries that can have both neighbours
    w_ab = sum(length for _, _, length in ab_sigs)
    chunk = max(16, int(CHUNK_ELEMENTS // (n_ch * w_ab)))
    buf_b = np.empty((n_ch, chunk, 2 * wb), dtype=dtype)
    buf_ab = np.empty((n_ch, chunk, w_ab), dtype=dtype)

    # full-length window views, made once; each block slices them (no copy until fill)
    b_views = [(sliding_window_view(sig, length, axis=1), off0) for sig, off0, length in b_sigs]
    ab_views = [(sliding_window_view(sig, length, axis=1), off0) for sig, off0, length in ab_sigs]
    x_view = sliding_window_view(xp, wb, axis=1)

    def fill(buf: np.ndarray, views: list, o: int, m: int) -> np.ndarray:
        col = 0
        for view, off0 in views:
            length = view.shape[2]
            buf[:, :m, col : col + length] = view[:, o + off0 : o + off0 + m]
            col += length
        return buf[:, :m].reshape(n_ch * m, col)

    for start in range(0, b_all.size, chunk):
        b = b_all[start : start + chunk]
        m = b.size
        o = pad + b[0]  # padded index of the first middle boundary
        sb = (x_view[:, o : o + m].reshape(n_ch * m, wb) @ U).reshape(n_ch, m, band, band)
        sbb = (fill(buf_b, b_views, o, m) @ G).reshape(n_ch, m, band, band)
        sab = (fill(buf_ab, ab_views, o, m) @ H).reshape(n_ch, m, band, band)
        st = np.clip(b[:, None] - d0s[None, :], 0, None)
        sa = cs[:, b[:, None] + 1] - cs[:, st]  # (C, m, band)
        saa = cs2[:, b[:, None] + 1] - cs2[:, st]
        ss_a = (np.maximum(saa - sa * sa / n0[:, 0], 0.0) + floor[:, 0]).astype(dtype)
        sa = sa.astype(dtype)
        # cov = sab - sa * sb / n0 ; ss_b = sbb - sb^2 / n0 (in place, to save passes)
        sb /= n0.astype(dtype)
        sab -= sa[..., None] * sb
        sb *= sb
        sb *= n0.astype(dtype)
        sbb -= sb
        np.maximum(sbb, 0, out=sbb)  # rounding can leave a flat period slightly negative
        sbb += floor.astype(dtype)
        sbb *= ss_a[..., None]
        np.sqrt(sbb, out=sbb)
        sab /= sbb
        np.clip(sab, -1.0, 1.0, out=sab)  # r of a (near-)flat period: rounding noise
        cost[b] = n_ch - sab.sum(axis=0, dtype=np.float64)
    bb = np.arange(n)[:, None, None]
    valid = (bb - d0s[None, :, None] >= 0) & (bb + d0s[None, None, :] <= n - 1)
    cost[~valid] = np.inf
    return cost


def segmentation_energy(x: np.ndarray, frames: np.ndarray) -> float:
    """Energy E (eq. 2) of given boundary frames on standardised channels ``(C, n)``."""
    frames = np.asarray(frames, dtype=np.int64)
    return float(pair_costs(x, frames[:-2], frames[1:-1], frames[2:]).sum())
