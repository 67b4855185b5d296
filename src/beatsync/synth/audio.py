"""Synthetic beat-tracking test signals with exact ground truth.

Data contract
-------------
- Audio is mono ``float32`` ``y`` with its sample rate ``sr`` [Hz].
- Ground-truth beats are 1-D ``float64`` arrays in seconds, strictly increasing,
  rendered sample-exactly: every beat is the onset of a click or of a drum hit.
- Tempo is in BPM.

The test set (:func:`make_beat_test_set`) crosses click tracks and drum patterns
(kick on beats 1 and 3, snare on 2 and 4, hi-hat on every eighth note) at 60, 90,
120, 150 and 180 BPM with five groups: ``clean``, ``drift`` (slow sinusoidal tempo
drift of +-5 %), ``swing`` (off-beat eighths delayed to 2/3 of the beat),
``noise`` (white noise at 10 dB SNR) and ``change`` (an abrupt tempo change halfway).
It stands in for the paper's test music, which is not available.

:func:`drum_song` renders a song for the motion-graph studies (paper B): the drum
pattern of :func:`drum_pattern` at a constant tempo, with a gain that changes every
``section_beats`` beats to a random level in ``level_range_db`` (seeded), so its
intensity varies like verses and choruses. Its beats are exact.

Notebook: ``notebooks/paper_a_sec4_beat_tracking.ipynb``; paper A, section 4.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..validation import (
    check_bpm,
    check_positive,
    check_times,
    frames_to_time,
    time_to_frames,
)

__all__ = [
    "BeatTestItem",
    "beat_times",
    "click_track",
    "drum_pattern",
    "add_noise",
    "make_beat_test_set",
    "DrumSong",
    "drum_song",
    "GROUPS",
    "KINDS",
    "METERS",
    "meter_pattern",
]

GROUPS = ("clean", "drift", "swing", "noise", "change")
#: Meters of :func:`meter_pattern`: beats per bar and eighth notes per beat (2/4 and
#: 3/4 simple, beat = quarter note; 6/8 compound, beat = dotted quarter).
METERS = {"2/4": (2, 2), "3/4": (3, 2), "6/8": (2, 3)}
KINDS = ("click", "drums")


@dataclass(frozen=True)
class BeatTestItem:
    """One synthetic test signal with its exact beats.

    Attributes
    ----------
    name : str
        Unique name, e.g. ``"drums_120_swing"``.
    group : str
        One of :data:`GROUPS`.
    kind : str
        ``"click"`` or ``"drums"``.
    y : np.ndarray [shape=(n,)], float32
    sr : int [Hz]
    beats : np.ndarray [s]
        Ground-truth beat times.
    bpm : float [bpm]
        Nominal tempo (of the first half for the ``change`` group).
    bpm_end : float [bpm]
        Tempo of the second half (equal to ``bpm`` except in the ``change`` group).
    """

    name: str
    group: str
    kind: str
    y: np.ndarray
    sr: int
    beats: np.ndarray
    bpm: float
    bpm_end: float

    @property
    def duration(self) -> float:
        """Length of the signal [s]."""
        return len(self.y) / self.sr


def beat_times(
    bpm: float,
    *,
    duration: float,
    start: float = 0.5,
    drift: float = 0.0,
    bpm_end: float | None = None,
    change_time: float | None = None,
) -> np.ndarray:
    """Beat times of a tempo function, exactly.

    The tempo is ``bpm * (1 + drift * sin(2 pi t / duration))`` (one slow cycle over
    the clip), switching abruptly to ``bpm_end`` at ``change_time`` if given. Beats
    are the times at which the integrated tempo (in beats) passes an integer.

    Parameters
    ----------
    bpm : float [bpm]
    duration : float > 0 [s]
    start : float >= 0 [s]
        Time of the first beat.
    drift : float in [0, 0.5)
        Relative amplitude of the sinusoidal tempo drift.
    bpm_end : float, optional [bpm]
    change_time : float, optional [s]

    Returns
    -------
    beats : np.ndarray [s]
    """
    bpm = check_bpm(bpm)
    duration = check_positive(duration, name="duration", unit="s")
    if not 0.0 <= drift < 0.5:
        raise ParameterError(f"drift={drift!r} must be a relative amplitude in [0, 0.5)")
    if start < 0 or start >= duration:
        raise ParameterError(f"start={start!r} must lie in [0, duration={duration}) [s]")
    fs = 1000.0  # integration grid [Hz]
    t = np.arange(int(np.ceil(duration * fs)) + 1) / fs
    tempo = bpm * (1.0 + drift * np.sin(2 * np.pi * t / duration))
    if bpm_end is not None:
        bpm_end = check_bpm(bpm_end, name="bpm_end")
        tc = duration / 2 if change_time is None else float(change_time)
        tempo = np.where(t < tc, tempo, bpm_end * tempo / bpm)
    # beats elapsed since `start`, by trapezoidal integration of beats per second
    rate = tempo / 60.0
    phase = np.concatenate([[0.0], np.cumsum((rate[1:] + rate[:-1]) / 2) / fs])
    phase -= np.interp(start, t, phase)
    n = np.arange(0, int(np.floor(phase[-1])) + 1)
    beats = np.interp(n, phase, t)
    return beats[beats < duration - 0.05]


def _kick(sr: int) -> np.ndarray:
    t = np.arange(int(0.25 * sr)) / sr
    f = 45.0 + 75.0 * np.exp(-t / 0.03)
    return np.sin(2 * np.pi * np.cumsum(f) / sr) * np.exp(-t / 0.07)


def _snare(sr: int, rng: np.random.Generator) -> np.ndarray:
    t = np.arange(int(0.18 * sr)) / sr
    noise = rng.standard_normal(t.size) * np.exp(-t / 0.05)
    tone = np.sin(2 * np.pi * 185.0 * t) * np.exp(-t / 0.04)
    return 0.5 * noise + 0.5 * tone


def _hihat(sr: int, rng: np.random.Generator) -> np.ndarray:
    t = np.arange(int(0.06 * sr)) / sr
    noise = np.diff(rng.standard_normal(t.size + 1))  # first difference: high-pass
    return 0.5 * noise * np.exp(-t / 0.012)


def _render(times: np.ndarray, template: np.ndarray, n: int, sr: int, gain=1.0) -> np.ndarray:
    """Add ``gain * template`` starting at the sample of each time (sample-exact onsets)."""
    out = np.zeros(n)
    idx = np.rint(np.asarray(times) * sr).astype(np.int64)
    for i in idx[(idx >= 0) & (idx < n)]:
        seg = template[: n - i]
        out[i : i + seg.size] += gain * seg
    return out


def _offbeats(beats: np.ndarray, swing: float) -> np.ndarray:
    if beats.size < 2:
        return np.empty(0)
    return beats[:-1] + swing * np.diff(beats)


def _check_common(beats, sr, duration):
    beats = check_times(beats, name="beats")
    sr_f = check_positive(sr, name="sr", unit="Hz")
    duration = check_positive(duration, name="duration", unit="s")
    return beats, int(round(sr_f)), duration


def click_track(
    beats: np.ndarray,
    *,
    sr: int = 22050,
    duration: float,
    swing: float | None = None,
    click_freq: float = 1000.0,
) -> np.ndarray:
    """Render a click at each beat (and optionally softer clicks off the beat).

    Parameters
    ----------
    beats : np.ndarray [s]
    sr : int > 0 [Hz]
    duration : float > 0 [s]
    swing : float in (0, 1), optional
        If given, a softer, higher click (0.4 amplitude, two octaves up) is added at
        ``beat + swing * interval`` between consecutive beats (0.5 straight eighths,
        2/3 swung eighths).
    click_freq : float > 0 [Hz]

    Returns
    -------
    y : np.ndarray [shape=(round(duration * sr),)], float32
    """
    beats, sr, duration = _check_common(beats, sr, duration)
    n = int(round(duration * sr))
    t = np.arange(int(0.03 * sr)) / sr
    click = np.sin(2 * np.pi * click_freq * t) * np.exp(-t / 0.006)
    y = _render(beats, click, n, sr)
    if swing is not None:
        high = np.sin(2 * np.pi * 4 * click_freq * t) * np.exp(-t / 0.004)
        y += _render(_offbeats(beats, swing), high, n, sr, gain=0.4)
    return (0.5 * y / max(np.max(np.abs(y)), 1e-12)).astype(np.float32)


def drum_pattern(
    beats: np.ndarray,
    *,
    sr: int = 22050,
    duration: float,
    swing: float = 0.5,
    offbeat_gain: float = 0.5,
    seed: int = 0,
) -> np.ndarray:
    """Render a rock drum pattern on the given beats.

    Kick on beats 1 and 3 (even beat indices), snare on 2 and 4, hi-hat on every
    beat and, played softer (``offbeat_gain``, as drummers accent the beat), on the
    off-beat eighth at ``beat + swing * interval``.

    Parameters
    ----------
    beats : np.ndarray [s]
    sr : int > 0 [Hz]
    duration : float > 0 [s]
    swing : float in (0, 1)
        Position of the off-beat eighth inside the beat (0.5 straight, 2/3 swung).
    offbeat_gain : float >= 0
        Amplitude of the off-beat hi-hat relative to the on-beat one.
    seed : int
        Seed of the noise in the snare and hi-hat sounds.

    Returns
    -------
    y : np.ndarray [shape=(round(duration * sr),)], float32
    """
    beats, sr, duration = _check_common(beats, sr, duration)
    if not 0.0 < swing < 1.0:
        raise ParameterError(f"swing={swing!r} must be a fraction of the beat in (0, 1)")
    rng = np.random.default_rng(seed)
    n = int(round(duration * sr))
    y = _render(beats[0::2], _kick(sr), n, sr, 1.0)
    y += _render(beats[1::2], _snare(sr, rng), n, sr, 0.8)
    hat = _hihat(sr, rng)
    y += _render(beats, hat, n, sr, 1.0)
    y += _render(_offbeats(beats, swing), hat, n, sr, offbeat_gain)
    return (0.5 * y / max(np.max(np.abs(y)), 1e-12)).astype(np.float32)


def meter_pattern(
    beats: np.ndarray,
    *,
    meter: str,
    sr: int = 22050,
    duration: float,
    seed: int = 0,
) -> np.ndarray:
    """Render a drum pattern in a meter, with eighth-note subdivisions and exact beats.

    The first beat of every bar gets a kick (gain 1), the other beats a snare (0.6);
    a hi-hat plays every eighth note: on the beats at gain 0.5, between them at 0.3
    (``METERS[meter][1]`` eighths per beat: 2 in 2/4 and 3/4, 3 in 6/8). ``beats`` are
    the beat (tactus) times: quarter notes in 2/4 and 3/4, dotted quarters in 6/8.

    Parameters
    ----------
    beats : np.ndarray [s]
    meter : {"2/4", "3/4", "6/8"}
    sr : int > 0 [Hz]
    duration : float > 0 [s]
    seed : int
        Seed of the noise in the snare and hi-hat sounds.

    Returns
    -------
    y : np.ndarray [shape=(round(duration * sr),)], float32
    """
    if meter not in METERS:
        raise ParameterError(f"meter={meter!r} is unknown; choose from {sorted(METERS)}")
    beats, sr, duration = _check_common(beats, sr, duration)
    per_bar, eighths = METERS[meter]
    rng = np.random.default_rng(seed)
    n = int(round(duration * sr))
    down = np.arange(beats.size) % per_bar == 0
    y = _render(beats[down], _kick(sr), n, sr, 1.0)
    y += _render(beats[~down], _snare(sr, rng), n, sr, 0.6)
    hat = _hihat(sr, rng)
    y += _render(beats, hat, n, sr, 0.5)
    for k in range(1, eighths):
        y += _render(_offbeats(beats, k / eighths), hat, n, sr, 0.3)
    return (0.5 * y / max(np.max(np.abs(y)), 1e-12)).astype(np.float32)


def add_noise(y: np.ndarray, *, snr_db: float, seed: int = 0) -> np.ndarray:
    """Add white Gaussian noise at ``snr_db`` [dB] relative to the mean power of ``y``."""
    y = np.asarray(y, dtype=np.float64)
    power = float(np.mean(y**2))
    if power <= 0:
        raise ParameterError("cannot set an SNR on an all-silent signal")
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(y.size) * np.sqrt(power / 10 ** (snr_db / 10))
    out = y + noise
    return (0.5 * out / np.max(np.abs(out))).astype(np.float32)


def _second_tempo(bpm: float) -> float:
    """Tempo after the abrupt change: +1/3 for slow tempi, -1/4 for fast ones."""
    return bpm * 4 / 3 if bpm <= 120 else bpm * 3 / 4


def make_beat_test_set(
    *,
    sr: int = 22050,
    duration: float = 30.0,
    bpms: Sequence[float] = (60, 90, 120, 150, 180),
    kinds: Sequence[str] = KINDS,
    groups: Sequence[str] = GROUPS,
    snr_db: float = 10.0,
    drift: float = 0.05,
    swing: float = 2 / 3,
    seed: int = 0,
) -> list[BeatTestItem]:
    """Build the synthetic beat-tracking test set.

    Parameters
    ----------
    sr : int > 0 [Hz]
    duration : float > 0 [s]
        Length of every item.
    bpms : sequence of float [bpm]
    kinds : sequence of {"click", "drums"}
    groups : sequence of {"clean", "drift", "swing", "noise", "change"}
    snr_db : float [dB]
        SNR of the ``noise`` group.
    drift : float
        Relative amplitude of the tempo drift of the ``drift`` group (0.05 = +-5 %).
    swing : float
        Off-beat position of the ``swing`` group (2/3 = triplet swing).
    seed : int
        Seed of the first-beat offsets and of all noise.

    Returns
    -------
    items : list of BeatTestItem
        In the order kinds x groups x bpms.

    Examples
    --------
    >>> items = make_beat_test_set(duration=10.0, bpms=[120], kinds=["click"])
    >>> [it.name for it in items][:2]
    ['click_120_clean', 'click_120_drift']
    """
    sr_i = int(round(check_positive(sr, name="sr", unit="Hz")))
    duration = check_positive(duration, name="duration", unit="s")
    if duration < 4.0:
        raise ParameterError(f"duration={duration!r} s is too short for a test item (>= 4 s)")
    for k in kinds:
        if k not in KINDS:
            raise ParameterError(f"unknown kind {k!r}; choose from {KINDS}")
    for g in groups:
        if g not in GROUPS:
            raise ParameterError(f"unknown group {g!r}; choose from {GROUPS}")
    rng = np.random.default_rng(seed)
    items = []
    for kind in kinds:
        for group in groups:
            for bpm in bpms:
                bpm = check_bpm(bpm)
                start = 0.2 + float(rng.uniform(0.0, 0.3))
                item_seed = int(rng.integers(2**31))
                bpm_end = _second_tempo(bpm) if group == "change" else bpm
                beats = beat_times(
                    bpm,
                    duration=duration,
                    start=start,
                    drift=drift if group == "drift" else 0.0,
                    bpm_end=bpm_end if group == "change" else None,
                )
                sw = swing if group == "swing" else 0.5
                if kind == "click":
                    y = click_track(
                        beats, sr=sr_i, duration=duration, swing=sw if group == "swing" else None
                    )
                else:
                    y = drum_pattern(beats, sr=sr_i, duration=duration, swing=sw, seed=item_seed)
                if group == "noise":
                    y = add_noise(y, snr_db=snr_db, seed=item_seed + 1)
                name = f"{kind}_{bpm:g}_{group}"
                items.append(BeatTestItem(name, group, kind, y, sr_i, beats, bpm, bpm_end))
    return items


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
        """Length of the song [s]."""
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
        Range of the random section gains (uniform, seeded), both <= 0 dB.
    seed : int
    start : float >= 0 [s]
        Time of the first beat.

    Returns
    -------
    DrumSong
        The gain is constant between beats, with 5 ms ramps at changes (no clicks).
    """
    duration = check_positive(duration, name="duration", unit="s")
    bpm = check_bpm(bpm)
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
    t = frames_to_time(np.arange(y.size), fps=sr)
    k = np.clip(np.searchsorted(beats, t, side="right") - 1, 0, beats.size - 1)
    env = 10.0 ** (gain_db[k] / 20.0)
    ramp = max(1, int(time_to_frames(0.005, fps=sr, mode="floor")))
    env = np.convolve(np.pad(env, (ramp, ramp), mode="edge"), np.ones(ramp) / ramp, "same")[
        ramp:-ramp
    ]
    y = (y * env).astype(np.float32)
    return DrumSong(y=y, sr=int(sr), beats=beats, bpm=bpm, gain_db=gain_db)
