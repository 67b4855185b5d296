"""The baselines of paper B's comparison: the multi-stage search and the random walk.

Both follow the objective and feasibility rules of :mod:`beatsync.graph.search`.
Notebook: ``notebooks/paper_b_tab01_search_speed.ipynb``; paper B section 4.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validation import as_float, as_int, check_positive
from .build import WeightedMotionGraph
from .objective import SearchResult, grid_times, make_result, prepare_search
from .timescale import completion_table, no_path_error, span_feasible

__all__ = [
    "conventional_search",
    "check_conventional_options",
    "conventional_core",
    "random_walk",
    "random_core",
]


def conventional_search(
    graph: WeightedMotionGraph,
    music_z: Any,
    music_durations: Any,
    *,
    segment_beats: int = 8,
    rhythm_sigma: float = 0.3,
    rhythm_threshold: float = 0.5,
    max_candidates: int = 20000,
    lam: float = 1.0,
    scale_bound: Any = None,
    steps: Any = (1,),
    node_mask: Any = None,
) -> SearchResult:
    """Multi-stage segment-by-segment search (after Shiratori et al. 2006).

    The music is cut into segments of ``segment_beats`` grid intervals (8: two 4/4
    bars). For each in turn, graph paths continuing the previous segment are enumerated
    breadth-first, each interval taking the feasible step whose time-scale is nearest 1;
    stage 1 keeps those whose rhythm match ``exp(-log(d_motion/d_music)^2 / (2
    rhythm_sigma^2))`` exceeds ``rhythm_threshold`` at every beat (else all, counted in
    ``info["rhythm_fallbacks"]``), at most ``max_candidates`` per depth (the best by
    rhythm; ``info["capped_segments"]``); stage 2 takes the best intensity match per grid
    interval. Dead ends are avoided with
    :func:`beatsync.graph.timescale.completion_table`. ``music_durations`` [s] is needed
    (the rhythm); the other arguments as in :func:`dp_search`.
    """
    music_z, lam, _, md, bound, steps, mask = prepare_search(
        graph, music_z, lam, 0.0, music_durations, scale_bound, steps, node_mask
    )
    if md is None:
        raise ParameterError("conventional_search needs music_durations [s] (the rhythm)")
    opts = check_conventional_options(
        segment_beats,
        rhythm_sigma=rhythm_sigma,
        rhythm_threshold=rhythm_threshold,
        max_candidates=max_candidates,
    )
    return conventional_core(graph, music_z, md, lam, bound, steps, mask, **opts)


def check_conventional_options(
    segment_beats: Any = 8,
    *,
    rhythm_sigma: Any = 0.3,
    rhythm_threshold: Any = 0.5,
    max_candidates: Any = 20000,
    **unknown: Any,
) -> dict[str, Any]:
    """Validate the options of the multi-stage search (keys of :func:`conventional_core`)."""
    if unknown:
        raise ParameterError(
            f"unknown option(s) {sorted(unknown)} of the multi-stage search: use "
            "segment_beats, rhythm_sigma, rhythm_threshold, max_candidates"
        )
    thr = as_float(rhythm_threshold, name="rhythm_threshold")
    if not 0 <= thr < 1:
        raise ParameterError(f"rhythm_threshold={rhythm_threshold!r} must lie in [0, 1)")
    return {
        "seg": as_int(segment_beats, name="segment_beats", unit="beats", minimum=1),
        "sigma": check_positive(rhythm_sigma, name="rhythm_sigma", unit="log-duration"),
        "thr": thr,
        "cap": as_int(max_candidates, name="max_candidates", minimum=1),
    }


def conventional_core(
    graph, music_z, md, lam, bound, steps, mask, seg=8, sigma=0.3, thr=0.5, cap=20000, *,
    subdivision=1,
):  # fmt: skip
    """:func:`conventional_search` on validated inputs."""
    t0 = time.perf_counter()
    g_n = music_z.size
    t = grid_times(md, g_n)
    alive, handoff = completion_table(graph, t, steps, bound, mask)
    if not alive[0].any():
        raise no_path_error(graph, t, bound, steps, subdivision, mask)
    ctx = _Ctx(graph, music_z, t, steps, bound, handoff, sigma, lam)
    indptr, succ, sw = graph.successor_lists()
    path: list[int] = []
    bnd = [0]
    fallbacks = 0
    capped = 0
    n_candidates = []
    s0 = 0
    while s0 < g_n:
        s1 = min(g_n, s0 + seg)
        if path:
            last = path[-1]
            first = succ[indptr[last] : indptr[last + 1]]
            first_w = lam * sw[indptr[last] : indptr[last + 1]]
        else:
            first = np.flatnonzero(graph.is_interval)
            first_w = np.zeros(first.size)
        keep = alive[s0][first]
        first, first_w = first[keep], first_w[keep]
        best = None
        for floor in (thr, 0.0):
            found, ok_cap = _enumerate(ctx, first, first_w, s0, s1, floor, cap, indptr, succ, sw)
            if found is not None:
                best = found
                capped += int(not ok_cap)
                break
            fallbacks += 1
        nodes, ends, n_cand = best
        n_candidates.append(n_cand)
        path.extend(nodes)
        bnd.extend(ends)
        s0 = ends[-1]
    elapsed = time.perf_counter() - t0
    info = {
        "segment_beats": seg,
        "rhythm_fallbacks": fallbacks,
        "capped_segments": capped,
        "candidates_per_segment": n_candidates,
    }
    return make_result(
        graph, path, bnd, music_z, lam, 0.0, md, bound, "conventional", elapsed, info
    )


class _Ctx:
    """Per-search constants of the multi-stage search."""

    def __init__(self, graph, music_z, t, steps, bound, handoff, sigma, lam):
        self.dm = graph.interval_duration()
        self.zm = graph.z_intensity
        self.cs1 = np.concatenate([[0.0], np.cumsum(music_z)])
        self.cs2 = np.concatenate([[0.0], np.cumsum(music_z * music_z)])
        self.t = t
        self.g_n = music_z.size
        self.steps = steps
        self.bound = bound
        self.handoff = handoff
        self.sigma = sigma
        self.lam = lam

    def step(self, nodes: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The feasible step nearest time-scale 1 (0 if none) and its rhythm score."""
        best = np.zeros(nodes.size, dtype=np.int64)
        dev = np.full(nodes.size, np.inf)
        for s in self.steps:
            kk = np.minimum(k + s, self.g_n)
            scale = (self.t[kk] - self.t[k]) / self.dm[nodes]
            ok = (k + s <= self.g_n) & np.isfinite(scale) & self.handoff[kk, nodes]
            if self.bound is not None:
                ok &= (scale >= self.bound[0] * (1 - 1e-9)) & (scale <= self.bound[1] * (1 + 1e-9))
            dv = np.abs(np.log(np.where(ok, scale, 1.0)))
            better = ok & (dv < dev)
            best[better] = s
            dev[better] = dv[better]
        kk = np.minimum(k + np.maximum(best, 1), self.g_n)
        r = np.exp(
            -(np.log(self.dm[nodes] / (self.t[kk] - self.t[k])) ** 2)
            / (2.0 * self.sigma * self.sigma)
        )
        return best, np.where(best > 0, r, 0.0)

    def icost(self, nodes: np.ndarray, k: np.ndarray, s: np.ndarray) -> np.ndarray:
        z = self.zm[nodes]
        e = k + s
        return s * z * z - 2 * z * (self.cs1[e] - self.cs1[k]) + (self.cs2[e] - self.cs2[k])


def _enumerate(ctx, first, first_w, s0, s1, floor, cap, indptr, succ, sw):
    """Breadth-first enumeration of candidate sequences covering grid s0..s1 (or beyond).

    Returns ``((nodes, ends, n_candidates) or None, complete)``: the chosen sequence and
    whether the candidate cap never bit.
    """
    st, r = ctx.step(first, np.full(first.size, s0))
    keep = (st > 0) & (r > floor) if floor > 0 else st > 0
    nodes = first[keep]
    ends = s0 + st[keep]
    cost = ctx.icost(nodes, np.full(nodes.size, s0), st[keep]) + first_w[keep]
    rsum = r[keep]
    levels = [(nodes, ends, np.full(nodes.size, -1), cost)]
    complete = True
    while True:
        nodes, ends, _, cost = levels[-1]
        open_ = np.flatnonzero((ends < s1) & (ends < ctx.g_n))
        if open_.size == 0:
            break
        last = nodes[open_]
        counts = indptr[last + 1] - indptr[last]
        rep = np.repeat(open_, counts)
        offs = np.arange(rep.size) - np.repeat(np.cumsum(counts) - counts, counts)
        eidx = np.repeat(indptr[last], counts) + offs
        nxt = succ[eidx]
        kk = ends[rep]
        stn, rn = ctx.step(nxt, kk)
        ok = (stn > 0) & (rn > floor) if floor > 0 else stn > 0
        rep, nxt, eidx, kk, stn, rn = rep[ok], nxt[ok], eidx[ok], kk[ok], stn[ok], rn[ok]
        new_cost = cost[rep] + ctx.lam * sw[eidx] + ctx.icost(nxt, kk, stn)
        new_r = rsum[rep] + rn
        if nxt.size > cap:
            complete = False
            top = np.argpartition(-new_r, cap - 1)[:cap]
            rep, nxt, kk, stn, new_cost, new_r = (
                rep[top], nxt[top], kk[top], stn[top], new_cost[top], new_r[top]
            )  # fmt: skip
        if nxt.size == 0:
            break
        levels.append((nxt, kk + stn, rep, new_cost))
        rsum = new_r
    # stage 2: the finished candidate with the best intensity match per grid interval
    best = None
    n_cand = 0
    for depth, (_nodes, ends, _, cost) in enumerate(levels):
        fin = np.flatnonzero((ends >= s1) | (ends >= ctx.g_n))
        n_cand += fin.size
        if fin.size:
            per = cost[fin] / (ends[fin] - s0)
            i = int(np.argmin(per))
            if best is None or per[i] < best[0]:
                best = (float(per[i]), depth, int(fin[i]))
    if best is None:
        return None, complete
    _, depth, idx = best
    seq, seq_ends = [], []
    while depth >= 0:
        nodes, ends, parent, _ = levels[depth]
        seq.append(int(nodes[idx]))
        seq_ends.append(int(ends[idx]))
        idx = int(parent[idx])
        depth -= 1
    return (seq[::-1], seq_ends[::-1], n_cand), complete


def random_walk(
    graph: WeightedMotionGraph,
    n_intervals: int,
    *,
    seed: int = 0,
    music_durations: Any = None,
    scale_bound: Any = None,
    steps: Any = (1,),
    node_mask: Any = None,
) -> SearchResult:
    """A random path covering ``n_intervals`` grid intervals (control; costs are NaN).

    The start node, every next node and every step are drawn uniformly among those from
    which the song can still be completed within the bounds (arguments as in
    :func:`dp_search`).
    """
    k_n = int(n_intervals)
    if k_n < 1:
        raise ParameterError(f"n_intervals={n_intervals!r} must be >= 1")
    _, _, _, md, bound, steps, mask = prepare_search(
        graph, np.zeros(k_n), 0.0, 0.0, music_durations, scale_bound, steps, node_mask
    )
    return random_core(graph, k_n, seed, md, bound, steps, mask)


def random_core(graph, k_n, seed, md, bound, steps, mask, *, subdivision=1):
    """:func:`random_walk` on validated inputs."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    t = grid_times(md, k_n)
    alive, handoff = completion_table(graph, t, steps, bound, mask)
    if not alive[0].any():
        raise no_path_error(graph, t, bound, steps, subdivision, mask)
    indptr, succ, _ = graph.successor_lists()
    dm = graph.interval_duration()
    path: list[int] = []
    bnd = [0]
    k = 0
    cand = np.flatnonzero(alive[0])
    while True:
        v = int(rng.choice(cand))
        options = []
        for s in steps:
            if k + s <= k_n:
                ok, _ = span_feasible(dm[v : v + 1], t, k, s, bound, None)
                if ok[0] and handoff[k + s, v] and (mask is None or mask[v]):
                    options.append(s)
        s = int(rng.choice(options))
        path.append(v)
        k += s
        bnd.append(k)
        if k == k_n:
            break
        nxt = succ[indptr[v] : indptr[v + 1]]
        cand = nxt[alive[k][nxt]]
    elapsed = time.perf_counter() - t0
    res = make_result(
        graph, path, bnd, np.zeros(k_n), 0.0, 0.0, md, bound, "random", elapsed, {"seed": seed}
    )
    nan = float("nan")  # the control optimises nothing: no costs
    return replace(res, cost=nan, intensity_cost=nan, transition_cost=nan)
