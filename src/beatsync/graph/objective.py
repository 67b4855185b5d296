"""The objective of the motion-graph searches, their result and their input checks.

What the DP (:mod:`beatsync.graph.search`, where the objective ``E`` is defined) and
the baselines (:mod:`beatsync.graph.baselines`) share; inputs are validated once, at
each public entry. Music values are 1-D over the ``G`` grid intervals (durations [s]);
paths are node ids, boundaries grid indices.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validation import check_finite, check_positive
from .build import WeightedMotionGraph
from .timescale import check_scale_bound

__all__ = [
    "SearchResult",
    "check_music",
    "check_steps",
    "prepare_search",
    "grid_times",
    "path_cost",
    "path_cost_core",
    "make_result",
    "interval_scales",
]


@dataclass(frozen=True)
class SearchResult:
    """A path through the graph for ``G`` music grid intervals.

    ``path`` ``(P,)``: the interval node of each motion interval; ``boundaries``
    ``(P + 1,)``: the grid boundary where each starts (and the last ends, ``G``);
    ``transitions`` ``(P,)``: entered through a transition edge; ``scales`` ``(P,)``:
    time-scale factors (NaN without music durations); ``cost``, ``intensity_cost``,
    ``transition_cost``, ``tempo_cost``: ``E`` and its parts (NaN for the random walk).
    """

    path: np.ndarray
    boundaries: np.ndarray
    transitions: np.ndarray
    scales: np.ndarray
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


def check_music(values: Any, name: str) -> np.ndarray:
    arr = check_finite(values, name=name)
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be 1-D (one value per music beat interval)")
    if arr.size == 0:
        raise ParameterError(
            f"{name} is empty: the music needs at least two beats (one interval) to compose"
        )
    return arr


def check_steps(steps: Any) -> tuple[int, ...]:
    try:
        out = tuple(sorted({int(s) for s in steps}))
        ok = len(out) > 0 and all(float(s) == int(s) for s in steps)
    except (TypeError, ValueError):
        ok = False
    if not ok or out[0] < 1:
        raise ParameterError(
            f"steps={steps!r} must be whole numbers >= 1 of grid intervals per motion interval"
        )
    return out


def prepare_search(
    graph, music_z, lam, tempo_weight, music_durations, scale_bound, steps, node_mask
):
    """Validate the inputs of a search once (each public search calls it first)."""
    if not isinstance(graph, WeightedMotionGraph):
        raise ParameterError("graph must be a WeightedMotionGraph (see beatsync.graph.build_graph)")
    music_z = check_music(music_z, "music intensity")
    v = check_positive(lam, name="lam", unit="transition cost factor", allow_zero=True)
    tw = check_positive(tempo_weight, name="tempo_weight", unit="cost", allow_zero=True)
    md = None
    if music_durations is not None:
        md = check_music(music_durations, "music_durations")
        if md.size != music_z.size:
            raise ParameterError(
                f"music_durations has {md.size} values for {music_z.size} intervals"
            )
        if np.any(md <= 0):
            raise ParameterError("music_durations must be > 0 [s]")
    bound = check_scale_bound(scale_bound)
    if md is None and (tw or bound is not None):
        raise ParameterError(
            "tempo_weight > 0 and scale_bound need music_durations [s] (one per interval)"
        )
    steps = check_steps(steps)
    mask = None
    if node_mask is not None:
        mask = np.asarray(node_mask, dtype=bool)
        if mask.shape != (graph.n_nodes,):
            raise ParameterError(f"node_mask has shape {mask.shape}, not ({graph.n_nodes},)")
    return music_z, v, tw, md, bound, steps, mask


def grid_times(md: np.ndarray | None, g_n: int) -> np.ndarray:
    """Grid boundary times from the interval durations (unit steps if unknown)."""
    if md is None:
        return np.arange(g_n + 1, dtype=np.float64)
    return np.concatenate([[0.0], np.cumsum(md)])


def path_cost(
    graph: WeightedMotionGraph,
    path: Any,
    music_z: Any,
    *,
    lam: float = 1.0,
    tempo_weight: float = 0.0,
    music_durations: Any = None,
    boundaries: Any = None,
    scale_bound: Any = None,
) -> tuple[float, float, float, float, np.ndarray]:
    """``(E, intensity, transition, tempo, transitions)`` of a path; refuses infeasible ones."""
    music_z, lam, tw, md, bound, _, _ = prepare_search(
        graph, music_z, lam, tempo_weight, music_durations, scale_bound, (1,), None
    )
    path = np.asarray(path, dtype=np.int64)
    bnd = np.arange(path.size + 1) if boundaries is None else np.asarray(boundaries, dtype=np.int64)
    if bnd.shape != (path.size + 1,) or bnd[0] != 0 or bnd[-1] != music_z.size:
        raise ParameterError(
            f"path has {path.size} nodes and boundaries {bnd.size} for {music_z.size} music "
            "intervals (boundaries must run from 0 to the number of intervals)"
        )
    if np.any(np.diff(bnd) < 1):
        raise ParameterError("boundaries must be strictly increasing")
    if np.any(path < 0) or np.any(path >= graph.n_nodes) or not graph.is_interval[path].all():
        raise ParameterError("path contains nodes that do not start an interval")
    return path_cost_core(graph, path, bnd, music_z, lam, tw, md, bound)


def path_cost_core(graph, path, bnd, music_z, lam, tw, md, bound):
    """:func:`path_cost` on validated inputs."""
    cs1 = np.concatenate([[0.0], np.cumsum(music_z)])
    cs2 = np.concatenate([[0.0], np.cumsum(music_z * music_z)])
    zm = graph.z_intensity[path]
    n = np.diff(bnd)
    inten = float(np.sum(n * zm * zm - 2 * zm * (cs1[bnd[1:]] - cs1[bnd[:-1]])))
    inten += float(cs2[-1])
    tempo = 0.0
    if md is not None:
        scales = interval_scales(graph, path, bnd, md, music_z.size)
        if bound is not None:
            bad = (scales < bound[0] * (1 - 1e-9)) | (scales > bound[1] * (1 + 1e-9))
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ParameterError(
                    f"path interval {i} has time-scale {scales[i]:.3f}, outside the bound "
                    f"{bound[0]:g}-{bound[1]:g}"
                )
        if tw:
            tempo = tw * float(np.sum(np.log(scales) ** 2))
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


def make_result(graph, path, bnd, music_z, lam, tw, md, bound, method, elapsed, info):
    """A :class:`SearchResult` for a found path (costs recomputed from the path)."""
    path = np.asarray(path, dtype=np.int64)
    bnd = np.asarray(bnd, dtype=np.int64)
    total, inten, tcost, tempo, trans = path_cost_core(
        graph, path, bnd, music_z, lam, tw, md, bound
    )
    return SearchResult(
        path=path,
        boundaries=bnd,
        transitions=trans,
        scales=interval_scales(graph, path, bnd, md, music_z.size),
        cost=total,
        intensity_cost=inten,
        transition_cost=tcost,
        tempo_cost=tempo,
        method=method,
        search_time=elapsed,
        info=info,
    )


def interval_scales(graph, path, bnd, md, g_n):
    """Time-scale factor of every interval of a path (NaN without music durations)."""
    if md is None:
        return np.full(path.size, np.nan)
    t = grid_times(md, g_n)
    return (t[bnd[1:]] - t[bnd[:-1]]) / graph.interval_duration()[path]
