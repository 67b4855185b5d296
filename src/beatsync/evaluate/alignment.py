"""Dance-music beat alignment scores.

Two incompatible scores are published under the name "beat alignment score"; both
compare motion beats (kinematic beats of the dance) with music beats through a
Gaussian of the distance to the nearest beat of the other kind, but they average
over different sets:

- :func:`beat_alignment_music` averages over **music beats**: for every music beat,
  how close is the nearest motion beat? This is the score as written in Li et al.
  2021 (AIST++ / FACT, "AI Choreographer", eq. of BeatAlign). It asks whether every
  beat of the song is danced; a dance with many extra motion beats is not penalised.
- :func:`beat_alignment_motion` averages over **motion beats**: for every motion
  beat, how close is the nearest music beat? This is the score of Siyao et al. 2022
  (Bailando, "BAS"), who noted the difference. It asks whether every accent of the
  dance falls on a beat; a dance that skips beats is not penalised.

Both use ``exp(-d^2 / (2 sigma^2))`` with ``d`` the distance to the nearest beat
[s]; the papers' sigma of 3 frames at 60 fps is ``sigma = 0.05`` s (default here).
Every table of this project says which of the two it reports; :func:`alignment_scores`
returns both.

Kinematic beats come from :func:`beatsync.motion_beats.kinematic_beats` (local minima
of smoothed joint speed).

Data contract
-------------
Beat times are 1-D float64 arrays in seconds, strictly increasing (as in
``mir_eval.beat``). Scores lie in ``[0, 1]``; 1 means every beat of the averaged set
sits exactly on a beat of the other set. Empty input is degenerate but legal: a
:class:`~beatsync.errors.BeatsyncWarning` is issued and the score is 0.

Notebook: ``notebooks/paper_a_tab01_frame_counts.ipynb`` (alignment before/after sync).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import BeatsyncWarning, ParameterError
from ..units import check_times

__all__ = [
    "validate",
    "nearest_distance",
    "beat_alignment_motion",
    "beat_alignment_music",
    "alignment_scores",
    "motion_alignment",
    "offset_control",
    "beat_phase_consistency",
    "kinematic_phase_offset",
    "evaluate_sync",
    "sync_table",
]

#: Gaussian width of both published scores: 3 frames at 60 fps [s]
DEFAULT_SIGMA = 0.05


def _check_sigma(sigma: Any) -> float:
    try:
        s = float(sigma)
    except (TypeError, ValueError):
        raise ParameterError(f"sigma={sigma!r} must be a number of seconds") from None
    if not np.isfinite(s) or s <= 0:
        raise ParameterError(f"sigma={sigma!r} must be a finite width > 0 [s]")
    if s >= 1.0:
        raise ParameterError(
            f"sigma={sigma!r} s is wider than a beat: sigma is in seconds, not frames "
            "(the papers' 3 frames at 60 fps is sigma=0.05)"
        )
    return s


def validate(motion_beats: Any, music_beats: Any) -> tuple[np.ndarray, np.ndarray]:
    """Check both beat sequences (1-D increasing seconds); return them as float64.

    Raises
    ------
    ParameterError
        Not 1-D, NaN, negative or unsorted times.
    """
    mb = check_times(motion_beats, name="motion_beats")
    yb = check_times(music_beats, name="music_beats")
    return mb, yb


def nearest_distance(events: Any, reference: Any) -> np.ndarray:
    """Distance [s] from each event to the nearest reference time.

    Parameters
    ----------
    events : np.ndarray [shape=(n,)] [s], increasing
    reference : np.ndarray [shape=(m,), m >= 1] [s], increasing

    Returns
    -------
    d : np.ndarray [shape=(n,)] [s], >= 0
    """
    e = np.asarray(events, dtype=np.float64)
    r = np.asarray(reference, dtype=np.float64)
    idx = np.searchsorted(r, e)
    lo = np.clip(idx - 1, 0, r.size - 1)
    hi = np.clip(idx, 0, r.size - 1)
    return np.minimum(np.abs(e - r[lo]), np.abs(e - r[hi]))


def _score(averaged: np.ndarray, other: np.ndarray, sigma: float, what: str) -> float:
    if averaged.size == 0 or other.size == 0:
        warnings.warn(
            f"no {what} to score (motion beats: averaged={averaged.size}, other={other.size}); "
            "returning 0",
            BeatsyncWarning,
            stacklevel=3,
        )
        return 0.0
    d = nearest_distance(averaged, other)
    return float(np.mean(np.exp(-(d * d) / (2.0 * sigma * sigma))))


def beat_alignment_motion(
    motion_beats: Any, music_beats: Any, *, sigma: float = DEFAULT_SIGMA
) -> float:
    """Beat alignment averaged over motion beats (Siyao et al. 2022, "BAS").

    ``(1/|M|) sum_{t in M} exp(-min_{b in B} (t - b)^2 / (2 sigma^2))`` with ``M`` the
    motion beats and ``B`` the music beats.

    Parameters
    ----------
    motion_beats : np.ndarray [shape=(n,)] [s]
    music_beats : np.ndarray [shape=(m,)] [s]
    sigma : float > 0 [s]
        Gaussian width; 0.05 s = 3 frames at 60 fps.

    Returns
    -------
    score : float in [0, 1]

    Examples
    --------
    >>> beat_alignment_motion([0.5, 1.0], [0.0, 0.5, 1.0, 1.5])
    1.0
    """
    sigma = _check_sigma(sigma)
    mb, yb = validate(motion_beats, music_beats)
    return _score(mb, yb, sigma, "motion beats")


def beat_alignment_music(
    motion_beats: Any, music_beats: Any, *, sigma: float = DEFAULT_SIGMA
) -> float:
    """Beat alignment averaged over music beats (Li et al. 2021, AIST++ "BeatAlign").

    ``(1/|B|) sum_{b in B} exp(-min_{t in M} (b - t)^2 / (2 sigma^2))``.

    Parameters
    ----------
    motion_beats : np.ndarray [shape=(n,)] [s]
    music_beats : np.ndarray [shape=(m,)] [s]
    sigma : float > 0 [s]

    Returns
    -------
    score : float in [0, 1]

    Examples
    --------
    >>> round(beat_alignment_music([0.5, 1.0], [0.0, 0.5, 1.0, 1.5]), 3)
    0.5
    """
    sigma = _check_sigma(sigma)
    mb, yb = validate(motion_beats, music_beats)
    return _score(yb, mb, sigma, "music beats")


def alignment_scores(
    motion_beats: Any,
    music_beats: Any,
    *,
    sigma: float = DEFAULT_SIGMA,
    span: tuple[float, float] | None = None,
) -> dict[str, float]:
    """Both beat alignment scores, plus the beat counts they were computed on.

    Parameters
    ----------
    motion_beats, music_beats : np.ndarray [s]
    sigma : float > 0 [s]
    span : (float, float), optional [s]
        Keep only beats inside ``[span[0], span[1]]`` (e.g. the time both the dance
        and the music play), so music after the dance ends is not counted as missed.

    Returns
    -------
    dict
        ``alignment_motion`` (averaged over motion beats), ``alignment_music``
        (averaged over music beats), ``n_motion_beats``, ``n_music_beats``, ``sigma_s``.
    """
    sigma = _check_sigma(sigma)
    mb, yb = validate(motion_beats, music_beats)
    if span is not None:
        lo, hi = float(span[0]), float(span[1])
        if not hi > lo:
            raise ParameterError(f"span={span!r} must be (start, end) with end > start [s]")
        mb = mb[(mb >= lo) & (mb <= hi)]
        yb = yb[(yb >= lo) & (yb <= hi)]
    return {
        "alignment_motion": _score(mb, yb, sigma, "motion beats"),
        "alignment_music": _score(yb, mb, sigma, "music beats"),
        "n_motion_beats": int(mb.size),
        "n_music_beats": int(yb.size),
        "sigma_s": sigma,
    }


def _kinematic_beats(motion: Any, **kwargs: Any) -> np.ndarray:
    from ..motion_beats import kinematic_beats

    return kinematic_beats(motion, **kwargs)


def motion_alignment(
    motion: Any,
    music_beats: Any,
    *,
    sigma: float = DEFAULT_SIGMA,
    offset: float = 0.0,
    **beat_kwargs: Any,
) -> dict[str, float]:
    """Both alignment scores of a motion's kinematic beats against music beats.

    Parameters
    ----------
    motion : beatsync.motion.Motion
        With a skeleton or marker positions; frame ``k`` plays at music time
        ``offset + k / fps``.
    music_beats : np.ndarray [s]
    sigma : float > 0 [s]
    offset : float [s]
        Music time of the motion's first frame.
    **beat_kwargs
        Passed to :func:`beatsync.motion_beats.kinematic_beats` (``method``, ``smooth``...).

    Returns
    -------
    dict
        As :func:`alignment_scores`, computed over the time both play.
    """
    mb = _kinematic_beats(motion, **beat_kwargs) + float(offset)
    mb = mb[mb >= 0]
    start = max(0.0, float(offset))
    end = float(offset) + float(motion.duration)
    return alignment_scores(mb, music_beats, sigma=sigma, span=(start, end))


def offset_control(
    motion_beats: Any,
    music_beats: Any,
    *,
    sigma: float = DEFAULT_SIGMA,
    n_trials: int = 200,
    seed: int = 0,
) -> dict[str, float]:
    """Chance level: both scores with the motion beats shifted by random offsets.

    Each trial shifts all motion beats by one offset drawn uniformly from
    ``[-T/2, T/2)``, ``T`` the median music beat period, so the rhythm of the dance is
    kept but its phase relative to the music is random.

    Returns
    -------
    dict
        Mean and standard deviation over trials of ``alignment_motion`` and
        ``alignment_music``, and ``n_trials``.
    """
    sigma = _check_sigma(sigma)
    mb, yb = validate(motion_beats, music_beats)
    if yb.size < 2:
        raise ParameterError("offset_control needs at least 2 music beats to know the beat period")
    if int(n_trials) < 1:
        raise ParameterError(f"n_trials={n_trials!r} must be >= 1")
    period = float(np.median(np.diff(yb)))
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(-period / 2, period / 2, size=int(n_trials))
    mot, mus = [], []
    for off in offsets:
        shifted = mb + off
        shifted = shifted[shifted >= 0]
        mot.append(_score(shifted, yb, sigma, "motion beats"))
        mus.append(_score(yb, shifted, sigma, "music beats"))
    return {
        "alignment_motion_mean": float(np.mean(mot)),
        "alignment_motion_std": float(np.std(mot)),
        "alignment_music_mean": float(np.mean(mus)),
        "alignment_music_std": float(np.std(mus)),
        "n_trials": int(n_trials),
    }


def beat_phase_consistency(motion_beats: Any, music_beats: Any) -> float:
    """How consistently motion beats fall at the same phase of the music's beat.

    The phase of a motion beat is its fractional position inside the music beat
    interval that contains it (0 on a beat, 0.5 half-way); the score is the length of
    the mean phase vector, ``|mean exp(2 pi i phase)|`` (vector strength): 1 if every
    motion beat sits at the same phase (phase-locked, whatever that phase is), near 0
    if the phases are spread (a dance drifting against the music). Motion beats
    outside the span of the music beats are ignored.

    Unlike the two alignment scores this does not reward one particular phase:
    synchronising period boundaries to beats (paper A) locks the phase of the dance
    but the dancer's accents may sit anywhere inside the period.

    Returns
    -------
    score : float in [0, 1]
    """
    mb, yb = validate(motion_beats, music_beats)
    if yb.size < 2:
        raise ParameterError("beat_phase_consistency needs at least 2 music beats")
    phase, _ = _phases(mb, yb)
    if phase.size == 0:
        warnings.warn("no motion beats inside the music's beats; returning 0", BeatsyncWarning,
                      stacklevel=2)
        return 0.0
    return float(np.abs(np.mean(np.exp(2j * np.pi * phase))))


def _phases(mb: np.ndarray, yb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mb = mb[(mb >= yb[0]) & (mb < yb[-1])]
    i = np.searchsorted(yb, mb, side="right") - 1
    return (mb - yb[i]) / (yb[i + 1] - yb[i]), np.diff(yb)[i]


def kinematic_phase_offset(motion_beats: Any, music_beats: Any) -> float:
    """Mean lag of the motion beats behind the music beats [s], in ``(-T/2, T/2]``.

    The circular mean of the motion beats' phases inside their beat intervals, times
    the median beat period ``T``. Synchronising with ``phase_offset=-lag``
    (:func:`beatsync.sync.synchronize`) moves the dancer's accents onto the beats.

    Raises
    ------
    ParameterError
        Fewer than 2 music beats, or no motion beat inside the music's beats.
    """
    mb, yb = validate(motion_beats, music_beats)
    if yb.size < 2:
        raise ParameterError("kinematic_phase_offset needs at least 2 music beats")
    phase, _ = _phases(mb, yb)
    if phase.size == 0:
        raise ParameterError("no motion beat falls inside the music's beats: no phase to measure")
    mean = np.angle(np.mean(np.exp(2j * np.pi * phase))) / (2 * np.pi)  # (-0.5, 0.5]
    return float(mean * np.median(np.diff(yb)))


def evaluate_sync(
    motion: Any,
    beats: Any,
    *,
    boundaries: Any = None,
    segment_input: Any = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
    **sync_kwargs: Any,
) -> dict[str, Any]:
    """Synchronise a motion to music beats and score it: one row of a results table.

    Runs :func:`beatsync.segment.segment` (unless ``boundaries`` are given),
    :func:`beatsync.sync.synchronize`, then both alignment scores and the phase
    consistency of the kinematic beats against the music beats *before* (the
    original motion played from music time 0) and *after* synchronisation, and the
    random-offset control of the synchronised motion (:func:`offset_control`), and
    ``aligned_*``: synchronised again with ``phase_offset = -kinematic_phase_offset``
    so that the dancer's accents, not the segmentation's boundaries, land on the beats.
    Motions without positions (plain joint-angle tables) get NaN alignment scores.

    Parameters
    ----------
    motion : Motion
    beats : np.ndarray [s]
        Music beats.
    boundaries : np.ndarray [s], optional
        Period boundaries; default from ``segment(segment_input or motion)``.
    segment_input : Motion, optional
        What to segment if different from ``motion`` (e.g. ``marker_angles(markers)``).
    period_range : (float, float) [s]
        Passed to ``segment``.
    sigma : float [s]
    n_control, seed
        Random-offset control trials and seed.
    **sync_kwargs
        Passed to :func:`~beatsync.sync.synchronize` (``beats_per_period``, ``out_fps``...).

    Returns
    -------
    dict
        ``input_frames``, ``output_frames``, ``periods_available``, ``periods_used``,
        ``beats_per_period``, ``mean_period_s``, ``speed_min``, ``speed_max``,
        ``max_residual_ms``, ``max_residual_frames``, and ``before_/after_/control_``
        ``motion`` / ``music`` alignment and ``before_/after_phase``; plus
        ``result`` (the :class:`~beatsync.sync.SyncResult`).
    """
    from ..sync import synchronize

    yb = check_times(beats, name="beats")
    n_periods = None
    if boundaries is None:
        from ..segment import segment

        seg = segment(motion if segment_input is None else segment_input,
                      period_range=period_range)
        boundaries = seg.boundaries
        n_periods = int(seg.n_periods)
    res = synchronize(motion, boundaries, yb, **sync_kwargs)
    rep = res.report
    row: dict[str, Any] = {
        "input_frames": rep["input_frames"],
        "input_fps": rep["input_fps"],
        "output_frames": rep["output_frames"],
        "periods_available": rep["periods_available"] if n_periods is None else n_periods,
        "periods_used": rep["periods_used"],
        "beats_per_period": rep["beats_per_period"],
        "mean_period_s": rep["mean_motion_period_s"],
        "beat_period_s": rep["beat_period_s"],
        "speed_min": rep["tempo_ratio_range"][0],
        "speed_max": rep["tempo_ratio_range"][1],
        "max_residual_ms": rep["max_abs_residual_ms"],
        "max_residual_frames": rep["max_abs_residual_frames"],
    }
    keys = ("before_motion", "before_music", "before_phase", "after_motion", "after_music",
            "after_phase", "control_motion", "control_music", "phase_offset_s",
            "aligned_motion", "aligned_music")
    try:
        mb_before = _kinematic_beats(motion)
        mb_after = _kinematic_beats(res.motion)
    except ParameterError:  # no positions: a plain joint-angle table
        row.update({k: float("nan") for k in keys})
        row["result"] = res
        return row
    end_before = float(motion.duration)
    end_after = float(res.motion.duration)
    before = alignment_scores(mb_before, yb, sigma=sigma, span=(0.0, min(end_before, yb[-1])))
    after = alignment_scores(mb_after, yb, sigma=sigma, span=(0.0, min(end_after, yb[-1])))
    in_after = yb[yb <= end_after]
    ctrl = offset_control(mb_after, in_after, sigma=sigma, n_trials=n_control, seed=seed)
    # accents on the beat: shift the landing by the measured kinematic lag
    lag = kinematic_phase_offset(mb_after, yb)
    kw = dict(sync_kwargs)
    first = int(kw.pop("first_beat", 0))
    if yb[first] - lag < 0:
        first += 1
    res_al = synchronize(motion, boundaries, yb, phase_offset=-lag, first_beat=first, **kw)
    mb_al = _kinematic_beats(res_al.motion)
    aligned = alignment_scores(
        mb_al, yb, sigma=sigma, span=(0.0, min(float(res_al.motion.duration), yb[-1]))
    )
    row.update(
        {
            "before_motion": before["alignment_motion"],
            "before_music": before["alignment_music"],
            "before_phase": beat_phase_consistency(mb_before, yb),
            "after_motion": after["alignment_motion"],
            "after_music": after["alignment_music"],
            "after_phase": beat_phase_consistency(mb_after, yb),
            "control_motion": ctrl["alignment_motion_mean"],
            "control_music": ctrl["alignment_music_mean"],
            "phase_offset_s": -lag,
            "aligned_motion": aligned["alignment_motion"],
            "aligned_music": aligned["alignment_music"],
        }
    )
    row["result"] = res
    return row


def sync_table(
    clips: dict[str, dict[str, Any]],
    songs: dict[str, dict[str, Any]],
    *,
    period_range: tuple[float, float] = (0.25, 1.25),
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
    paper_frames: dict[tuple[str, str], Any] | None = None,
) -> Any:
    """Synchronise every clip to every song; one table row per pair (paper A, Table 1).

    Parameters
    ----------
    clips : dict
        ``name -> {"motion": Motion, "segment_input": Motion or None, "data": str}``;
        each clip is segmented once (``segment(segment_input or motion)``).
    songs : dict
        ``name -> {"beats": np.ndarray [s], "bpm": float, "data": str}``.
    period_range : (float, float) [s]
    sigma : float [s]
    n_control, seed
        Random-offset control (see :func:`offset_control`).
    paper_frames : dict, optional
        ``(clip, song) -> the paper's number of output frames``; missing pairs are
        reported as ``"n/a"`` (not available), never invented.

    Returns
    -------
    pandas.DataFrame
        Columns: clip, clip data, fps, input frames, song, song data, BPM, periods,
        periods used, beats/period, output frames, paper output frames, max residual
        [frames], alignment before/after/control (``_motion``: averaged over motion
        beats, Siyao et al. 2022; ``_music``: averaged over music beats, Li et al.
        2021), phase consistency before/after, and ``note`` (why a clip has no
        result, e.g. segmentation refused it as not periodic).
    """
    import pandas as pd

    from ..segment import segment

    paper_frames = paper_frames or {}
    rows = []
    for cname, clip in clips.items():
        motion = clip["motion"]
        seg_in = clip.get("segment_input") or motion
        try:
            seg = segment(seg_in, period_range=period_range)
        except ParameterError as exc:  # e.g. refused as not periodic: say so in the table
            for sname, song in songs.items():
                rows.append({"clip": cname, "clip data": clip.get("data", ""),
                             "fps": float(motion.fps), "input frames": int(motion.n_frames),
                             "song": sname, "song data": song.get("data", ""),
                             "BPM": song.get("bpm", float("nan")),
                             "paper output frames": paper_frames.get((cname, sname), "n/a"),
                             "note": f"segmentation refused: {str(exc)[:60]}..."})
            continue
        for sname, song in songs.items():
            r = evaluate_sync(
                motion, song["beats"], boundaries=seg.boundaries, sigma=sigma,
                n_control=n_control, seed=seed,
            )
            rows.append(
                {
                    "clip": cname,
                    "clip data": clip.get("data", ""),
                    "fps": r["input_fps"],
                    "input frames": r["input_frames"],
                    "song": sname,
                    "song data": song.get("data", ""),
                    "BPM": song.get("bpm", float("nan")),
                    "periods": int(seg.n_periods),
                    "periods used": r["periods_used"],
                    "beats/period": r["beats_per_period"],
                    "output frames": r["output_frames"],
                    "paper output frames": paper_frames.get((cname, sname), "n/a"),
                    "max residual [frames]": r["max_residual_frames"],
                    "before_motion": r["before_motion"],
                    "after_motion": r["after_motion"],
                    "control_motion": r["control_motion"],
                    "before_music": r["before_music"],
                    "after_music": r["after_music"],
                    "control_music": r["control_music"],
                    "before_phase": r["before_phase"],
                    "after_phase": r["after_phase"],
                    "phase offset [s]": r["phase_offset_s"],
                    "aligned_motion": r["aligned_motion"],
                    "aligned_music": r["aligned_music"],
                    "note": "",
                }
            )
    return pd.DataFrame(rows)
