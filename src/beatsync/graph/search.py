"""Path searches on a weighted motion graph: the DP of paper B and its baselines.

Objective (paper B, eqs. 3-6, as we read them)
----------------------------------------------
The music is a *grid* of ``G`` intervals (its beats, or half beats, see
:mod:`beatsync.graph.timescale`) with a z-scored intensity ``z_j`` each. A dance is a
path of interval nodes ``u_0 .. u_{P-1}`` (:meth:`WeightedMotionGraph.successors`)
with boundaries ``0 = b_0 < b_1 < ... < b_P = G``: interval ``u_i`` is time-warped onto
grid intervals ``[b_i, b_{i+1})``, ``b_{i+1} - b_i`` taken from ``steps`` (``(1,)``:
one interval per beat, as in paper B). After ``u_i`` the dancer either continues with
the next beat frame's own interval (cost 0) or takes a transition edge (cost
``lam * w2``, eq. 2). The cost is

    E = sum_i sum_{j in [b_i, b_{i+1})} (z_motion(u_i) - z_j)^2 + lam * sum_{transitions} w2
        + tempo_weight * sum_i log(d_motion(u_i) / d_music(b_i, b_{i+1}))^2.

The tempo term is 0 by default. In all three searches alike, ``scale_bound = (lo, hi)``
makes an interval whose time-scale factor ``d_music / d_motion`` lies outside
``[lo, hi]`` infeasible, and ``node_mask`` restricts them to part of the graph.

:func:`dp_search` (proposed) is exact and linear in the music:
``D_k(v) = min_{s in steps} c(v, k - s, k) + min_u (D_{k-s}(u) + lam w(u, v))``. The
baseline and the control are in :mod:`beatsync.graph.baselines`.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb`` (times),
``notebooks/paper_b_tab02_quality_proxies.ipynb`` (quality); paper B sections 3.3-3.4.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..validation import check_choice
from .baselines import conventional_search, random_walk
from .build import WeightedMotionGraph
from .objective import SearchResult, grid_times, make_result, path_cost, prepare_search
from .timescale import no_path_error, span_feasible

__all__ = [
    "METHODS",
    "SearchResult",
    "dp_search",
    "dp_core",
    "conventional_search",
    "random_walk",
    "path_cost",
]

#: Search methods of :func:`beatsync.graph.compose.compose`.
METHODS = ("dp", "conventional", "random")


def dp_search(
    graph: WeightedMotionGraph,
    music_z: Any,
    *,
    lam: float = 1.0,
    start: str = "any",
    tempo_weight: float = 0.0,
    music_durations: Any = None,
    scale_bound: Any = None,
    steps: Any = (1,),
    node_mask: Any = None,
) -> SearchResult:
    """Globally optimal path by dynamic programming (paper B, eqs. 3-6, module docstring).

    ``music_z`` ``(G,)``: z-scored music intensity per grid interval; ``start``: at any
    interval node, or only at each clip's first beat frame (``"clip_start"``);
    ``music_durations`` [s] ``(G,)``: needed for ``tempo_weight > 0`` and
    ``scale_bound``; ``steps``: grid intervals one motion interval may cover;
    ``node_mask`` ``(N,)``: nodes the path may use. ``search_time`` counts the DP only.
    """
    music_z, lam, tw, md, bound, steps, mask = prepare_search(
        graph, music_z, lam, tempo_weight, music_durations, scale_bound, steps, node_mask
    )
    return dp_core(graph, music_z, lam, tw, md, bound, steps, mask, start=start)


def dp_core(graph, music_z, lam, tw, md, bound, steps, mask, *, start="any", subdivision=1):
    """:func:`dp_search` on validated inputs but ``start`` (the compose path calls this)."""
    check_choice(start, ("any", "clip_start"), name="start")
    t0 = time.perf_counter()
    pred, weight, _ = graph.predecessor_table()
    lw = weight * lam if lam > 0 else np.where(np.isinf(weight), np.inf, 0.0)
    g_n = music_z.size
    n = graph.n_nodes
    t = grid_times(md, g_n)
    dm = graph.interval_duration()
    zm = np.where(graph.is_interval, graph.z_intensity, 0.0)
    cs1 = np.concatenate([[0.0], np.cumsum(music_z)])
    cs2 = np.concatenate([[0.0], np.cumsum(music_z * music_z)])
    arrive = np.full((g_n + 1, n), np.inf)  # cost to start node v at boundary j
    arrive[0] = np.where(graph.is_interval, 0.0, np.inf)
    if mask is not None:
        arrive[0][~mask] = np.inf
    if start == "clip_start":
        first = np.ones(n, dtype=bool)
        first[1:] = graph.node_clip[1:] != graph.node_clip[:-1]
        arrive[0][~first] = np.inf
    arg_arrive = np.zeros((g_n + 1, n), dtype=np.int32)
    arg_step = np.zeros((g_n + 1, n), dtype=np.int16)
    rows = np.arange(n)
    for k in range(1, g_n + 1):
        d = np.full(n, np.inf)
        for s in steps:
            j = k - s
            if j < 0:
                continue
            ok, scale = span_feasible(dm, t, j, s, bound, mask)
            c = s * zm * zm - 2.0 * zm * (cs1[k] - cs1[j]) + (cs2[k] - cs2[j])
            if tw:
                c = c + tw * np.log(scale) ** 2
            cand = arrive[j] + np.where(ok, c, np.inf)
            better = cand < d
            d = np.where(better, cand, d)
            arg_step[k][better] = s
        if k < g_n:
            cand = d[pred] + lw
            col = np.argmin(cand, axis=1)
            arg_arrive[k] = col
            arrive[k] = cand[rows, col]
            if mask is not None:
                arrive[k][~mask] = np.inf
    end = int(np.argmin(d))
    if not np.isfinite(d[end]):
        raise no_path_error(graph, t, bound, steps, subdivision, mask)
    path, bnd = [end], [g_n]
    k, v = g_n, end
    while True:
        j = k - int(arg_step[k, v])
        bnd.append(j)
        if j == 0:
            break
        v = int(pred[v, arg_arrive[j, v]])
        path.append(v)
        k = j
    elapsed = time.perf_counter() - t0
    return make_result(
        graph, path[::-1], bnd[::-1], music_z, lam, tw, md, bound, "dp", elapsed, {"start": start}
    )
