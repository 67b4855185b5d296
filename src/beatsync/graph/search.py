"""Path searches on a weighted motion graph: the DP of paper B and its baselines.

Objective (paper B, eqs. 3-6, as we read them)
----------------------------------------------
A dance for ``K`` music beat intervals is a path ``u_0 .. u_{K-1}`` of interval nodes
(:meth:`WeightedMotionGraph.successors`): after playing interval ``u_k`` the dancer
stands on the beat frame ``next_node[u_k]`` and either continues with that frame's
own interval (cost 0) or takes a transition edge to a similar beat frame (cost
``lam * w2``, eq. 2). Its cost is

    E = sum_k (z_motion(u_k) - z_music(k))^2 + lam * sum_{transitions} w2
        + tempo_weight * sum_k log(d_motion(u_k) / d_music(k))^2,

with both intensities z-scored (motion over the library, music over the song). The
tempo term is 0 by default (paper B matches intensity only: every interval is
time-warped onto its music interval); it penalises strong warps when set.

- :func:`dp_search` (proposed): dynamic programming over the K intervals with every
  interval node as a start node; ``D_k(v) = c_k(v) + min_u (D_{k-1}(u) + lam w(u, v))``;
  time ``O(K (N + E))``, linear in K; exact optimum of ``E``.
- :func:`conventional_search` (baseline in the spirit of Shiratori et al. 2006): the
  music is cut into segments of ``segment_beats`` beats; for each segment in turn,
  candidate motion sequences (graph paths continuing the previous segment) are
  enumerated breadth-first, keeping only those whose rhythm matches the music above
  ``rhythm_threshold`` at every beat (stage 1); the candidate with the best intensity
  match (the same ``E`` restricted to the segment) is chosen (stage 2). The
  enumeration is exhaustive up to ``max_candidates`` partial paths per depth (then
  the best by rhythm are kept), which makes it a bounded greedy search: it is not
  given the DP.
- :func:`random_walk` (control): uniform choice among the successors that can still
  complete the K intervals.

Data contract: music intensities are 1-D arrays over the K beat intervals (already
z-scored for the objective); durations in seconds. Paths are arrays of node ids.

Notebook: ``notebooks/paper_b_tab01_search_speed.ipynb`` (times),
``notebooks/paper_b_tab02_quality_proxies.ipynb`` (quality); paper B sections 3.3-3.4.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..units import check_finite
from .build import WeightedMotionGraph

__all__ = [
    "METHODS",
    "search",
    "SearchResult",
    "dp_search",
    "conventional_search",
    "random_walk",
    "path_cost",
    "node_costs",
]


#: Search methods of :func:`search`.
METHODS = ("dp", "conventional", "random")


@dataclass(frozen=True)
class SearchResult:
    """A path through the graph for K music intervals.

    Attributes
    ----------
    path : np.ndarray [shape=(K,)] int
        Interval node played during each music beat interval.
    transitions : np.ndarray [shape=(K,)] bool
        True where interval ``k`` is entered through a transition edge (``k >= 1``).
    cost, intensity_cost, transition_cost, tempo_cost : float
        The objective ``E`` and its parts.
    method : str
    search_time : float [s]
    info : dict
    """

    path: np.ndarray
    transitions: np.ndarray
    cost: float
    intensity_cost: float
    transition_cost: float
    tempo_cost: float
    method: str
    search_time: float
    info: dict = field(default_factory=dict)

    @property
    def n_transitions(self) -> int:
        return int(self.transitions.sum())


def _check_music(values: Any, name: str) -> np.ndarray:
    arr = check_finite(values, name=name)
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be 1-D (one value per music beat interval)")
    if arr.size == 0:
        raise ParameterError(
            f"{name} is empty: the music needs at least two beats (one interval) to compose"
        )
    return arr


def _check_lam(lam: Any) -> float:
    v = float(lam)
    if not np.isfinite(v) or v < 0:
        raise ParameterError(f"lam={lam!r} (transition cost factor) must be finite and >= 0")
    return v


def node_costs(
    graph: WeightedMotionGraph,
    music_z: np.ndarray,
    *,
    tempo_weight: float = 0.0,
    music_durations: np.ndarray | None = None,
) -> np.ndarray:
    """Local costs ``c_k(v)``, shape ``(K, N)`` (inf where ``v`` starts no interval)."""
    zm = np.where(graph.is_interval, graph.z_intensity, np.nan)
    c = (zm[None, :] - music_z[:, None]) ** 2
    if tempo_weight:
        if music_durations is None:
            raise ParameterError("tempo_weight > 0 needs music_durations [s]")
        dm = graph.interval_duration()
        c = c + tempo_weight * np.log(dm[None, :] / music_durations[:, None]) ** 2
    return np.where(np.isnan(c), np.inf, c)


def _prepare(graph, music_z, lam, tempo_weight, music_durations):
    if not isinstance(graph, WeightedMotionGraph):
        raise ParameterError("graph must be a WeightedMotionGraph (see beatsync.graph.build_graph)")
    music_z = _check_music(music_z, "music intensity")
    lam = _check_lam(lam)
    tw = float(tempo_weight)
    if not np.isfinite(tw) or tw < 0:
        raise ParameterError(f"tempo_weight={tempo_weight!r} must be finite and >= 0")
    md = None
    if music_durations is not None:
        md = _check_music(music_durations, "music_durations")
        if md.size != music_z.size:
            raise ParameterError(
                f"music_durations has {md.size} values for {music_z.size} intervals"
            )
        if np.any(md <= 0):
            raise ParameterError("music_durations must be > 0 [s]")
    return music_z, lam, tw, md


def path_cost(
    graph: WeightedMotionGraph,
    path: Any,
    music_z: Any,
    *,
    lam: float = 1.0,
    tempo_weight: float = 0.0,
    music_durations: Any = None,
) -> tuple[float, float, float, float, np.ndarray]:
    """Objective ``E`` of a given path (and its parts); refuses infeasible paths.

    Returns
    -------
    (total, intensity, transition, tempo, transitions)
        ``transitions`` is the boolean array of :class:`SearchResult`.
    """
    music_z, lam, tw, md = _prepare(graph, music_z, lam, tempo_weight, music_durations)
    path = np.asarray(path, dtype=np.int64)
    if path.shape != music_z.shape:
        raise ParameterError(f"path has {path.size} nodes for {music_z.size} music intervals")
    if np.any(path < 0) or np.any(path >= graph.n_nodes) or not graph.is_interval[path].all():
        raise ParameterError("path contains nodes that do not start an interval")
    zm = graph.z_intensity[path]
    inten = float(np.sum((zm - music_z) ** 2))
    tempo = 0.0
    if tw:
        if md is None:
            raise ParameterError("tempo_weight > 0 needs music_durations [s]")
        dm = graph.interval_duration()[path]
        tempo = tw * float(np.sum(np.log(dm / md) ** 2))
    indptr, succ, sw = graph.successor_lists()
    trans = np.zeros(path.size, dtype=bool)
    tcost = 0.0
    for k in range(1, path.size):
        a, b = int(path[k - 1]), int(path[k])
        out = succ[indptr[a] : indptr[a + 1]]
        hit = np.flatnonzero(out == b)
        if hit.size == 0:
            raise ParameterError(f"path step {k}: no edge from node {a} to node {b}")
        if graph.next_node[a] != b:
            trans[k] = True
            tcost += lam * float(sw[indptr[a] + hit[0]])
    return inten + tcost + tempo, inten, tcost, tempo, trans


def _result(graph, path, music_z, lam, tw, md, method, elapsed, info) -> SearchResult:
    total, inten, tcost, tempo, trans = path_cost(
        graph, path, music_z, lam=lam, tempo_weight=tw, music_durations=md
    )
    return SearchResult(
        path=np.asarray(path, dtype=np.int64),
        transitions=trans,
        cost=total,
        intensity_cost=inten,
        transition_cost=tcost,
        tempo_cost=tempo,
        method=method,
        search_time=elapsed,
        info=info,
    )


def dp_search(
    graph: WeightedMotionGraph,
    music_z: Any,
    *,
    lam: float = 1.0,
    start: str = "any",
    tempo_weight: float = 0.0,
    music_durations: Any = None,
) -> SearchResult:
    """Globally optimal path by dynamic programming (paper B, eqs. 3-6).

    Parameters
    ----------
    graph : WeightedMotionGraph
    music_z : np.ndarray [shape=(K,)]
        Z-scored music intensity per beat interval.
    lam : float >= 0
        Factor on the transition weights.
    start : {"any", "clip_start"}
        Start nodes: every interval node (default: "all first beat frames"), or only
        the first beat frame of each clip.
    tempo_weight : float >= 0
        Weight of the tempo term (0 as in the paper).
    music_durations : np.ndarray [shape=(K,)] [s], optional
        Needed when ``tempo_weight > 0``.

    Returns
    -------
    SearchResult
        ``search_time`` counts the DP only (the graph is built offline).

    Raises
    ------
    ParameterError
        Empty music, or a library that cannot cover K intervals.
    """
    music_z, lam, tw, md = _prepare(graph, music_z, lam, tempo_weight, music_durations)
    if start not in ("any", "clip_start"):
        raise ParameterError(f"start={start!r} must be 'any' or 'clip_start'")
    t0 = time.perf_counter()
    pred, weight, _ = graph.predecessor_table()
    lw = weight * lam if lam > 0 else np.where(np.isinf(weight), np.inf, 0.0)
    costs = node_costs(graph, music_z, tempo_weight=tw, music_durations=md)
    k_n = music_z.size
    d = costs[0].copy()
    if start == "clip_start":
        first = np.ones(graph.n_nodes, dtype=bool)
        first[1:] = graph.node_clip[1:] != graph.node_clip[:-1]
        d[~first] = np.inf
    back = np.empty((k_n, graph.n_nodes), dtype=np.int32)
    rows = np.arange(graph.n_nodes)
    for k in range(1, k_n):
        cand = d[pred] + lw
        col = np.argmin(cand, axis=1)
        back[k] = col
        d = cand[rows, col] + costs[k]
    end = int(np.argmin(d))
    if not np.isfinite(d[end]):
        raise ParameterError(
            f"no path of {k_n} beat intervals exists in the graph (dead ends): add clips or "
            "raise TH to create more transitions"
        )
    path = np.empty(k_n, dtype=np.int64)
    path[-1] = end
    for k in range(k_n - 1, 0, -1):
        path[k - 1] = pred[path[k], back[k, path[k]]]
    elapsed = time.perf_counter() - t0
    return _result(graph, path, music_z, lam, tw, md, "dp", elapsed, {"start": start})


def _rhythm_score(dm: np.ndarray, ds: np.ndarray, sigma: float) -> np.ndarray:
    return np.exp(-(np.log(dm / ds) ** 2) / (2.0 * sigma * sigma))


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
) -> SearchResult:
    """Multi-stage segment-by-segment search (after Shiratori et al. 2006).

    Parameters
    ----------
    graph : WeightedMotionGraph
    music_z : np.ndarray [shape=(K,)]
        Z-scored music intensity per beat interval.
    music_durations : np.ndarray [shape=(K,)] [s]
        Duration of each music beat interval (the rhythm to match).
    segment_beats : int >= 1
        Music segment length [beat intervals] (8 = two 4/4 bars).
    rhythm_sigma : float > 0
        Width of the rhythm match ``exp(-log(d_motion/d_music)^2 / (2 sigma^2))``.
    rhythm_threshold : float in [0, 1)
        Stage 1: a candidate's rhythm match must exceed it at every beat. A segment
        without any such candidate falls back to all candidates (counted in
        ``info["rhythm_fallbacks"]``).
    max_candidates : int >= 1
        Cap on partial candidate sequences per depth (the best by rhythm are kept);
        ``info["capped_segments"]`` counts the segments where it bit.
    lam : float >= 0

    Returns
    -------
    SearchResult
    """
    music_z, lam, _, md = _prepare(graph, music_z, lam, 0.0, music_durations)
    if md is None:
        raise ParameterError("conventional_search needs music_durations [s] (the rhythm)")
    seg = int(segment_beats)
    if seg < 1:
        raise ParameterError(f"segment_beats={segment_beats!r} must be >= 1")
    if not rhythm_sigma > 0:
        raise ParameterError(f"rhythm_sigma={rhythm_sigma!r} must be > 0")
    if not 0 <= rhythm_threshold < 1:
        raise ParameterError(f"rhythm_threshold={rhythm_threshold!r} must lie in [0, 1)")
    cap = int(max_candidates)
    if cap < 1:
        raise ParameterError(f"max_candidates={max_candidates!r} must be >= 1")
    t0 = time.perf_counter()
    indptr, succ, sw = graph.successor_lists()
    dm = graph.interval_duration()
    zm = graph.z_intensity
    interval_nodes = np.flatnonzero(graph.is_interval)
    k_n = music_z.size
    path: list[int] = []
    fallbacks = 0
    capped = 0
    hard_cuts = 0
    n_candidates = []
    for s0 in range(0, k_n, seg):
        s1 = min(k_n, s0 + seg)
        if path:
            last = path[-1]
            first = succ[indptr[last] : indptr[last + 1]]
            first_w = lam * sw[indptr[last] : indptr[last + 1]]
            if first.size == 0:
                hard_cuts += 1
                first, first_w = interval_nodes, np.zeros(interval_nodes.size)
        else:
            first, first_w = interval_nodes, np.zeros(interval_nodes.size)
        best = None
        for floor in (rhythm_threshold, 0.0):
            paths, ok_cap = _enumerate(
                first, first_w, s0, s1, indptr, succ, sw, dm, md, lam, rhythm_sigma, floor, cap
            )
            if paths[0].shape[0] > 0:
                best = paths
                capped += int(not ok_cap)
                break
            fallbacks += 1
        if best is None:
            raise ParameterError(
                f"no motion sequence covers music beats {s0}..{s1}: the graph has dead ends; "
                "add clips or raise TH"
            )
        seqs, tcost, _ = best
        n_candidates.append(int(seqs.shape[0]))
        # stage 2: intensity matching over the candidates
        e = np.sum((zm[seqs] - music_z[None, s0:s1]) ** 2, axis=1) + tcost
        path.extend(int(x) for x in seqs[int(np.argmin(e))])
    elapsed = time.perf_counter() - t0
    info = {
        "segment_beats": seg,
        "rhythm_fallbacks": fallbacks,
        "capped_segments": capped,
        "hard_cuts": hard_cuts,
        "candidates_per_segment": n_candidates,
    }
    if hard_cuts:
        # a hard cut is not an edge of the graph: score the path piecewise
        return SearchResult(
            path=np.asarray(path),
            transitions=np.zeros(len(path), dtype=bool),
            cost=float("nan"),
            intensity_cost=float(np.sum((zm[path] - music_z) ** 2)),
            transition_cost=float("nan"),
            tempo_cost=0.0,
            method="conventional",
            search_time=elapsed,
            info=info,
        )
    return _result(graph, np.asarray(path), music_z, lam, 0.0, md, "conventional", elapsed, info)


def _enumerate(first, first_w, s0, s1, indptr, succ, sw, dm, md, lam, sigma, floor, cap):
    """Breadth-first enumeration of candidate sequences for music intervals s0..s1-1."""
    r = _rhythm_score(dm[first], md[s0], sigma)
    keep = r > floor if floor > 0 else np.ones(first.size, dtype=bool)
    seqs = first[keep][:, None]
    tcost = first_w[keep]
    rsum = r[keep]
    complete = True
    for k in range(s0 + 1, s1):
        if seqs.shape[0] == 0:
            break
        last = seqs[:, -1]
        counts = indptr[last + 1] - indptr[last]
        rep = np.repeat(np.arange(seqs.shape[0]), counts)
        offs = np.arange(rep.size) - np.repeat(np.cumsum(counts) - counts, counts)
        eidx = indptr[last][rep] + offs
        nxt = succ[eidx]
        rn = _rhythm_score(dm[nxt], md[k], sigma)
        ok = rn > floor if floor > 0 else np.ones(nxt.size, dtype=bool)
        rep, nxt, eidx, rn = rep[ok], nxt[ok], eidx[ok], rn[ok]
        seqs = np.concatenate([seqs[rep], nxt[:, None]], axis=1)
        tcost = tcost[rep] + lam * sw[eidx]
        rsum = rsum[rep] + rn
        if seqs.shape[0] > cap:
            complete = False
            top = np.argpartition(-rsum, cap - 1)[:cap]
            seqs, tcost, rsum = seqs[top], tcost[top], rsum[top]
    return (seqs, tcost, rsum), complete


def random_walk(graph: WeightedMotionGraph, n_intervals: int, *, seed: int = 0) -> SearchResult:
    """A random path of ``n_intervals`` intervals (control).

    The start node and every next node are drawn uniformly among the successors from
    which the remaining intervals can still be completed (no dead ends).

    Returns
    -------
    SearchResult
        Costs are filled with NaN (no music is used); ``transitions`` is set.
    """
    if not isinstance(graph, WeightedMotionGraph):
        raise ParameterError("graph must be a WeightedMotionGraph")
    k_n = int(n_intervals)
    if k_n < 1:
        raise ParameterError(f"n_intervals={n_intervals!r} must be >= 1")
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    src, dst, _ = graph.successors()
    indptr, succ, _ = graph.successor_lists()
    # alive[r]: can play r more intervals starting here
    alive = [graph.is_interval.copy()]
    for _ in range(1, k_n):
        prev = alive[-1]
        nxt = graph.is_interval & (np.bincount(src, weights=prev[dst], minlength=graph.n_nodes) > 0)
        alive.append(nxt)
        if np.array_equal(nxt, prev):
            break

    def ok(r: int) -> np.ndarray:
        return alive[min(r, len(alive)) - 1]

    starts = np.flatnonzero(ok(k_n))
    if starts.size == 0:
        raise ParameterError(f"no path of {k_n} intervals exists in the graph")
    path = [int(rng.choice(starts))]
    for k in range(1, k_n):
        cand = succ[indptr[path[-1]] : indptr[path[-1] + 1]]
        cand = cand[ok(k_n - k)[cand]]
        path.append(int(rng.choice(cand)))
    path_a = np.asarray(path, dtype=np.int64)
    trans = np.zeros(k_n, dtype=bool)
    trans[1:] = graph.next_node[path_a[:-1]] != path_a[1:]
    return SearchResult(
        path=path_a,
        transitions=trans,
        cost=float("nan"),
        intensity_cost=float("nan"),
        transition_cost=float("nan"),
        tempo_cost=0.0,
        method="random",
        search_time=time.perf_counter() - t0,
        info={"seed": seed},
    )


def search(
    graph: WeightedMotionGraph,
    music_z: Any,
    music_durations: Any,
    *,
    method: str = "dp",
    lam: float = 1.0,
    seed: int = 0,
    **kwargs: Any,
) -> SearchResult:
    """Search a path with ``method``.

    Dispatches to :func:`dp_search`, :func:`conventional_search` or :func:`random_walk`.
    """
    if method == "dp":
        return dp_search(graph, music_z, lam=lam, music_durations=music_durations, **kwargs)
    if method == "conventional":
        return conventional_search(graph, music_z, music_durations, lam=lam, **kwargs)
    if method == "random":
        return random_walk(graph, len(music_z), seed=seed)
    raise ParameterError(f"method={method!r} is not one of {METHODS}")
