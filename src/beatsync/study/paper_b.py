"""Paper B's study: libraries, timing and quality tables, figures (the notebooks' calls).

The notebooks only call these functions.

- :func:`load_library` returns the motion libraries that stand in for paper B's
  (their Break dance and Indian dance captures are not available): the four CMU
  salsa takes, the CMU walking clips of one skeleton, or synthetic dances
  (:mod:`beatsync.synth.library`).
- :func:`speed_table` times the DP (proposed) and the multi-stage search
  (conventional) on synthetic drum songs of the given lengths
  (:func:`beatsync.synth.audio.drum_song`), side by side in the same run, graph build
  excluded, and :func:`ratio_table` derives the speedups and the time ratios when
  the music doubles, with paper B's reported values beside ours.
- :func:`threshold_table` counts transition edges for several TH under two
  normalisations of ``rd`` (per frame-to-frame distance, and per 0.1 s of typical
  movement, our default).
- :func:`quality_table` scores compositions with the proxies of
  :mod:`beatsync.evaluate.composition` (:func:`composition_proxies` computes the
  arrays they need: kinematic beats, positions, intensities).
- :func:`write_artifacts` writes tables (CSV), figures (PNG) and the parameters with
  the package version (JSON) under ``results/<notebook>/``.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb``,
``notebooks/paper_b_tab02_quality_proxies.ipynb``.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import BeatsyncWarning, ParameterError
from ..graph.build import WeightedMotionGraph, build_graph
from ..graph.compose import compose
from ..graph.search import conventional_search, dp_search
from .artifacts import write_artifacts

__all__ = [
    "LIBRARIES",
    "PAPER_B_TABLE1",
    "load_library",
    "song",
    "speed_table",
    "ratio_table",
    "threshold_table",
    "quality_table",
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
    """Clips (and exact beats for synthetic ones, else None) of a study library.

    Parameters
    ----------
    name : {"salsa", "synthetic", "walk"}
    duration : float [s]
        Length of each synthetic clip.
    n_clips : int
        Number of synthetic clips.
    seed : int
    """
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


def song(duration: float, *, bpm: float = 100.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Beats [s] and level per beat interval [dB] of a synthetic drum song."""
    from ..music import beat_rms_db
    from ..synth.audio import drum_song

    s = drum_song(duration, bpm=bpm, seed=seed, sr=22050)
    return s.beats, beat_rms_db(s.y, s.sr, s.beats)


def _z(level: np.ndarray) -> np.ndarray:
    from ..motion_beats import zscore

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        return zscore(level)


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
) -> Any:
    """Search times of the DP and the conventional method (best of ``repeats``) [s].

    Each DP timing sample is the mean of ``dp_inner`` consecutive runs (one DP takes
    about a millisecond, too short to time alone on a shared machine).

    Times are the searches' own clocks (:attr:`SearchResult.search_time`): the graph
    build and its successor/predecessor tables (built once per graph, offline) are
    excluded, as in paper B.

    Returns
    -------
    pandas.DataFrame
        One row per (library, music length): ``library``, ``stands_in_for``,
        ``music_s``, ``n_beats``, ``nodes``, ``transitions``, ``dp_s``,
        ``conventional_s``, ``speedup``, ``dp_cost``, ``conventional_cost``.
    """
    import pandas as pd

    rows = []
    for name, g in graphs.items():
        g.predecessor_table()  # search tables belong to the offline graph
        g.successor_lists()
        for dur in durations:
            beats, level = song(float(dur), bpm=bpm, seed=seed)
            z = _z(level)
            md = np.diff(beats)
            t_dp, t_cv = [], []
            for _ in range(int(repeats)):
                runs = [dp_search(g, z) for _ in range(max(1, int(dp_inner)))]
                dp = runs[-1]
                t_dp.append(float(np.mean([r.search_time for r in runs])))
                cv = conventional_search(
                    g, z, md, segment_beats=segment_beats, max_candidates=max_candidates
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
    clips: Sequence[Any],
    *,
    beats: Sequence[np.ndarray] | None = None,
    ths: Sequence[float] = (1.0, 2.0, 3.0, 5.0, 10.0),
) -> Any:
    """Transition edges for each TH under two ``rd`` normalisations.

    ``rd_unit = 0.1 s`` is our default (module :mod:`beatsync.graph.build`);
    ``rd_unit = 1 / fps`` measures the pose jump in frame-to-frame distances.
    """
    import pandas as pd

    g = build_graph(clips, beats=beats, th=1e12, require_transitions=False)
    fps = float(clips[0].fps)
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


def quality_table(
    graph: WeightedMotionGraph,
    *,
    durations: Sequence[float] = (30.0,),
    seeds: Sequence[int] = (0,),
    bpm: float = 100.0,
    methods: Sequence[str] = ("dp", "dp_rd", "conventional", "random"),
    sigma: float = 0.05,
) -> Any:
    """Quality proxies per method, one row per (method, song).

    Methods: ``"dp"`` (proposed, eq. 2 as written), ``"dp_rd"`` (proposed with
    ``w2 = rd``), ``"dp_tempo"`` (extension: DP with a tempo term, weight 1),
    ``"conventional"``, ``"random"``.
    """
    import pandas as pd

    labels = {
        "dp": "proposed DP (w2 = max(rd, 2))",
        "dp_rd": "proposed DP (w2 = rd)",
        "dp_tempo": "proposed DP + tempo term (extension)",
        "conventional": "conventional multi-stage",
        "random": "random walk (control)",
    }
    g_rd = graph.with_rule("rd")
    rows = []
    for dur in durations:
        for seed in seeds:
            beats, level = song(float(dur), bpm=bpm, seed=int(seed))
            for m in methods:
                if m not in labels:
                    raise ParameterError(f"unknown method {m!r}; choose from {sorted(labels)}")
                g = g_rd if m == "dp_rd" else graph
                kw: dict[str, Any] = {}
                method = m
                if m in ("dp_rd", "dp_tempo"):
                    method = "dp"
                if m == "dp_tempo":
                    kw["tempo_weight"] = 1.0
                comp = compose(g, beats, level, method=method, seed=int(seed), **kw)
                q = composition_proxies(comp, sigma=sigma)
                rows.append({"method": labels[m], "music_s": float(dur), "seed": int(seed), **q})
    return pd.DataFrame(rows)


def composition_proxies(
    comp: Any, *, sigma: float = 0.05, blend: float = 1.0 / 3.0, beat_smooth: float = 0.1
) -> dict[str, float]:
    """Quality proxies of a :class:`~beatsync.graph.compose.Composition`.

    Runs the stages the proxies need on the composed motion (kinematic beats with
    ``beat_smooth`` [s] smoothing, joint positions, intensity per music beat interval)
    and scores them with :func:`beatsync.evaluate.composition.quality_proxies`. On
    noise-free motion the default smoothing can move a speed minimum by a frame or
    two, so motion whose beats land exactly scores alignment 1 only with 0.

    Returns
    -------
    dict
        The proxies plus ``n_transitions``.
    """
    from ..evaluate.composition import foot_joints, quality_proxies
    from ..motion_beats import beat_interval_intensity, kinematic_beats, motion_positions
    from ..units import frames_to_time

    m = comp.motion
    beats = comp.music_beats
    last = float(frames_to_time(m.n_frames - 1, fps=m.fps))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
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
    """Foot sliding and velocity-change statistics of the captured clips themselves.

    The reference for :func:`quality_table`: what the proxies read on real capture.
    """
    import pandas as pd

    from ..evaluate.composition import foot_joints, foot_sliding, velocity_change
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
    import matplotlib

    matplotlib.use("Agg", force=False)
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
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ..motion_beats import beat_interval_intensity
    from ..units import frames_to_time

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
