"""Paper B's study: libraries, timing and quality tables, figures (the notebooks' calls).

The libraries (:data:`LIBRARIES`) stand in for paper B's captures, not available.
Table 1 (:func:`speed_table`) times the proposed DP and the conventional search;
Table 2 (:func:`quality_table`) scores compositions with the proxies of
:mod:`beatsync.evaluate.composition` and :mod:`beatsync.graph.plausibility`.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb``,
``notebooks/paper_b_tab02_quality_proxies.ipynb``.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import ParameterError, silenced
from ..graph.build import WeightedMotionGraph, build_graph
from ..graph.compose import compose
from ..graph.search import conventional_search, dp_search
from ..graph.timescale import DEFAULT_SCALE_BOUND
from .artifacts import write_artifacts

__all__ = [
    "LIBRARIES",
    "PAPER_B_TABLE1",
    "load_library",
    "song",
    "speed_table",
    "ratio_table",
    "threshold_table",
    "QUALITY_METHODS",
    "library_graphs",
    "quality_table",
    "quality_means",
    "plausibility_targets",
    "eligibility_table",
    "example_composition",
    "composition_proxies",
    "library_reference",
    "summary_graphs",
    "plot_speed",
    "plot_intensity",
    "write_artifacts",
]

#: Library name -> (what it stands in for, description).
LIBRARIES = {
    "salsa": (
        "paper B's Break dance library",
        "CMU salsa 60_01, 61_01, 60_04, 61_04 (60 fps, 4 clips, 132 s)",
    ),
    "synthetic": (
        "paper B's Indian dance library",
        "4 synthetic in-place dances, 90-130 BPM, 3-move vocabulary (beatsync.synth.library)",
    ),
    "walk": (
        "paper B's Indian dance library",
        "CMU walking 007_02, 007_12 (007_01 has another skeleton and is left out)",
    ),
}

#: What paper B reports for its Table 1 (absolute times are not available to us).
PAPER_B_TABLE1 = {
    "ratio_proposed": 2.05,
    "ratio_conventional": 2.61,
    "speedup_range": (27.0, 543.0),
    "absolute_times": "not available",
}


def load_library(
    name: str, *, duration: float = 30.0, n_clips: int = 4, seed: int = 0
) -> tuple[list[Any], list[np.ndarray] | None]:
    """Clips of a study library (:data:`LIBRARIES`), and exact beats for the synthetic
    one (``n_clips`` of ``duration`` [s] each), else None."""
    from .. import datasets

    if name == "salsa":
        return [datasets.load_salsa(t) for t in datasets.SALSA_CLIPS], None
    if name == "walk":
        return [datasets.load_walk(c) for c in ("007_02", "007_12")], None
    if name == "synthetic":
        from ..synth.library import synthetic_library

        clips, beats = synthetic_library(n_clips, duration=duration, seed=seed)
        return clips, beats
    raise ParameterError(f"unknown library {name!r}; choose from {sorted(LIBRARIES)}")


def library_graphs(
    names: Sequence[str],
    *,
    th: float = 3.0,
    th_max: float | None = None,
    duration: float = 30.0,
    seed: int = 0,
) -> tuple[dict[str, WeightedMotionGraph], dict[str, WeightedMotionGraph]]:
    """The graph of each study library at ``th``, and the graph at ``th_max`` (the
    largest TH the notebook needs, default ``th``) it is filtered from: each library's
    distances are computed once."""
    top = max(th, th_max) if th_max is not None else th
    graphs, full = {}, {}
    for name in names:
        clips, beats = load_library(name, duration=duration, seed=seed)
        full[name] = build_graph(clips, beats=beats, th=top, require_transitions=False)
        graphs[name] = full[name].with_threshold(th) if top > th else full[name]
    return graphs, full


def song(duration: float, *, bpm: float = 100.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Beats [s] and level per beat interval [dB] of a synthetic drum song."""
    from ..music import beat_rms_db
    from ..synth.audio import drum_song

    s = drum_song(duration, bpm=bpm, seed=seed, sr=22050)
    return s.beats, beat_rms_db(s.y, s.sr, s.beats)


def _z(level: np.ndarray) -> np.ndarray:
    from ..motion_beats import zscore

    with silenced():
        return zscore(level)


def _song_grid(graph: WeightedMotionGraph, beats: np.ndarray, level: np.ndarray, bound: Any):
    """What compose searches for a song: the tempo plan, z per grid interval, the grid
    intervals' durations [s] and the search's options."""
    from ..graph.timescale import music_grid, plan_tempo

    plan = plan_tempo(graph, beats, scale_bound=bound)
    grid, glevel = music_grid(beats, level, plan.subdivision)
    kw = {"scale_bound": plan.bound, "steps": plan.steps, "node_mask": plan.node_mask}
    return plan, _z(glevel), np.diff(grid), kw


def speed_table(
    graphs: dict[str, WeightedMotionGraph],
    durations: Sequence[float] = (30.0, 60.0),
    *,
    bpm: float = 100.0,
    repeats: int = 3,
    seed: int = 0,
    segment_beats: int = 8,
    max_candidates: int = 20000,
    dp_inner: int = 10,
    scale_bound: Any = DEFAULT_SCALE_BOUND,
    conventional_repeats: int = 2,
) -> Any:
    """Search times [s] of the DP (best of ``repeats``, each the mean of ``dp_inner``
    runs: one takes about a millisecond) and the conventional search (best of
    ``conventional_repeats``: it takes seconds); one row per library and music length.

    Both search as :func:`beatsync.graph.compose.compose` does: on the song's grid, with
    the tempo plan and ``scale_bound`` (``None``: paper B as written). The times are the
    searches' own clocks: the graph and its search tables (offline) are excluded, as in
    paper B.
    """
    import pandas as pd

    rows = []
    for name, g in graphs.items():
        g.predecessor_table()  # search tables belong to the offline graph
        g.successor_lists()
        for dur in durations:
            beats, level = song(float(dur), bpm=bpm, seed=seed)
            plan, z, md, kw = _song_grid(g, beats, level, scale_bound)
            t_dp, t_cv = [], []
            for i in range(int(repeats)):
                runs = [
                    dp_search(g, z, music_durations=md, **kw) for _ in range(max(1, int(dp_inner)))
                ]
                dp = runs[-1]
                t_dp.append(float(np.mean([r.search_time for r in runs])))
                if i >= max(1, int(conventional_repeats)):
                    continue
                cv = conventional_search(
                    g,
                    z,
                    md,
                    segment_beats=segment_beats * plan.subdivision,
                    max_candidates=max_candidates,
                    **kw,
                )
                t_cv.append(cv.search_time)
            rows.append(
                {
                    "library": name,
                    "stands_in_for": LIBRARIES.get(name, ("", ""))[0],
                    "music_s": float(dur),
                    "n_beats": int(beats.size),
                    "nodes": g.n_nodes,
                    "transitions": g.n_transitions,
                    "multiplicity": "/".join(f"{m:g}" for m in plan.multiplicity),
                    "dp_s": min(t_dp),
                    "conventional_s": min(t_cv),
                    "speedup": min(t_cv) / min(t_dp),
                    "dp_cost": dp.cost,
                    "conventional_cost": cv.cost,
                }
            )
    return pd.DataFrame(rows)


def ratio_table(speed: Any) -> Any:
    """Time ratio (longest / shortest music) per library and method, with paper B's values."""
    import pandas as pd

    rows = []
    for name, grp in speed.groupby("library", sort=False):
        grp = grp.sort_values("music_s")
        lo, hi = grp.iloc[0], grp.iloc[-1]
        rows.append(
            {
                "library": name,
                "music": f"{lo.music_s:g} s -> {hi.music_s:g} s",
                "ratio_dp": hi.dp_s / lo.dp_s,
                "ratio_dp_paper": PAPER_B_TABLE1["ratio_proposed"],
                "ratio_conventional": hi.conventional_s / lo.conventional_s,
                "ratio_conventional_paper": PAPER_B_TABLE1["ratio_conventional"],
                "speedup_min": float(grp.speedup.min()),
                "speedup_max": float(grp.speedup.max()),
                "speedup_paper": "27-543x",
            }
        )
    return pd.DataFrame(rows)


def threshold_table(
    graph: WeightedMotionGraph, *, ths: Sequence[float] = (1.0, 2.0, 3.0, 5.0, 10.0)
) -> Any:
    """Transition edges for each TH with ``rd`` per 0.1 s of typical movement (our
    default, :mod:`beatsync.graph.build`) and per frame-to-frame distance (TH ``x`` in
    frames is ``x / (0.1 fps)`` in ours); ``graph`` built with a TH of at least ``max(ths)``.
    """
    import pandas as pd

    g = graph
    fps = float(g.clips[0].fps)
    n_pairs = g.n_nodes * (g.n_nodes - 1) // 2
    rows = []
    for unit_name, factor in (("0.1 s of typical movement", 1.0), ("1 frame", 0.1 * fps)):
        rd = g.trans_rd * factor
        for th in ths:
            n = int(np.sum(rd < th)) // 2
            rows.append(
                {
                    "rd unit": unit_name,
                    "TH": float(th),
                    "transitions": n,
                    "share of pairs": n / max(1, n_pairs),
                    "nodes with a transition": int(np.unique(g.trans_src[rd < th]).size),
                    "nodes": g.n_nodes,
                }
            )
    return pd.DataFrame(rows)


#: Methods of :func:`quality_table`: label, search method, compose options.
QUALITY_METHODS: dict[str, tuple[str, str, dict]] = {
    "dp": ("proposed DP, tempo-matched (default)", "dp", {}),
    "conventional": ("conventional multi-stage, tempo-matched", "conventional", {}),
    "random": ("random walk, tempo-matched (control)", "random", {}),
    "dp_unbounded": ("proposed DP, unbounded (paper B as written)", "dp", {"scale_bound": None}),
    "dp_rd_unbounded": ("proposed DP (w2 = rd), unbounded", "dp", {"scale_bound": None}),
    "dp_tempo_unbounded": (
        "proposed DP + tempo term, unbounded (extension)",
        "dp",
        {"scale_bound": None, "tempo_weight": 1.0},
    ),
    "conventional_unbounded": (
        "conventional multi-stage, unbounded",
        "conventional",
        {"scale_bound": None},
    ),
    "random_unbounded": ("random walk, unbounded (control)", "random", {"scale_bound": None}),
}

#: Tempo-matched DP compositions of the last quality_table, by (graph, bpm, s, seed).
_COMPOSED: dict[tuple, Any] = {}

_PLAUSIBILITY_COLUMNS = (
    "root_speed_p99",
    "rotation_speed_p99",
    "root_speed_ratio",
    "rotation_speed_ratio",
    "scale_min",
    "scale_p50",
    "scale_max",
)


def quality_table(
    graph: WeightedMotionGraph,
    *,
    bpms: Sequence[float] = (120.0,),
    durations: Sequence[float] = (60.0,),
    seeds: Sequence[int] = (0,),
    methods: Sequence[str] = ("dp", "conventional", "random", "dp_unbounded"),
    sigma: float = 0.05,
) -> Any:
    """Quality proxies and physical plausibility per method, one row per (method, song).

    ``methods``: keys of :data:`QUALITY_METHODS`; the tempo-matched ones compose with
    :func:`~beatsync.graph.compose.compose`'s defaults, the unbounded ones as paper B
    (every interval warped onto one beat). ``scale_outside`` counts the intervals
    outside the default time-scale bound, for every method alike.
    """
    import pandas as pd

    for m in methods:
        if m not in QUALITY_METHODS:
            raise ParameterError(f"unknown method {m!r}; choose from {sorted(QUALITY_METHODS)}")
    g_rd = graph.with_rule("rd")
    lo, hi = DEFAULT_SCALE_BOUND
    rows = []
    _COMPOSED.clear()
    for bpm, dur, seed in itertools.product(bpms, durations, seeds):
        beats, level = song(float(dur), bpm=float(bpm), seed=int(seed))
        for m in methods:
            label, method, kw = QUALITY_METHODS[m]
            g = g_rd if m.startswith("dp_rd") else graph
            with silenced():
                comp = compose(g, beats, level, method=method, seed=int(seed), **kw)
            if m == "dp":  # kept for example_composition (no second search)
                _COMPOSED[(id(graph), float(bpm), float(dur), int(seed))] = comp
            s = comp.search.scales
            rows.append(
                {
                    "method": label,
                    "bpm": float(bpm),
                    "music_s": float(dur),
                    "seed": int(seed),
                    **composition_proxies(comp, sigma=sigma),
                    **{k: comp.plausibility[k] for k in _PLAUSIBILITY_COLUMNS},
                    "scale_outside": int(np.sum((s < lo - 1e-9) | (s > hi + 1e-9))),
                    "two_beat_share": float(np.mean(np.diff(comp.search.boundaries) > 1))
                    if comp.tempo.subdivision == 1
                    else 0.0,
                    "speed_warning": bool(comp.warnings),
                }
            )
    return pd.DataFrame(rows)


def quality_means(quality: Any, *, by: Sequence[str] = ("method",)) -> Any:
    """Mean of every numeric column of :func:`quality_table` per method (and ``by``)."""
    drop = [c for c in ("seed", "music_s", "bpm") if c not in by]
    num = quality.drop(columns=drop)
    return num.groupby(list(by), sort=False).mean(numeric_only=True).reset_index()


def plausibility_targets(quality: Any, *, bound: tuple[float, float] = DEFAULT_SCALE_BOUND) -> Any:
    """The issue's targets per tempo-matched method and song tempo, PASS or FAIL.

    99th-percentile root and joint rotation speed at most 1.25x the fastest library
    clip's, every time-scale factor within ``bound``, and the DP's beat alignment
    (both scores) no lower than the unbounded DP's on the same songs.
    """
    import pandas as pd

    rows = []
    unb = quality[quality.method == QUALITY_METHODS["dp_unbounded"][0]]
    for key in ("dp", "conventional", "random"):
        label = QUALITY_METHODS[key][0]
        for bpm, grp in quality[quality.method == label].groupby("bpm", sort=True):
            row = {
                "method": label,
                "bpm": float(bpm),
                "root_speed_ratio_max": float(grp.root_speed_ratio.max()),
                "rotation_speed_ratio_max": float(grp.rotation_speed_ratio.max()),
                "scale_min": float(grp.scale_min.min()),
                "scale_max": float(grp.scale_max.max()),
            }
            ok = (
                row["root_speed_ratio_max"] <= 1.25
                and row["rotation_speed_ratio_max"] <= 1.25
                and row["scale_min"] >= bound[0] - 1e-9
                and row["scale_max"] <= bound[1] + 1e-9
            )
            if key == "dp" and not unb.empty:
                ref = unb[unb.bpm == bpm]
                row["alignment_motion_vs_unbounded"] = float(
                    grp.alignment_motion.mean() - ref.alignment_motion.mean()
                )
                row["alignment_music_vs_unbounded"] = float(
                    grp.alignment_music.mean() - ref.alignment_music.mean()
                )
            row["speed_and_bound"] = "PASS" if ok else "FAIL"
            rows.append(row)
    return pd.DataFrame(rows)


def eligibility_table(
    graph: WeightedMotionGraph, *, bpms: Sequence[float] = (120.0,), duration: float = 60.0
) -> Any:
    """Which clips a song of each tempo uses, and why (the tempo plan of compose)."""
    import pandas as pd

    from ..graph.timescale import plan_tempo

    rows = []
    for bpm in bpms:
        beats, _ = song(float(duration), bpm=float(bpm))
        plan = plan_tempo(graph, beats)
        mult = "/".join(f"{m:g}" for m in plan.multiplicity)
        for r in plan.clip_table:
            rows.append(
                {
                    "song_bpm": float(bpm),
                    "clip": r["clip"],
                    "clip_bpm": r["tempo_bpm"],
                    "group": r["group"],
                    "eligible": r["eligible"],
                    "multiplicity": mult,
                    "reason": r["reason"],
                }
            )
    return pd.DataFrame(rows)


def example_composition(
    graph: WeightedMotionGraph, *, bpm: float, duration: float, seed: int = 0, **kwargs: Any
) -> Any:
    """One composition (DP by default) of the study's drum song, warnings silenced.

    The tempo-matched DP composition of the last :func:`quality_table` for the same
    graph and song is reused when no other option is given.
    """
    key = (id(graph), float(bpm), float(duration), int(seed))
    if not kwargs and key in _COMPOSED:
        return _COMPOSED[key]
    beats, level = song(float(duration), bpm=float(bpm), seed=int(seed))
    with silenced():
        return compose(graph, beats, level, **kwargs)


def composition_proxies(
    comp: Any, *, sigma: float = 0.05, blend: float = 1.0 / 3.0, beat_smooth: float = 0.1
) -> dict[str, float]:
    """:func:`beatsync.evaluate.composition.quality_proxies` of a composition, and its
    ``n_transitions``: kinematic beats (smoothed over ``beat_smooth`` [s]; on noise-free
    motion only 0 keeps beats that land exactly), positions and intensities computed."""

    from ..evaluate.composition import foot_joints, quality_proxies
    from ..motion_beats import beat_interval_intensity, kinematic_beats, motion_positions
    from ..validation import frames_to_time

    m = comp.motion
    beats = comp.music_beats
    last = float(frames_to_time(m.n_frames - 1, fps=m.fps))
    with silenced():
        mb = kinematic_beats(m, smooth=beat_smooth)
        inside = beats[beats <= last + 1e-9]
        inten = beat_interval_intensity(m, inside) if inside.size >= 2 else np.empty(0)
    pos = motion_positions(m)
    q = quality_proxies(
        motion_beats=mb,
        music_beats=beats,
        span=(float(beats[0]), float(min(beats[-1], last))),
        positions=pos,
        foot_positions=motion_positions(m, joints=foot_joints(m)),
        fps=m.fps,
        transition_times=comp.synthesis.transition_times,
        motion_intensity=inten,
        music_level=comp.music_level,
        sigma=sigma,
        blend=blend,
    )
    return {**q, "n_transitions": int(comp.search.n_transitions)}


def library_reference(clips: Sequence[Any]) -> Any:
    """Foot sliding, velocity-change and speed statistics of the captured clips themselves.

    The reference for :func:`quality_table`: what the proxies read on real capture,
    and the root and joint rotation speed percentiles the plausibility ratios divide
    by (the largest clip 99th percentiles).
    """
    import pandas as pd

    from ..evaluate.composition import foot_joints, foot_sliding, velocity_change
    from ..graph.plausibility import speed_profile
    from ..motion_beats import motion_positions

    rows = []
    for c in clips:
        dv = velocity_change(motion_positions(c), fps=c.fps)
        feet = motion_positions(c, joints=foot_joints(c))
        rows.append(
            {
                "clip": c.name,
                "foot_sliding": foot_sliding(feet, fps=c.fps),
                "velocity_change_p99_over_median": float(np.percentile(dv, 99) / np.median(dv)),
                **speed_profile(c),
            }
        )
    return pd.DataFrame(rows)


def summary_graphs(graphs: dict[str, WeightedMotionGraph]) -> Any:
    """Size of each graph (deterministic: no timings)."""
    import pandas as pd

    rows = []
    for name, g in graphs.items():
        rows.append(
            {
                "library": name,
                "stands_in_for": LIBRARIES.get(name, ("", ""))[0],
                "clips": len(g.clips),
                "beat frames": g.n_nodes,
                "intervals": g.n_intervals,
                "transition edges": g.n_transitions,
                "TH": g.th,
                "smallest rd": g.min_rd,
                "median beat interval [s]": float(np.nanmedian(g.interval_duration())),
            }
        )
    return pd.DataFrame(rows)


def plot_speed(speed: Any) -> Any:
    """Log-scale bar chart of search times per library and music length."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.5))
    labels = [f"{r.library}\n{r.music_s:g} s" for r in speed.itertuples()]
    x = np.arange(len(labels))
    ax.bar(x - 0.2, speed.dp_s, 0.4, label="proposed (DP)")
    ax.bar(x + 0.2, speed.conventional_s, 0.4, label="conventional (multi-stage)")
    ax.set_yscale("log")
    ax.set_xticks(x, labels)
    ax.set_ylabel("search time [s]")
    ax.set_title("Search time, graph build excluded")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_intensity(comp: Any) -> Any:
    """Music level and composed-motion intensity per beat interval (both z-scored)."""
    import matplotlib.pyplot as plt

    from ..motion_beats import beat_interval_intensity
    from ..validation import frames_to_time

    m = comp.motion
    last = float(frames_to_time(m.n_frames - 1, fps=m.fps))
    beats = comp.music_beats[comp.music_beats <= last]
    inten = _z(beat_interval_intensity(m, beats))
    fig, ax = plt.subplots(figsize=(7, 3))
    mid = (beats[:-1] + beats[1:]) / 2
    ax.plot(mid, comp.music_z[: mid.size], label="music level (z)")
    ax.plot(mid, inten, label="motion intensity after warping (z)")
    for t in comp.synthesis.transition_times:
        ax.axvline(t, color="0.7", lw=0.8)
    ax.set_xlabel("music time [s] (grey: transitions)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
