"""Music intensity per beat interval, and a synthetic song with loud and quiet parts.

Paper B matches the *intensity* of the dance with that of the music beat by beat.
Music intensity of a beat interval ``[b_i, b_{i+1})`` is its sound pressure level,
the RMS of the samples in dB (re full scale 1.0, floored at ``amin``); for the
search it is z-scored over the song (:func:`music_intensity`).

:func:`drum_song` renders a documented synthetic song for the speed and quality
studies: the drum pattern of :func:`beatsync.synth.audio.drum_pattern` (kick, snare,
hi-hat eighths) at a constant tempo, with a gain that changes every
``section_beats`` beats to a random level in ``level_range_db`` (seeded), so its
intensity varies like verses and choruses. Its beats are exact.

Data contract: audio is mono float ``y`` with ``sr`` [Hz]; beats are 1-D float64
seconds, strictly increasing; intensities are one value per beat interval.

Notebooks: ``notebooks/tab01_speed_motion_graph.ipynb``,
``notebooks/tab02_quality_proxies.ipynb``; paper B section 3.3.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ParameterError
from .motion_beats import zscore
from .units import check_finite, check_positive, check_times

__all__ = [
    "beat_rms_db",
    "music_intensity",
    "track_music_beats",
    "DrumSong",
    "drum_song",
]


def _check_audio(y: Any, sr: Any) -> tuple[np.ndarray, float]:
    sr = check_positive(sr, name="sr", unit="Hz")
    y = check_finite(y, name="audio samples")
    if y.ndim != 1:
        raise ParameterError(
            f"audio must be mono 1-D samples, got shape {y.shape} (mix channels down first)"
        )
    if y.size == 0:
        raise ParameterError("the audio is empty")
    return y, sr


def beat_rms_db(y: Any, sr: float, beats: Any, *, amin: float = 1e-5) -> np.ndarray:
    """Sound pressure level (RMS in dB re 1.0) of each interval between successive beats.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
    sr : float > 0 [Hz]
    beats : np.ndarray [shape=(K+1,)] [s], inside the audio
    amin : float > 0
        RMS floor (silence reads ``20 log10(amin)`` dB, -100 dB by default).

    Returns
    -------
    level : np.ndarray [shape=(K,)] [dB]
    """
    y, sr = _check_audio(y, sr)
    beats = check_times(beats, name="music beats", duration=y.size / sr)
    if beats.size < 2:
        raise ParameterError(
            f"the music has {beats.size} beat(s): at least two are needed for one interval "
            "(is it silence, or too short?)"
        )
    if not amin > 0:
        raise ParameterError(f"amin={amin!r} must be > 0")
    idx = np.clip(np.rint(beats * sr).astype(np.int64), 0, y.size)
    if np.any(np.diff(idx) <= 0):
        raise ParameterError("two music beats fall on the same audio sample")
    cum = np.concatenate([[0.0], np.cumsum(np.asarray(y, dtype=np.float64) ** 2)])
    ms = (cum[idx[1:]] - cum[idx[:-1]]) / np.diff(idx)
    return 20.0 * np.log10(np.maximum(np.sqrt(np.maximum(ms, 0.0)), amin))


def music_intensity(y: Any, sr: float, beats: Any, *, amin: float = 1e-5) -> np.ndarray:
    """Z-scored :func:`beat_rms_db` (zeros, with a warning, if the level is constant)."""
    return zscore(beat_rms_db(y, sr, beats, amin=amin), name="music intensity")


def track_music_beats(
    y: Any, sr: float, *, bpm: float | None = None, method: str = "psf"
) -> np.ndarray:
    """Music beat times [s] from the project's tracker.

    Uses :func:`beatsync.beats.track_beats`; if that module is not installed, falls
    back to :func:`librosa.beat.beat_track` (with ``start_bpm=bpm`` when given).

    Raises
    ------
    ParameterError
        Silence or a signal without beats.
    """
    y, sr = _check_audio(y, sr)
    if bpm is not None:
        bpm = check_positive(bpm, name="bpm", unit="BPM")
    if not np.any(np.abs(y) > 1e-6):
        raise ParameterError("the music is silent: no beats to dance to")
    try:
        from .beats import track_beats  # type: ignore[attr-defined]
    except ImportError:
        track_beats = None
    if track_beats is not None:
        kwargs: dict[str, Any] = {"method": method}
        if bpm is not None:
            kwargs["bpm"] = bpm
        beats = np.asarray(track_beats(y, int(round(sr)), **kwargs).beats, dtype=np.float64)
    else:  # pragma: no cover - only before beatsync.beats exists
        import librosa

        kw = {"start_bpm": bpm} if bpm is not None else {}
        _, beats = librosa.beat.beat_track(
            y=np.asarray(y, dtype=np.float32), sr=int(round(sr)), units="time", **kw
        )
        beats = np.asarray(beats, dtype=np.float64)
    if beats.size < 2:
        raise ParameterError(
            f"the beat tracker found {beats.size} beat(s) in the music: it needs a steady "
            "pulse (give --bpm, or a longer or louder piece)"
        )
    return check_times(beats, name="music beats")


@dataclass(frozen=True)
class DrumSong:
    """A synthetic song with exact beats and known loudness sections.

    Attributes
    ----------
    y : np.ndarray float32
    sr : int [Hz]
    beats : np.ndarray [s]
    bpm : float [bpm]
    gain_db : np.ndarray [shape=(len(beats),)] [dB]
        Gain applied from each beat on.
    """

    y: np.ndarray
    sr: int
    beats: np.ndarray
    bpm: float
    gain_db: np.ndarray

    @property
    def duration(self) -> float:
        return len(self.y) / self.sr


def drum_song(
    duration: float,
    *,
    bpm: float = 100.0,
    sr: int = 22050,
    section_beats: int = 8,
    level_range_db: tuple[float, float] = (-24.0, 0.0),
    seed: int = 0,
    start: float = 0.5,
) -> DrumSong:
    """Render a drum song whose loudness changes every ``section_beats`` beats.

    Parameters
    ----------
    duration : float > 0 [s]
    bpm : float > 0 [bpm]
    sr : int > 0 [Hz]
    section_beats : int >= 1
    level_range_db : (float, float) [dB]
        Range of the random section gains (uniform, seeded).
    seed : int
    start : float >= 0 [s]
        Time of the first beat.

    Returns
    -------
    DrumSong
    """
    from .synth.audio import beat_times, drum_pattern

    duration = check_positive(duration, name="duration", unit="s")
    bpm = check_positive(bpm, name="bpm", unit="BPM")
    if int(section_beats) < 1:
        raise ParameterError(f"section_beats={section_beats!r} must be >= 1")
    lo, hi = (float(v) for v in level_range_db)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi <= 0):
        raise ParameterError(f"level_range_db={level_range_db!r} must be (low, high) <= 0 dB")
    beats = beat_times(bpm, duration=duration, start=start)
    y = drum_pattern(beats, sr=sr, duration=duration, seed=seed).astype(np.float64)
    rng = np.random.default_rng(seed)
    n_sec = int(np.ceil(beats.size / int(section_beats)))
    levels = rng.uniform(lo, hi, size=n_sec)
    gain_db = levels[np.arange(beats.size) // int(section_beats)]
    # gain envelope: constant between beats, 5 ms ramps at changes (no clicks)
    t = np.arange(y.size) / sr
    k = np.clip(np.searchsorted(beats, t, side="right") - 1, 0, beats.size - 1)
    env = 10.0 ** (gain_db[k] / 20.0)
    ramp = max(1, int(0.005 * sr))
    env = np.convolve(np.pad(env, (ramp, ramp), mode="edge"), np.ones(ramp) / ramp, "same")[
        ramp:-ramp
    ]
    y = (y * env).astype(np.float32)
    return DrumSong(y=y, sr=int(sr), beats=beats, bpm=bpm, gain_db=gain_db)
