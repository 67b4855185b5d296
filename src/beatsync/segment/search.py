"""The globally optimal segmentation: DP over the forward DAG of boundary pairs (eqs. 3-5).

The result is boundary frames ``t_0 < ... < t_p`` with every period in the band
``lo..hi`` (:func:`period_band`), the first in the lead-in (``t_0 < lo``) and the last
in the tail (``t_p >= n - lo``), and the energy ``E`` (eq. 2). These functions trust
their inputs (the public entry checks with :func:`search_decimation` that the search
fits in memory); a failure here is a broken invariant and raises ``RuntimeError``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .costs import CHUNK_ELEMENTS, edge_costs, pair_costs

__all__ = [
    "SEARCH_MEMORY_BUDGET",
    "period_band",
    "shortest_path",
    "min_mean_energy",
    "count_windows",
    "count_fits",
    "shortest_path_count",
    "search_bytes",
    "search_decimation",
    "optimum",
]

SEARCH_MEMORY_BUDGET = 512 * 2**20
"""Bytes [B] the exact search may use; above it the search runs on a decimated signal."""

_FAST_DTYPE = np.float32  # edge-cost sums in float32: faster, |error| ~1e-5 per edge
_DP_BLOCK_ELEMENTS = 2e6  # elements of one block of the fixed-count DP
_MAX_REFINE_PASSES = 10  # full-rate refinement passes after a decimated search


def period_band(nominal: float, alpha: float) -> tuple[int, int]:
    """Whole-frame period lengths around ``nominal`` [frames] (eq. 3), rounded outward."""
    return int(np.floor((1 - alpha) * nominal + 1e-9)), int(np.ceil((1 + alpha) * nominal - 1e-9))


def shortest_path(
    cost: np.ndarray, n: int, lo: int, hi: int, reward: float = 0.0
) -> tuple[np.ndarray, float]:
    """DP over the forward DAG of boundary pairs, in frame order (eqs. 4-5).

    ``V[b, i]`` is the least energy of a chain of periods ending at frame ``b`` whose last
    period has ``lo + i`` frames; chains start at any ``t_0 < lo`` and end at any
    ``t_p >= n - lo``. Frames go in blocks of ``lo`` (a block depends only on earlier
    ones), so the loop runs ``n / lo`` times.
    """
    band = hi - lo + 1
    d = np.arange(lo, hi + 1)
    V0 = np.full((n, band), np.inf)  # chains of one period (start states)
    t0 = np.arange(lo)[:, None]
    t1 = t0 + d[None, :]  # first pairs (t0, t0 + d)
    ok0 = t1 <= n - 1
    V0[t1[ok0], np.broadcast_to(np.arange(band), t1.shape)[ok0]] = 0.0
    V1 = np.full((n, band), np.inf)  # chains of >= 2 periods (at least one edge)
    ptr = np.full((n, band), -1, dtype=np.int64)
    from_start = np.zeros((n, band), dtype=bool)
    Vb = V0.copy()  # min(V0, V1), final once its block is done
    for start in range(lo, n, lo):
        b = np.arange(start, min(start + lo, n))
        prev = b[:, None] - d[None, :]  # (m, band_i1): middle boundary
        ok = prev >= lo
        pc = np.where(ok, prev, 0)
        # total[m, i1, i0] = Vb[prev, i0] + cost[prev, i0, i1]
        total = Vb[pc] + (cost[pc, :, np.arange(band)[None, :]] - reward)
        total = np.where(ok[..., None], total, np.inf)
        best = np.argmin(total, axis=2)
        V1[b] = np.take_along_axis(total, best[..., None], axis=2)[..., 0]
        ptr[b] = best
        from_start[b] = V0[b] <= V1[b]
        Vb[b] = np.minimum(V0[b], V1[b])
    tail = V1[n - lo :]  # candidates for the virtual end node
    flat = int(np.argmin(tail))
    end, i = n - lo + flat // band, flat % band
    value = float(V1[end, i])
    if not np.isfinite(value):
        raise RuntimeError(
            f"no chain of two periods of {lo}-{hi} frames fits {n} frames (checked at entry)"
        )
    frames = [end]
    b = end
    while True:  # (b, i) is a state of V1
        i_prev = int(ptr[b, i])
        b_prev = b - (lo + i)
        frames.append(b_prev)
        if from_start[b_prev, i_prev]:
            frames.append(b_prev - (lo + i_prev))
            break
        b, i = b_prev, i_prev
    frames = np.array(frames[::-1], dtype=np.int64)
    return frames, value + reward * (frames.size - 2)


def min_mean_energy(solve: Any, max_iter: int = 30) -> tuple[np.ndarray, float]:
    """Dinkelbach iteration: the segmentation minimising ``E / (p - 1)``.

    ``solve(reward)`` returns the frames and energy ``E`` of ``argmin E - reward (p-1)``;
    from ``reward = 0`` the reward is set to the current mean energy per pair until that
    no longer decreases (with free ends, this keeps the optimum from dropping a period at
    an end just to have one term fewer).
    """
    frames, energy = solve(0.0)
    ratio = energy / (frames.size - 2)
    for _ in range(max_iter):
        f_new, e_new = solve(ratio)
        r_new = e_new / (f_new.size - 2)
        if r_new >= ratio - 1e-12:
            break
        frames, energy, ratio = f_new, e_new, r_new
    return frames, energy


def count_windows(n: int, lo: int, hi: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Feasible frames ``first[k] .. last[k]`` of boundary ``t_k`` (k = 0..count), free ends."""
    k = np.arange(count + 1)
    first = np.maximum(k * lo, (n - lo) - (count - k) * hi)
    last = np.minimum(lo - 1 + k * hi, (n - 1) - (count - k) * lo)
    return first, last


def count_fits(n: int, lo: int, hi: int, count: int) -> bool:
    """Whether ``count`` periods of ``lo..hi`` frames fit ``n`` frames with the free ends."""
    first, last = count_windows(n, lo, hi, count)
    return bool(np.all(first <= last))


def shortest_path_count(
    cost: np.ndarray, n: int, lo: int, hi: int, count: int
) -> tuple[np.ndarray, float]:
    """DP of :func:`shortest_path` constrained to exactly ``count`` periods (eqs. 4-5).

    Layer ``k`` holds ``V_k[b, i]`` over the frames where boundary ``t_k`` can lie
    (:func:`count_windows`); with the count fixed, ``argmin E`` is the paper's objective.
    """
    band = hi - lo + 1
    d = np.arange(lo, hi + 1)
    i1 = np.arange(band)[None, :]
    first, last = count_windows(n, lo, hi, count)
    if np.any(first > last):
        raise RuntimeError(f"{count} periods of {lo}-{hi} frames do not fit in {n} frames")
    b = np.arange(first[1], last[1] + 1)
    start = b[:, None] - d[None, :]
    V = np.where((start >= first[0]) & (start <= last[0]), 0.0, np.inf)  # layer 1
    ptrs = []
    for k in range(2, count + 1):
        b_all = np.arange(first[k], last[k] + 1)
        Vk = np.full((b_all.size, band), np.inf)
        pk = np.zeros((b_all.size, band), dtype=np.int32)
        rows = max(1, int(_DP_BLOCK_ELEMENTS // (band * band)))
        for s0 in range(0, b_all.size, rows):
            b = b_all[s0 : s0 + rows]
            prev = b[:, None] - d[None, :]  # (m, band_i1): middle boundary t_{k-1}
            ok = (prev >= first[k - 1]) & (prev <= last[k - 1])
            pc = np.clip(prev, first[k - 1], last[k - 1])
            # total[m, i1, i0] = V_{k-1}[prev, i0] + cost[prev, i0, i1]
            total = V[pc - first[k - 1]] + cost[pc, :, i1]
            total[~ok] = np.inf
            best = np.argmin(total, axis=2)
            Vk[s0 : s0 + b.size] = np.take_along_axis(total, best[..., None], axis=2)[..., 0]
            pk[s0 : s0 + b.size] = best
        V = Vk
        ptrs.append(pk)
    flat = int(np.argmin(V))
    value = float(V.flat[flat])
    if not np.isfinite(value):
        raise RuntimeError(f"no finite path of {count} periods of {lo}-{hi} frames in {n} frames")
    b, i = first[count] + flat // band, flat % band
    frames = [int(b)]
    for k in range(count, 1, -1):
        i_prev = int(ptrs[k - 2][b - first[k], i])
        b = b - (lo + i)
        frames.append(int(b))
        i = i_prev
    frames.append(int(b - (lo + i)))
    return np.array(frames[::-1], dtype=np.int64), value


def coarse_band(lo: int, hi: int, factor: int) -> tuple[int, int]:
    """Period band [coarse frames] at 1/``factor`` of the rate, inside ``[lo, hi]`` if possible."""
    lo_c, hi_c = -(-lo // factor), hi // factor
    if lo_c > hi_c:
        lo_c, hi_c = lo // factor, -(-hi // factor)
    return lo_c, hi_c


def search_bytes(n: int, lo: int, hi: int, n_ch: int, count: int | None) -> float:
    """Estimated peak memory [bytes] of the exact search (kernels, edge costs, DP)."""
    band = hi - lo + 1
    nq = band * band
    kernels = 8.0 * nq * (hi + 1) * (2 * (band + 2) + 6)  # H (dense and stacked), U, G
    chunk = max(16.0, CHUNK_ELEMENTS / (n_ch * (hi + 1)))
    blocks = 3 * 4.0 * n_ch * chunk * nq  # float32 block products
    costs = 11.0 * n * nq  # float64 cost table and its validity masks
    if count is None:
        dp = 8.0 * 4 * lo * nq + 8.0 * 6 * n * band
    else:
        first, last = count_windows(n, lo, hi, count)
        states = float(np.clip(last - first + 1, 0, None).sum()) * band
        dp = 12.0 * states + 24.0 * min(_DP_BLOCK_ELEMENTS, n * nq)
    return kernels + blocks + costs + dp


def _refine(
    x: np.ndarray, guess: np.ndarray, lo: int, hi: int, radius: int
) -> tuple[np.ndarray, float]:
    """Exact ``argmin E`` at full rate with each boundary within ``radius`` of ``guess``.

    A DP over the boundary index (states: pairs of candidate frames for consecutive
    boundaries) that keeps the count, the band and the free-end rules.
    """
    n = x.shape[1]
    p = guess.size - 1
    off = np.arange(-radius, radius + 1)
    cands = []
    for i, g in enumerate(guess):
        c = np.unique(np.clip(g + off, 0, n - 1))
        if i == 0:
            c = c[c < lo]
        if i == p:
            c = c[c >= n - lo]
        cands.append(c)
    length = cands[1][None, :] - cands[0][:, None]
    S = np.where((length >= lo) & (length <= hi), 0.0, np.inf)  # S[u, v]
    ptrs = []
    for i in range(2, p + 1):
        U, Vv, W = np.meshgrid(cands[i - 2], cands[i - 1], cands[i], indexing="ij")
        ok = np.isfinite(S)[:, :, None] & (W - Vv >= lo) & (W - Vv <= hi)
        c = np.full(U.shape, np.inf)
        if ok.any():
            c[ok] = pair_costs(x, U[ok], Vv[ok], W[ok])
        total = S[:, :, None] + c
        arg = np.argmin(total, axis=0)  # (v, w) -> u
        S = np.take_along_axis(total, arg[None], axis=0)[0]
        ptrs.append(arg)
    flat = int(np.argmin(S)) if S.size else 0
    if not S.size or not np.isfinite(S.flat[flat]):
        raise RuntimeError(
            "no full-rate segmentation near the decimated optimum fits the alpha band"
        )
    iv, iw = divmod(flat, S.shape[1])
    idx = [iw, iv]  # boundary indices p, p-1, ...
    for arg in reversed(ptrs):
        idx.append(int(arg[idx[-1], idx[-2]]))
    idx = idx[::-1]
    frames = np.array([cands[i][j] for i, j in enumerate(idx)], dtype=np.int64)
    return frames, float(S.flat[flat])


def search_decimation(
    n: int, lo: int, hi: int, n_ch: int, count: int | None, budget: float = SEARCH_MEMORY_BUDGET
) -> int | None:
    """Smallest time decimation factor whose search fits ``budget`` bytes (None: none does)."""
    factor = 1
    while True:
        lo_c, hi_c = coarse_band(lo, hi, factor)
        if lo_c < 2:
            return None
        if search_bytes((n - 1) // factor + 1, lo_c, hi_c, n_ch, count) <= budget:
            return factor
        factor += 1


def optimum(
    x: np.ndarray, lo: int, hi: int, count: int | None, factor: int = 1
) -> tuple[np.ndarray, float]:
    """Optimal boundary frames and energy, searched at 1/``factor`` of the frame rate.

    ``factor > 1``: the optimum of the decimated signal (box filter, every ``factor``-th
    frame, band :func:`coarse_band`), then every boundary refined at full rate within
    ``+-factor`` frames (float64 costs), re-centred until the energy stops decreasing: a
    local refinement, equal to the full-rate optimum whenever that lies in the window.
    """

    def search(xx: np.ndarray, lo_: int, hi_: int) -> tuple[np.ndarray, float]:
        nn = xx.shape[1]
        cost = edge_costs(xx, lo_, hi_, dtype=_FAST_DTYPE)
        if count is None:
            return min_mean_energy(lambda r: shortest_path(cost, nn, lo_, hi_, r))
        return shortest_path_count(cost, nn, lo_, hi_, count)

    if factor == 1:
        return search(x, lo, hi)
    lo_c, hi_c = coarse_band(lo, hi, factor)
    from scipy.ndimage import uniform_filter1d

    # box-filtered, every factor-th frame (coarse frame k is frame k * factor), z-scored
    xs = uniform_filter1d(x, size=factor, axis=1, mode="nearest")[:, ::factor]
    xs = xs - xs.mean(axis=1, keepdims=True)
    frames_c, _ = search(xs / np.maximum(xs.std(axis=1, keepdims=True), 1e-12), lo_c, hi_c)
    frames, energy = _refine(x, frames_c * factor, lo, hi, radius=factor)
    for _ in range(_MAX_REFINE_PASSES):  # re-centre the window until it no longer moves
        f_new, e_new = _refine(x, frames, lo, hi, radius=factor)
        if e_new >= energy - 1e-12:
            break
        frames, energy = f_new, e_new
    return frames, energy
