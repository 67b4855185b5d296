"""End-to-end composition: music beats and intensity -> path -> synthesized dance.

:func:`compose` z-scores the music level per beat interval (RMS [dB],
:func:`beatsync.music.beat_rms_db`), plans the tempo, searches the graph and
synthesizes the motion; :func:`compose_music` starts from audio. The output motion
starts at music time 0.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb``,
``notebooks/paper_b_tab02_quality_proxies.ipynb``; paper B section 3.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError, silenced, warn
from ..motion import Motion
from ..motion_beats import zscore
from ..validation import check_choice, check_finite, check_times
from .baselines import check_conventional_options, conventional_core, random_core
from .build import WeightedMotionGraph
from .objective import SearchResult, prepare_search
from .plausibility import plausibility
from .search import METHODS, dp_core
from .synthesis import SynthesisResult, check_output, synthesize_core
from .timescale import (
    DEFAULT_SCALE_BOUND,
    TempoPlan,
    check_scale_bound,
    music_grid,
    plan_tempo,
)

__all__ = ["Composition", "compose", "compose_music", "check_music_beats"]


@dataclass(frozen=True, eq=False)
class Composition:
    """A composed dance (frame ``j`` of ``motion`` plays at ``j / motion.fps`` s of the music).

    ``music_level`` [dB] and ``music_z`` (z-scored) are per beat interval; ``timings``
    [s] holds ``search_s`` and ``synthesis_s``; ``plausibility`` the speeds against the
    library's (:func:`beatsync.graph.plausibility.plausibility`) and ``warnings`` its
    warnings; ``anchors`` [s] the music times on which the path's motion beats land.
    """

    motion: Motion
    search: SearchResult
    synthesis: SynthesisResult
    music_beats: np.ndarray
    music_level: np.ndarray
    music_z: np.ndarray
    timings: dict = field(default_factory=dict)
    tempo: TempoPlan | None = None
    plausibility: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    anchors: np.ndarray | None = None

    @property
    def n_transitions(self) -> int:
        return self.search.n_transitions

    def report(self) -> dict:
        """A JSON-ready summary (path as clip/beat-frame pairs, costs, timings)."""
        return {
            "method": self.search.method,
            "n_beats": int(self.music_beats.size),
            "n_intervals": int(self.search.path.size),
            "n_transitions": self.n_transitions,
            "cost": self.search.cost,
            "intensity_cost": self.search.intensity_cost,
            "transition_cost": self.search.transition_cost,
            "search_time_s": self.search.search_time,
            "synthesis_time_s": self.timings.get("synthesis_s"),
            "duration_s": (self.motion.n_frames - 1) / self.motion.fps,  # the last frame's time
            "fps": self.motion.fps,
            "transition_times_s": self.synthesis.transition_times,
            "graph": self.synthesis.info.get("graph_summary", {}),
            "tempo": self.tempo.report() if self.tempo is not None else None,
            "multiplicity_used": self.multiplicity_used(),
            "plausibility": self.plausibility,
            "warnings": list(self.warnings),
        }

    def multiplicity_used(self) -> dict[str, int]:
        """How many intervals covered each number of music beats."""
        sub = self.tempo.subdivision if self.tempo is not None else 1
        vals, counts = np.unique(np.diff(self.search.boundaries), return_counts=True)
        return {f"{v / sub:g}": int(c) for v, c in zip(vals, counts, strict=True)}


def check_music_beats(beats: Any, *, duration: float | None = None) -> np.ndarray:
    """The one check of music beats [s] on the compose path (``duration``: the audio's)."""
    n = 0 if beats is None else int(np.asarray(beats).size)
    if n < 2:
        raise ParameterError(
            f"the music has {n} beat(s): at least two are needed to compose a dance "
            "(is the beats file empty, or the music silent?)"
        )
    return check_times(beats, name="music beats", duration=duration)


def compose(
    graph: WeightedMotionGraph,
    music_beats: Any,
    music_level: Any,
    *,
    method: str = "dp",
    lam: float = 1.0,
    fps: float | None = None,
    blend: float = 1.0 / 3.0,
    end_time: float | None = None,
    seed: int = 0,
    warp: str = "pchip",
    scale_bound: Any = DEFAULT_SCALE_BOUND,
    multiplicity: Any = "auto",
    tempo_select: bool = True,
    **search_kwargs: Any,
) -> Composition:
    """Compose a dance for the given music beats [s] and levels [dB] (one per beat interval).

    ``method``: ``"dp"`` (proposed), ``"conventional"`` (baseline) or ``"random"``
    (control, seeded by ``seed``); ``fps``, ``blend``, ``end_time``, ``warp``: as in
    :func:`beatsync.graph.synthesis.synthesize`; ``scale_bound`` (``None``: unbounded,
    paper B as written), ``multiplicity`` and ``tempo_select``: :mod:`.timescale`;
    ``search_kwargs``: the options of :func:`.dp_search` or :func:`.conventional_search`.
    A result much faster than its library warns (:mod:`.plausibility`).
    """
    beats = check_music_beats(music_beats)
    level = check_finite(music_level, name="music level")
    if level.shape != (beats.size - 1,):
        raise ParameterError(
            f"music_level has {level.size} values for {beats.size - 1} beat intervals "
            "(one per interval between successive beats)"
        )
    check_choice(method, METHODS, name="method")
    bound = check_scale_bound(scale_bound)
    fps, blend, end_time = check_output(graph, beats, fps, blend, warp, 0.0, end_time)
    plan = plan_tempo(
        graph, beats, scale_bound=bound, multiplicity=multiplicity, tempo_select=bool(tempo_select)
    )
    grid, grid_level = music_grid(beats, level, plan.subdivision)
    with silenced():
        z = zscore(grid_level, name="music intensity")
    res = _search(graph, z, np.diff(grid), method, lam, seed, plan, search_kwargs)
    t0 = time.perf_counter()
    anchors = grid[res.boundaries]
    syn = synthesize_core(graph, res.path, anchors, fps, blend, 0.0, end_time, warp)
    syn.info["graph_summary"] = graph.summary()
    syn_s = time.perf_counter() - t0
    plaus, notes = plausibility(syn.motion, graph.speed_reference(), res.scales, bound)
    for note in notes:
        warn(note, stacklevel=2)
    return Composition(
        motion=syn.motion,
        search=res,
        synthesis=syn,
        music_beats=beats,
        music_level=level,
        music_z=z[:: plan.subdivision],
        timings={"search_s": res.search_time, "synthesis_s": syn_s},
        tempo=plan,
        plausibility=plaus,
        warnings=notes,
        anchors=anchors,
    )


def _search(graph, z, md, method, lam, seed, plan, kwargs):
    """Run one search on the song's grid under the tempo plan (inputs validated here)."""
    sub = plan.subdivision
    tw = 0.0
    if method == "conventional":
        opts = check_conventional_options(**kwargs)
        opts["seg"] = opts["seg"] * sub
    elif method == "random":
        if kwargs:
            raise ParameterError(f"the random walk takes no options {sorted(kwargs)}")
        lam = 0.0
    else:
        start = kwargs.pop("start", "any")
        tw = kwargs.pop("tempo_weight", 0.0)
        if kwargs:
            raise ParameterError(f"unknown DP option(s) {sorted(kwargs)}: use tempo_weight, start")
    z, lam, tw, md, bound, steps, mask = prepare_search(
        graph, z, lam, tw, md, plan.bound, plan.steps, plan.node_mask
    )
    if method == "conventional":
        return conventional_core(graph, z, md, lam, bound, steps, mask, **opts, subdivision=sub)
    if method == "random":
        return random_core(graph, z.size, seed, md, bound, steps, mask, subdivision=sub)
    return dp_core(graph, z, lam, tw, md, bound, steps, mask, start=start, subdivision=sub)


def compose_music(
    graph: WeightedMotionGraph,
    y: Any,
    sr: float,
    *,
    beats: Any = None,
    bpm: float | None = None,
    **kwargs: Any,
) -> Composition:
    """Compose a dance for audio (as long as the audio): beats tracked or given [s], levels."""
    from ..music import beat_rms_db, track_music_beats

    y_arr = np.asarray(y)
    if beats is None:
        beats = track_music_beats(y_arr, sr, bpm=bpm)  # validates the audio
    else:
        beats = check_music_beats(beats, duration=y_arr.size / float(sr))
    level = beat_rms_db(y_arr, sr, beats)
    kwargs.setdefault("end_time", y_arr.size / float(sr))
    return compose(graph, beats, level, **kwargs)
