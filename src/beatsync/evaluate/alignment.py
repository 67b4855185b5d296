"""Dance-music beat alignment scores.

Two incompatible scores are published as "beat alignment score"; both take a Gaussian
``exp(-d^2 / (2 sigma^2))`` of the distance ``d`` [s] to the nearest beat of the other
kind, but average over different sets:

- :func:`beat_alignment_motion` averages over **motion beats** (Li et al. 2021, AIST++
  "BeatAlign"): does every accent of the dance fall on a beat? Skipped beats cost nothing.
- :func:`beat_alignment_music` averages over **music beats** (Siyao et al. 2022,
  Bailando "BAS"): is every beat of the song danced? Extra motion beats cost nothing.

The papers' sigma of 3 frames at 60 fps is ``sigma = 0.05`` s (the default). Beat times
are 1-D float64 seconds, strictly increasing; scores lie in ``[0, 1]``, 0 (with a
warning) for empty input.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError, warn
from ..validation import (
    as_float,
    beat_phase,
    check_fps,
    check_positive,
    check_times,
    frames_to_time,
    nearest,
    time_to_frames,
)

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
#: sigmas beyond a span's ends that a nearest beat may lie (its weight is below 1.2 %)
SPAN_REACH = 3.0


def _checked(motion_beats: Any, music_beats: Any, sigma: Any):
    """``(motion_beats, music_beats, sigma)`` validated (:func:`validate`, sigma [s])."""
    s = check_positive(sigma, name="sigma", unit="s")
    if s >= 1.0:
        raise ParameterError(
            f"sigma={sigma!r} s is wider than a beat: sigma is in seconds, not frames "
            "(the papers' 3 frames at 60 fps is sigma=0.05)"
        )
    return *validate(motion_beats, music_beats), s


def validate(motion_beats: Any, music_beats: Any) -> tuple[np.ndarray, np.ndarray]:
    """Check both beat sequences (1-D increasing seconds); return them as float64."""
    mb = check_times(motion_beats, name="motion_beats")
    yb = check_times(music_beats, name="music_beats")
    return mb, yb


def nearest_distance(events: Any, reference: Any) -> np.ndarray:
    """Distance [s] from each event to the nearest of the increasing ``reference`` times."""
    e = np.asarray(events, dtype=np.float64)
    return np.abs(e - nearest(e, reference))


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
    """Beat alignment averaged over motion beats ``M`` (Li et al. 2021, AIST++ "BeatAlign").

    ``(1/|M|) sum_{t in M} exp(-min_{b in B} (t - b)^2 / (2 sigma^2))``, ``B`` the music
    beats, ``sigma`` [s].

    Examples
    --------
    >>> beat_alignment_motion([0.5, 1.0], [0.0, 0.5, 1.0, 1.5])
    1.0
    """
    mb, yb, sigma = _checked(motion_beats, music_beats, sigma)
    return _score(mb, yb, sigma, "motion beats")


def beat_alignment_music(
    motion_beats: Any, music_beats: Any, *, sigma: float = DEFAULT_SIGMA
) -> float:
    """Beat alignment averaged over music beats ``B`` (Siyao et al. 2022, Bailando "BAS").

    ``(1/|B|) sum_{b in B} exp(-min_{t in M} (b - t)^2 / (2 sigma^2))``.

    Examples
    --------
    >>> round(beat_alignment_music([0.5, 1.0], [0.0, 0.5, 1.0, 1.5]), 3)
    0.5
    """
    mb, yb, sigma = _checked(motion_beats, music_beats, sigma)
    return _score(yb, mb, sigma, "music beats")


def alignment_scores(
    motion_beats: Any,
    music_beats: Any,
    *,
    sigma: float = DEFAULT_SIGMA,
    span: tuple[float, float] | None = None,
) -> dict[str, float]:
    """Both beat alignment scores (``alignment_motion``, ``alignment_music``), the beat counts
    they were computed on and ``sigma_s``. Given a ``span`` [s], only beats inside it are
    averaged (e.g. the time both the dance and the music play); the nearest beat of the
    other kind may lie up to ``SPAN_REACH`` sigmas outside it, so a beat on the span's
    edge danced a frame later still counts.
    """
    mb, yb, sigma = _checked(motion_beats, music_beats, sigma)
    mb_near, yb_near = mb, yb
    if span is not None:
        try:
            lo, hi = span
        except (TypeError, ValueError):
            raise ParameterError(f"span={span!r} must be (start, end) [s]") from None
        lo = as_float(lo, name="span start", unit="s")
        hi = as_float(hi, name="span end", unit="s")
        if not hi > lo:
            raise ParameterError(f"span={span!r} must be (start, end) with end > start [s]")
        r = SPAN_REACH * sigma
        mb_near = mb[(mb >= lo - r) & (mb <= hi + r)]
        yb_near = yb[(yb >= lo - r) & (yb <= hi + r)]
        mb = mb[(mb >= lo) & (mb <= hi)]
        yb = yb[(yb >= lo) & (yb <= hi)]
    return {
        "alignment_motion": _score(mb, yb_near, sigma, "motion beats"),
        "alignment_music": _score(yb, mb_near, sigma, "music beats"),
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
    """Chance level: mean and sd of both scores over ``n_trials`` shifts of all motion beats
    by one offset uniform in ``[-T/2, T/2)`` (``T`` the median music beat period).
    """
    mb, yb, sigma = _checked(motion_beats, music_beats, sigma)
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
    """How consistently motion beats fall at one phase of the music's beat: the vector
    strength ``|mean exp(2 pi i phase)|`` of their phases in the music's beat intervals, 1
    when phase-locked at whatever phase, near 0 for a dance drifting against the music."""
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

    ``landed`` [s]: the music time each event is shown at (e.g. ``target_beats_s +
    residual_ms / 1e3`` of a sync report); ``targets`` [s]: the beat each was meant for.
    Returns ``residual_ms`` and ``max_abs_residual_ms``, and given the motion's ``fps``
    [Hz], ``residual_nearest_frame_ms`` and ``max_abs_residual_frames`` (what a viewer sees).

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
    """:func:`alignment_scores` (``kwargs``: its ``span``) plus ``phase_consistency`` (NaN with
    fewer than two music beats).
    """
    out: dict[str, float] = dict(alignment_scores(motion_beats, music_beats, sigma=sigma, **kwargs))
    mb, yb = validate(motion_beats, music_beats)
    out["phase_consistency"] = beat_phase_consistency(mb, yb) if yb.size >= 2 else float("nan")
    return out
