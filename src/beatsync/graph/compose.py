"""End-to-end composition: music beats and intensity -> path -> synthesized dance.

:func:`compose` takes music beats [s] and the music level per beat interval (RMS in
dB, :func:`beatsync.music.beat_rms_db`), z-scores the level, searches the graph with
the chosen method (``"dp"`` proposed, ``"conventional"`` baseline, ``"random"``
control) and synthesizes the motion. :func:`compose_music` starts from audio.

Data contract: beats in seconds (1-D float64, strictly increasing); levels one per
beat interval; the output motion starts at music time 0.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb``,
``notebooks/paper_b_tab02_quality_proxies.ipynb``; paper B section 3.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import BeatsyncWarning, ParameterError
from ..motion import Motion
from ..motion_beats import zscore
from ..units import check_finite, check_times
from .build import WeightedMotionGraph
from .search import SearchResult, search
from .warp import SynthesisResult, synthesize

__all__ = ["Composition", "compose", "compose_music", "check_music_beats"]


@dataclass(frozen=True, eq=False)
class Composition:
    """A composed dance.

    Attributes
    ----------
    motion : Motion
        Frame ``j`` plays at ``j / motion.fps`` seconds of the music.
    search : SearchResult
    synthesis : SynthesisResult
    music_beats : np.ndarray [s]
    music_level : np.ndarray [dB] (one per interval)
    music_z : np.ndarray (z-scored level)
    timings : dict [s]
        ``search_s`` and ``synthesis_s``.
    """

    motion: Motion
    search: SearchResult
    synthesis: SynthesisResult
    music_beats: np.ndarray
    music_level: np.ndarray
    music_z: np.ndarray
    timings: dict = field(default_factory=dict)

    @property
    def n_transitions(self) -> int:
        return self.search.n_transitions

    def report(self) -> dict:
        """A JSON-ready summary (path as clip/beat-frame pairs, costs, timings)."""
        g = self.synthesis.info.get("graph_summary", {})
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
            "duration_s": self.motion.n_frames / self.motion.fps,
            "fps": self.motion.fps,
            "transition_times_s": self.synthesis.transition_times,
            "graph": g,
        }


def check_music_beats(beats: Any, *, duration: float | None = None) -> np.ndarray:
    """The one check of music beats on the compose path: seconds, increasing, at least two.

    Parameters
    ----------
    beats : array_like [s]
    duration : float, optional [s]
        Length of the audio the beats belong to (beats after it are refused).

    Raises
    ------
    ParameterError
        Fewer than two beats, non-finite, not increasing, or after the audio.
    """
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
    **search_kwargs: Any,
) -> Composition:
    """Compose a dance for the given music beats and levels.

    Parameters
    ----------
    graph : WeightedMotionGraph
    music_beats : np.ndarray [shape=(K+1,)] [s]
    music_level : np.ndarray [shape=(K,)] [dB]
        Music intensity per beat interval; z-scored here.
    method : {"dp", "conventional", "random"}
    lam : float >= 0
        Factor on transition weights.
    fps : float, optional [Hz]
        Output rate (default the library's).
    blend : float [s]
        Transition blend length.
    end_time : float, optional [s]
        Output length (default the last beat).
    seed : int
        Random walk seed.
    warp : {"pchip", "linear"}
        Time warp inside runs (see :func:`beatsync.graph.warp.synthesize`).
    **search_kwargs
        Passed to the search (``segment_beats``, ``tempo_weight``, ...).

    Raises
    ------
    ParameterError
        Fewer than two music beats, level/beat count mismatch.
    """
    beats = check_music_beats(music_beats)
    level = check_finite(music_level, name="music level")
    if level.shape != (beats.size - 1,):
        raise ParameterError(
            f"music_level has {level.size} values for {beats.size - 1} beat intervals "
            "(one per interval between successive beats)"
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        z = zscore(level, name="music intensity")
    res = search(graph, z, np.diff(beats), method=method, lam=lam, seed=seed, **search_kwargs)
    t0 = time.perf_counter()
    syn = synthesize(graph, res.path, beats, fps=fps, blend=blend, end_time=end_time, warp=warp)
    syn.info["graph_summary"] = graph.summary()
    return Composition(
        motion=syn.motion,
        search=res,
        synthesis=syn,
        music_beats=beats,
        music_level=level,
        music_z=z,
        timings={"search_s": res.search_time, "synthesis_s": time.perf_counter() - t0},
    )


def compose_music(
    graph: WeightedMotionGraph,
    y: Any,
    sr: float,
    *,
    beats: Any = None,
    bpm: float | None = None,
    **kwargs: Any,
) -> Composition:
    """Compose a dance for audio: track beats (or use ``beats`` [s]), measure levels, compose.

    The output lasts as long as the audio (the last interval's warp continues).
    """
    from ..music import beat_rms_db, track_music_beats

    y_arr = np.asarray(y)
    if beats is None:
        beats = track_music_beats(y_arr, sr, bpm=bpm)  # validates the audio
    else:
        beats = check_music_beats(beats, duration=y_arr.size / float(sr))
    level = beat_rms_db(y_arr, sr, beats)
    kwargs.setdefault("end_time", y_arr.size / float(sr))
    return compose(graph, beats, level, **kwargs)
