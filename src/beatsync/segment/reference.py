"""The literal reference of eqs. 1-5: Python loops over DAG edges, channels and samples.

Paper A (Panagiotakis et al.), section 3, written out without vectorisation: the
reference the tests and ``benchmarks/bench_segment.py`` compare the fast path
(:mod:`.costs`, :mod:`.search`) with (same optimum and free-end rules, far slower).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .costs import FLAT_REL_VAR
from .search import min_mean_energy

__all__ = ["literal_edge_cost", "segment_literal", "literal_dp"]


def literal_edge_cost(x: np.ndarray, t0: int, t1: int, t2: int) -> float:
    """Eqs. 1-2 for one pair of consecutive periods, written out with loops."""
    n_ch = x.shape[0]
    d0, d1 = t1 - t0, t2 - t1
    e = 0.0
    for ch in range(n_ch):
        a_seg = x[ch, t0 : t1 + 1]
        b_seg = np.interp(np.arange(d0 + 1) * (d1 / d0), np.arange(d1 + 1), x[ch, t1 : t2 + 1])
        ma, mb = a_seg.mean(), b_seg.mean()
        num = 0.0
        va = FLAT_REL_VAR * (d0 + 1)
        vb = FLAT_REL_VAR * (d0 + 1)
        for k in range(d0 + 1):
            num += (a_seg[k] - ma) * (b_seg[k] - mb)
            va += (a_seg[k] - ma) ** 2
            vb += (b_seg[k] - mb) ** 2
        e += 1.0 - num / np.sqrt(va * vb)
    return e


def segment_literal(
    x: np.ndarray, lo: int, hi: int, reward: float | None = None
) -> tuple[np.ndarray, float]:
    """Reference: direct, loop-by-loop implementation of eqs. 1-5 (no vectorisation).

    Every DAG edge is costed with :func:`literal_edge_cost` once, then relaxed in
    topological order by :func:`literal_dp`. ``reward``: solve ``argmin E - reward (p - 1)``
    (0: the plain ``argmin E``); ``None``: the Dinkelbach iteration of
    :func:`min_mean_energy` (the objective of :func:`segment`). Returns the boundary
    frames and the energy E.
    """
    n = x.shape[1]
    edges: dict[tuple[int, int, int], float] = {}
    for t1 in range(lo, n):  # every edge (t0, t1) -> (t1, t2) of the DAG
        for t0 in range(max(t1 - hi, 0), t1 - lo + 1):
            for t2 in range(t1 + lo, min(t1 + hi, n - 1) + 1):
                edges[(t0, t1, t2)] = literal_edge_cost(x, t0, t1, t2)
    solve = lambda r: literal_dp(edges, n, lo, hi, r)  # noqa: E731
    if reward is None:
        return min_mean_energy(solve)
    return solve(reward)


def literal_dp(
    edges: dict[tuple[int, int, int], float], n: int, lo: int, hi: int, reward: float
) -> tuple[np.ndarray, float]:
    """Shortest path over the DAG of boundary pairs with plain loops (eqs. 4-5)."""
    start: set[tuple[int, int]] = set()
    for t0 in range(lo):  # first pairs (t0, t1): lead-in shorter than any period
        for t1 in range(t0 + lo, min(t0 + hi, n - 1) + 1):
            start.add((t0, t1))
    best: dict[tuple[int, int], float] = {}  # chains with at least one edge
    back: dict[tuple[int, int], tuple[int, int]] = {}
    for t1 in range(lo, n):  # topological order: by middle boundary
        for t0 in range(t1 - hi, t1 - lo + 1):
            here = min(0.0 if (t0, t1) in start else np.inf, best.get((t0, t1), np.inf))
            if not np.isfinite(here):
                continue
            for t2 in range(t1 + lo, min(t1 + hi, n - 1) + 1):
                cand = here + edges[(t0, t1, t2)] - reward
                if cand < best.get((t1, t2), np.inf):
                    best[(t1, t2)] = cand
                    back[(t1, t2)] = (t0, t1)
    ends = [(k, v) for k, v in best.items() if k[1] >= n - lo]  # tail shorter than lo
    if not ends:
        raise ParameterError(
            f"no segmentation into two or more periods of {lo}-{hi} frames fits {n} frames"
        )
    node, energy = min(ends, key=lambda kv: kv[1])
    frames = [node[1], node[0]]
    while True:
        prev = back[node]
        frames.append(prev[0])
        if prev in start and (prev not in best or 0.0 <= best[prev]):
            break
        node = prev
    frames_arr = np.array(frames[::-1], dtype=np.int64)
    return frames_arr, float(energy) + reward * (frames_arr.size - 2)
