"""Dance-music beat alignment scores.

Two incompatible scores are published under the name "beat alignment score"; both
compare motion beats (kinematic beats of the dance) with music beats through a
Gaussian of the distance to the nearest beat of the other kind, but they average
over different sets:

- :func:`beat_alignment_motion` averages over **motion beats**: for every motion
  beat, how close is the nearest music beat? This is the score as written in Li et
  al. 2021 (AIST++ / FACT, "AI Choreographer", the BeatAlign equation over the
  kinematic beats; their ``tools/calculate_beat_scores.py`` loops over the motion
  beats too). It asks whether every accent of the dance falls on a beat; a dance
  that skips beats is not penalised.
- :func:`beat_alignment_music` averages over **music beats**: for every music beat,
  how close is the nearest motion beat? This is the score of Siyao et al. 2022
  (Bailando, "BAS"; their ``utils/beat_align_score.py`` loops over the music beats).
  It asks whether every beat of the song is danced; a dance with many extra motion
  beats is not penalised.

Both use ``exp(-d^2 / (2 sigma^2))`` with ``d`` the distance to the nearest beat
[s]; the papers' sigma of 3 frames at 60 fps is ``sigma = 0.05`` s (default here).
Every table of this project says which of the two it reports; :func:`alignment_scores`
returns both.

Motion beats are given as times (e.g. from :func:`beatsync.motion_beats.kinematic_beats`,
local minima of smoothed joint speed); this module never runs a stage (mir_eval style:
:func:`validate`, the metrics, and :func:`evaluate` returning all of them). Also here:
:func:`beat_phase_consistency` (is the dance phase-locked to the music?),
:func:`offset_control` (chance level by random offsets of the motion beats) and
:func:`sync_residuals` (how far synchronised boundaries land from their beats).
What runs the pipeline for the paper's tables is in :mod:`beatsync.study.paper_a_sync`.

Data contract
-------------
Beat times are 1-D float64 arrays in seconds, strictly increasing (as in
``mir_eval.beat``). Scores lie in ``[0, 1]``; 1 means every beat of the averaged set
sits exactly on a beat of the other set. Empty input is degenerate but legal: a
:class:`~beatsync.errors.BeatsyncWarning` is issued and the score is 0.

Notebooks: ``notebooks/paper_a_tab01_frame_counts.ipynb`` (alignment before/after sync),
``notebooks/paper_a_fig03_animation_frames.ipynb`` (residuals).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError, warn
from ..validation import beat_phase, check_fps, check_times, frames_to_time, time_to_frames

__all__ = [
    "validate",
    "nearest_distance",
    "beat_alignment_motion",
    "beat_alignment_music",
    "alignment_scores",
    "offset_control",
    "beat_phase_consistency",
    "sync_residuals",
    "evaluate",
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
        warn(
            f"no {what} to score (motion beats: averaged={averaged.size}, other={other.size}); "
            "returning 0",
            stacklevel=3,
        )
        return 0.0
    d = nearest_distance(averaged, other)
    return float(np.mean(np.exp(-(d * d) / (2.0 * sigma * sigma))))


def beat_alignment_motion(
    motion_beats: Any, music_beats: Any, *, sigma: float = DEFAULT_SIGMA
) -> float:
    """Beat alignment averaged over motion beats (Li et al. 2021, AIST++ "BeatAlign").

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
    """Beat alignment averaged over music beats (Siyao et al. 2022, Bailando "BAS").

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
    phase = beat_phase(mb, yb)
    if phase.size == 0:
        warn("no motion beats inside the music's beats; returning 0", stacklevel=2)
        return 0.0
    return float(np.abs(np.mean(np.exp(2j * np.pi * phase))))


def sync_residuals(landed: Any, targets: Any, *, fps: float | None = None) -> dict[str, Any]:
    """How far synchronised events land from the beats they were meant for.

    Parameters
    ----------
    landed : np.ndarray [shape=(n,)] [s]
        Music time at which each event (period boundary, motion beat) is shown, e.g.
        ``np.asarray(report["target_beats_s"]) + np.asarray(report["residual_ms"]) / 1e3``.
    targets : np.ndarray [shape=(n,)] [s]
        The beat (or beat plus phase offset) each event was meant for.
    fps : float > 0, optional [Hz]
        Frame rate of the synchronised motion: also the residual of the frame
        nearest to each landing (what a viewer sees).

    Returns
    -------
    dict
        ``residual_ms`` (landed - target), ``max_abs_residual_ms``, and with ``fps``:
        ``residual_nearest_frame_ms``, ``max_abs_residual_frames``.

    Raises
    ------
    ParameterError
        Different lengths, not times, a bad ``fps``.

    Examples
    --------
    >>> round(sync_residuals([1.0, 2.001], [1.0, 2.0])["max_abs_residual_ms"], 9)
    1.0
    """
    x = check_times(landed, name="landed")
    t = check_times(targets, name="targets")
    if x.shape != t.shape:
        raise ParameterError(
            f"landed has {x.size} times but targets {t.size}: one target per landed event"
        )
    res = (x - t) * 1e3
    out: dict[str, Any] = {
        "residual_ms": res,
        "max_abs_residual_ms": float(np.abs(res).max()) if res.size else 0.0,
    }
    if fps is not None:
        fps = check_fps(fps)
        near = (frames_to_time(time_to_frames(x, fps=fps), fps=fps) - t) * 1e3
        out["residual_nearest_frame_ms"] = near
        out["max_abs_residual_frames"] = float(np.abs(near).max() * fps / 1e3) if near.size else 0.0
    return out


def evaluate(
    motion_beats: Any, music_beats: Any, *, sigma: float = DEFAULT_SIGMA, **kwargs: Any
) -> dict[str, float]:
    """Every alignment metric of motion beats against music beats.

    Parameters
    ----------
    motion_beats, music_beats : np.ndarray [s]
    sigma : float > 0 [s]
    **kwargs
        ``span`` for :func:`alignment_scores`.

    Returns
    -------
    dict
        :func:`alignment_scores` plus ``phase_consistency`` (NaN with fewer than two
        music beats).
    """
    out: dict[str, float] = dict(alignment_scores(motion_beats, music_beats, sigma=sigma, **kwargs))
    yb = validate(motion_beats, music_beats)[1]
    out["phase_consistency"] = (
        beat_phase_consistency(motion_beats, music_beats) if yb.size >= 2 else float("nan")
    )
    return out
