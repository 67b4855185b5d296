"""Music intensity per beat interval (paper B section 3.3): the sound pressure level of
``[b_i, b_{i+1})``, the RMS in dB re full scale 1.0, z-scored over the song for the search.

Audio is mono float ``y`` at ``sr`` [Hz], checked as the tracker checks it; beats are 1-D
float64 seconds, strictly increasing (:func:`track_music_beats`). A synthetic song with
loudness sections is :func:`beatsync.synth.audio.drum_song` (stages never import ``synth``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .beats import check_audio, track_beats
from .errors import ParameterError
from .motion_beats import zscore
from .validation import check_times, time_to_frames

__all__ = [
    "beat_rms_db",
    "music_intensity",
    "track_music_beats",
]


def beat_rms_db(y: Any, sr: float, beats: Any, *, amin: float = 1e-5) -> np.ndarray:
    """Sound pressure level [dB re 1.0] of each interval between ``K+1`` beats [s]; ``amin``
    floors the RMS (silence reads ``20 log10(amin)``, -100 dB by default)."""
    y, sr = check_audio(y, sr, allow_silent=True)
    beats = check_times(beats, name="music beats", duration=y.size / sr)
    if beats.size < 2:
        raise ParameterError(
            f"the music has {beats.size} beat(s): at least two are needed for one interval "
            "(is it silence, or too short?)"
        )
    if not amin > 0:
        raise ParameterError(f"amin={amin!r} must be > 0")
    idx = np.clip(time_to_frames(beats, fps=sr, mode="round"), 0, y.size)
    if np.any(np.diff(idx) <= 0):
        raise ParameterError("two music beats fall on the same audio sample")
    cum = np.concatenate([[0.0], np.cumsum(y**2)])
    ms = (cum[idx[1:]] - cum[idx[:-1]]) / np.diff(idx)
    return 20.0 * np.log10(np.maximum(np.sqrt(np.maximum(ms, 0.0)), amin))


def music_intensity(y: Any, sr: float, beats: Any, *, amin: float = 1e-5) -> np.ndarray:
    """Z-scored :func:`beat_rms_db` (zeros, with a warning, if the level is constant)."""
    return zscore(beat_rms_db(y, sr, beats, amin=amin), name="music intensity")


def track_music_beats(
    y: Any,
    sr: float,
    *,
    bpm: float | None = None,
    method: str = "psf",
    min_bpm: float | None = None,
    max_bpm: float | None = None,
) -> np.ndarray:
    """Music beat times [s] from :func:`beatsync.beats.track_beats`, at least two (else a
    :class:`ParameterError`, as for silence, audio too short or a bad ``bpm``)."""
    y, sr = check_audio(y, sr)
    given = {"bpm": bpm, "min_bpm": min_bpm, "max_bpm": max_bpm}
    kwargs = {k: v for k, v in given.items() if v is not None}
    beats = track_beats(y, int(round(sr)), method=method, **kwargs).beats
    if beats.size < 2:
        raise ParameterError(
            f"the beat tracker found {beats.size} beat(s) in the music: it needs a steady "
            "pulse (give --bpm, or a longer or louder piece)"
        )
    return beats
