"""Tempo-matched composition: clip tempi, tempo sub-groups, beat multiplicity, scale bound.

Paper B builds its graphs per sub-group of motions that "share a range of tempos" and
selects one "according to the music genre and music tempo", so that a motion beat
interval is never squeezed into a music beat of a very different length; this module
makes those choices explicit and the searches enforce them.

- **Clip tempo**: :func:`beatsync.motion_beats.motion_tempo` of its beat frames.
- **Tempo sub-groups**: clips sorted by tempo, grouped greedily to span at most
  ``hi / lo`` of the scale bound; a group is *eligible* for a song when some
  multiplicity brings its central tempo within the bound (else the closest one is
  used, and the report says so).
- **Beat multiplicity** ``m``: music beats per motion interval, from ``rho = song BPM /
  library BPM``: the rungs of ``(1, 2, 3, 4)`` that bracket ``rho``, or the one within
  5 % of it, or ``(1/2, 1)`` (the grid is then half beats) when the library is more
  than ``1 / lo`` times faster than the music; each interval picks within that set.
- **Time-scale factor**: music / natural duration of an interval (``> 1``: slower);
  every interval must lie within ``scale_bound`` (default ``(0.8, 1.25)``).

Notebook: ``notebooks/paper_b_tab02_quality_proxies.ipynb``; paper B section 3.1.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..motion_beats import motion_tempo
from ..validation import check_interval

__all__ = [
    "DEFAULT_SCALE_BOUND",
    "LADDER",
    "TempoPlan",
    "check_scale_bound",
    "clip_tempi",
    "tempo_groups",
    "choose_multiplicity",
    "plan_tempo",
    "music_grid",
    "span_feasible",
    "completion_table",
    "no_path_error",
    "check_multiplicity",
]

#: Default bound on the time-scale factor of every interval (music / natural duration).
DEFAULT_SCALE_BOUND = (0.8, 1.25)
#: Beat multiplicities (music beats per motion interval) the plan may choose from.
LADDER = (0.5, 1.0, 2.0, 3.0, 4.0)


def check_scale_bound(bound: Any, *, name: str = "scale_bound") -> tuple[float, float] | None:
    """``None`` (unbounded) or ``(lo, hi)`` with ``0 < lo <= 1 <= hi``."""
    if bound is None:
        return None
    try:
        lo, hi = check_interval(bound, name=name, unit="time-scale factor")
    except ParameterError as exc:
        raise ParameterError(f"{exc}; e.g. (0.8, 1.25), or None for unbounded") from None
    if not lo <= 1.0 <= hi:
        raise ParameterError(
            f"{name}=({lo:g}, {hi:g}) must contain 1 (an interval played at its own speed); "
            "the factor is music duration / natural duration"
        )
    return lo, hi


def clip_tempi(graph: Any) -> np.ndarray:
    """Tempo of every clip of a graph from its beat frames [BPM] (NaN: fewer than 2 beats)."""
    t = graph.node_time()
    out = np.full(len(graph.clips), np.nan)
    for c in range(len(graph.clips)):
        tc = t[graph.node_clip == c]
        if tc.size >= 2:
            out[c] = motion_tempo(tc)
    return out


def tempo_groups(tempi: Any, *, width: float) -> np.ndarray:
    """Group index per clip: sorted by tempo, a group spans at most ``width`` (ratio)."""
    tempi = np.asarray(tempi, dtype=np.float64)
    group = np.full(tempi.size, -1, dtype=np.int64)
    order = [i for i in np.argsort(tempi) if np.isfinite(tempi[i])]
    g, start = -1, None
    for i in order:
        if start is None or tempi[i] > start * width * (1 + 1e-12):
            g += 1
            start = tempi[i]
        group[i] = g
    return group


def choose_multiplicity(
    library_bpm: float, song_bpm: float, bound: tuple[float, float] | None
) -> tuple[float, ...]:
    """Beat multiplicities for a tempo ratio (see module docstring)."""
    rho = float(song_bpm) / float(library_bpm)
    lo = bound[0] if bound is not None else DEFAULT_SCALE_BOUND[0]
    if rho < lo:
        return (0.5, 1.0)
    rungs = LADDER[1:]
    near = [m for m in rungs if abs(np.log(rho / m)) <= np.log(1.05)]
    if near:  # the tempi are (nearly) a whole ratio apart: that multiplicity only
        return (near[0],)
    below = [m for m in rungs if m <= rho]
    above = [m for m in rungs if m >= rho]
    pick = {below[-1] if below else rungs[0], above[0] if above else rungs[-1]}
    return tuple(sorted(pick))


@dataclass(frozen=True, eq=False)
class TempoPlan:
    """Which clips a song may use, with which multiplicities, under which bound.

    ``subdivision`` is 1 (grid = music beats) or 2 (half beats), ``steps`` the grid
    intervals per motion interval (``multiplicity * subdivision``), ``clip_table`` one
    dict per clip (``clip``, ``tempo_bpm``, ``group``, ``eligible``, ``reason``) and
    ``node_mask`` the nodes of eligible clips.
    """

    song_bpm: float
    library_bpm: float
    bound: tuple[float, float] | None
    multiplicity: tuple[float, ...]
    subdivision: int
    steps: tuple[int, ...]
    clip_table: list = field(default_factory=list)
    node_mask: np.ndarray | None = None

    def report(self) -> dict:
        return {
            "song_bpm": self.song_bpm,
            "library_bpm": self.library_bpm,
            "scale_bound": list(self.bound) if self.bound is not None else None,
            "multiplicity": list(self.multiplicity),
            "subdivision": self.subdivision,
            "clips": self.clip_table,
        }


def plan_tempo(
    graph: Any,
    music_beats: np.ndarray,
    *,
    scale_bound: tuple[float, float] | None = DEFAULT_SCALE_BOUND,
    multiplicity: Any = "auto",
    tempo_select: bool = True,
) -> TempoPlan:
    """Eligible clips and multiplicities for a song (``tempo_select=False``: every clip);
    unbounded, ``"auto"`` is one beat per motion beat (paper B as written)."""
    multiplicity = check_multiplicity(multiplicity)
    if scale_bound is None and multiplicity == "auto":
        multiplicity = (1.0,)
    song_bpm = float(60.0 / np.median(np.diff(music_beats)))
    tempi = clip_tempi(graph)
    width = scale_bound[1] / scale_bound[0] if scale_bound is not None else np.inf
    groups = tempo_groups(tempi, width=width)
    n_groups = int(groups.max()) + 1 if groups.size and groups.max() >= 0 else 0
    eligible_groups: set[int] = set()
    why: dict[int, str] = {}
    dev = {}
    rungs = LADDER if multiplicity == "auto" else multiplicity
    for g in range(n_groups):
        tg = float(np.exp(np.mean(np.log(tempi[groups == g]))))
        scales = np.array([m * tg / song_bpm for m in rungs])
        k = int(np.argmin(np.abs(np.log(scales))))
        dev[g] = abs(float(np.log(scales[k])))
        inside = scale_bound is None or scale_bound[0] <= scales[k] <= scale_bound[1]
        members = tempi[groups == g]
        why[g] = (
            f"tempo group {g} ({members.min():.0f}-{members.max():.0f} BPM, centre "
            f"{tg:.0f}): {rungs[k]:g} music beat(s) per motion beat gives time-scale "
            f"{scales[k]:.2f}"
        )
        if inside or not tempo_select:
            eligible_groups.add(g)
    closest_only = False
    if not eligible_groups and n_groups:
        eligible_groups.add(min(dev, key=dev.get))
        closest_only = True
    rows = []
    for c, clip in enumerate(graph.clips):
        g = int(groups[c])
        ok = g in eligible_groups
        if g < 0:
            reason = "fewer than two beat frames: no tempo, no interval"
        else:
            own = f"clip at {tempi[c]:.0f} BPM, "
            if not tempo_select:
                reason = own + "tempo selection off (whole library); " + why[g]
            elif ok and closest_only:
                reason = own + why[g] + f", outside the bound: closest group to {song_bpm:.0f} BPM"
            elif ok:
                reason = own + why[g] + " (within the bound)"
            else:
                reason = own + why[g] + " (outside the bound)"
        rows.append(
            {
                "clip": clip.name,
                "tempo_bpm": float(tempi[c]),
                "group": g,
                "eligible": bool(ok),
                "reason": reason,
            }
        )
    eligible = np.array([r["eligible"] for r in rows], dtype=bool)
    lib_bpm = float(np.median(tempi[eligible])) if eligible.any() else float("nan")
    if multiplicity == "auto":
        mult = choose_multiplicity(lib_bpm, song_bpm, scale_bound) if eligible.any() else (1.0,)
    else:
        mult = multiplicity
    sub = 2 if 0.5 in mult else 1
    steps = tuple(int(round(m * sub)) for m in mult)
    return TempoPlan(
        song_bpm=song_bpm,
        library_bpm=lib_bpm,
        bound=scale_bound,
        multiplicity=mult,
        subdivision=sub,
        steps=steps,
        clip_table=rows,
        node_mask=eligible[graph.node_clip],
    )


def check_multiplicity(multiplicity: Any) -> Any:
    """``"auto"`` or a non-empty set of values from :data:`LADDER`."""
    if isinstance(multiplicity, str) and multiplicity == "auto":
        return "auto"
    try:
        vals = [] if isinstance(multiplicity, str) else [float(m) for m in multiplicity]
    except (TypeError, ValueError):
        vals = []
    if not vals or any(v not in LADDER for v in vals):
        raise ParameterError(
            f"multiplicity={multiplicity!r} must be 'auto' or music beats per motion "
            f"interval from {LADDER}"
        )
    return tuple(sorted(set(vals)))


def music_grid(beats: np.ndarray, level: np.ndarray, subdivision: int):
    """Grid times and the level per grid interval (half beats repeat their beat's level)."""
    if subdivision == 1:
        return beats, level
    grid = np.insert(beats, np.arange(1, beats.size), (beats[:-1] + beats[1:]) / 2)
    return grid, np.repeat(level, 2)


def span_feasible(
    durations: np.ndarray,
    grid_times: np.ndarray,
    start: int,
    step: int,
    bound: tuple[float, float] | None,
    node_mask: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Feasibility and scale over nodes of every interval over grid ``[start, start + step]``."""
    span = grid_times[start + step] - grid_times[start]
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = span / durations
    ok = np.isfinite(scale)
    if bound is not None:
        ok &= (scale >= bound[0] * (1 - 1e-9)) & (scale <= bound[1] * (1 + 1e-9))
    if node_mask is not None:
        ok &= node_mask
    return ok, scale


def completion_table(
    graph: Any,
    grid_times: np.ndarray,
    steps: tuple[int, ...],
    bound: tuple[float, float] | None,
    node_mask: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Which nodes can start at each grid boundary and still reach the last one.

    ``alive[k, v]``: interval ``v`` started at boundary ``k`` can complete the song;
    ``handoff[k, v]``: after an interval ending on ``v``'s end at boundary ``k`` it can
    (``k = G``, or a successor of ``v`` alive at ``k``). Both ``(G + 1, N)`` bool.
    """
    src, dst, _ = graph.successors()
    n = graph.n_nodes
    g_n = grid_times.size - 1
    dur = graph.interval_duration()
    alive = np.zeros((g_n + 1, n), dtype=bool)
    handoff = np.zeros((g_n + 1, n), dtype=bool)
    handoff[g_n] = True
    for k in range(g_n - 1, -1, -1):
        ok_any = np.zeros(n, dtype=bool)
        for s in steps:
            if k + s > g_n:
                continue
            ok, _ = span_feasible(dur, grid_times, k, s, bound, node_mask)
            ok_any |= ok & handoff[k + s]
        alive[k] = ok_any
        handoff[k] = np.bincount(src, weights=alive[k][dst], minlength=n) > 0
    return alive, handoff


def no_path_error(
    graph: Any,
    grid_times: np.ndarray,
    bound: tuple[float, float] | None,
    steps: tuple[int, ...],
    subdivision: int,
    node_mask: np.ndarray | None,
) -> ParameterError:
    """The error when no path satisfies the bounds: it names both tempi and the bound."""
    beat_s = float(np.median(np.diff(grid_times))) * subdivision
    song_bpm = 60.0 / beat_s
    tempi = clip_tempi(graph)
    mask = np.ones(graph.n_nodes) if node_mask is None else node_mask
    used = np.bincount(graph.node_clip, weights=mask, minlength=len(tempi)) > 0
    lib = tempi[used & np.isfinite(tempi)]
    lib_txt = (
        f"{np.median(lib):.0f} BPM (clips {np.min(lib):.0f}-{np.max(lib):.0f})"
        if lib.size
        else "unknown"
    )
    mult = ", ".join(f"{s / subdivision:g}" for s in steps)
    if bound is None:
        return ParameterError(
            f"no path of {grid_times.size - 1} music intervals exists in the graph (dead "
            "ends): add clips or raise TH to create more transitions"
        )
    return ParameterError(
        f"no dance satisfies the time-scale bound {bound[0]:g}-{bound[1]:g}: the library "
        f"dances at {lib_txt}, the song at {song_bpm:.0f} BPM, with {mult} music beat(s) "
        f"per motion beat; relax the bound (scale_bound / --scale-bound, e.g. "
        f"{bound[0] * 0.8:.2f} {bound[1] * 1.25:.2f}), allow other multiplicities, or use "
        "a library danced nearer the song's tempo"
    )
