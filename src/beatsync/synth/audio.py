"""Synthetic beat-tracking test signals with exact ground truth.

Audio is mono ``float32`` at ``sr`` [Hz]; beats are 1-D ``float64`` seconds, every one
the onset of a click or a drum hit (sample-exact). The test set (:func:`make_beat_test_set`,
standing in for the paper's test music) crosses click tracks and drum patterns at 60-180
BPM with five :data:`GROUPS`: ``clean``, ``drift`` (sinusoidal tempo drift of +-5 %),
``swing`` (off-beat eighths at 2/3 of the beat), ``noise`` (white noise at 10 dB SNR) and
``change`` (an abrupt tempo change halfway). :func:`drum_song`, for paper B's studies, has
a gain that changes every few beats, like verses and choruses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..validation import (
    check_bpm,
    check_choice,
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
    """One synthetic test signal (``name`` e.g. ``"drums_120_swing"``) with its exact
    ``beats`` [s]; ``bpm`` [bpm] is the tempo of the first half and ``bpm_end`` of the
    second (equal but in the ``change`` group).
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
    """Beat times [s] of a tempo function, exactly.

    The tempo is ``bpm * (1 + drift * sin(2 pi t / duration))`` (``drift`` in [0, 0.5)),
    switching abruptly to ``bpm_end`` at ``change_time`` (default: halfway) if given; the
    first beat is at ``start`` [s], the others where the integrated tempo passes an integer.
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
    """A click at each beat (float32, ``round(duration * sr)`` samples); given ``swing``, a
    softer click two octaves up at ``beat + swing * interval`` (0.5 straight, 2/3 swung).
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
    """A rock drum pattern on ``beats`` (float32): kick on beats 1 and 3, snare on 2 and 4,
    hi-hat on every beat and, ``offbeat_gain`` softer, at ``beat + swing * interval``.
    ``seed`` draws the noise of the snare and hi-hat.
    """
    beats, sr, duration = _check_common(beats, sr, duration)
    if not 0.0 < swing < 1.0:
        raise ParameterError(f"swing={swing!r} must be a fraction of the beat in (0, 1)")
    down = np.arange(beats.size) % 2 == 0
    return _drums(beats, down, [swing], (0.8, 1.0, offbeat_gain), sr, duration, seed)


def meter_pattern(
    beats: np.ndarray,
    *,
    meter: str,
    sr: int = 22050,
    duration: float,
    seed: int = 0,
) -> np.ndarray:
    """A drum pattern in ``meter`` (:data:`METERS`; ``beats`` the tactus), float32: a kick on
    the first beat of every bar, snares on the others, a hi-hat on every eighth.
    """
    check_choice(meter, sorted(METERS), name="meter")
    beats, sr, duration = _check_common(beats, sr, duration)
    per_bar, eighths = METERS[meter]
    down = np.arange(beats.size) % per_bar == 0
    offsets = [k / eighths for k in range(1, eighths)]
    return _drums(beats, down, offsets, (0.6, 0.5, 0.3), sr, duration, seed)


def _drums(beats, down, offsets, gains, sr, duration, seed) -> np.ndarray:
    """Kick on the ``down`` beats, snare on the others, hi-hat on every beat and at each
    offset [beats]; ``gains`` of the snare, the hi-hat and the off-beat hi-hats."""
    snare_gain, hat_gain, offbeat_gain = gains
    rng = np.random.default_rng(seed)
    n = int(round(duration * sr))
    y = _render(beats[down], _kick(sr), n, sr, 1.0)
    y += _render(beats[~down], _snare(sr, rng), n, sr, snare_gain)
    hat = _hihat(sr, rng)
    y += _render(beats, hat, n, sr, hat_gain)
    for offset in offsets:
        y += _render(_offbeats(beats, offset), hat, n, sr, offbeat_gain)
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
    """The synthetic beat-tracking test set, in the order kinds x groups x bpms; ``snr_db``
    [dB], ``drift`` and ``swing`` set their groups, ``seed`` draws first beats and noise.

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
    for what, values, known in (("kind", kinds, KINDS), ("group", groups, GROUPS)):
        for v in values:  # the first unknown one, in the order given
            check_choice(v, known, name=what)
    rng = np.random.default_rng(seed)
    items = []
    for kind in kinds:
        for group in groups:
            for bpm in bpms:
                bpm = check_bpm(bpm)
                start = 0.2 + float(rng.uniform(0.0, 0.3))
                item_seed = int(rng.integers(2**31))
                bpm_end = bpm
                if group == "change":  # +1/3 for slow tempi, -1/4 for fast ones
                    bpm_end = bpm * 4 / 3 if bpm <= 120 else bpm * 3 / 4
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
    """A synthetic song with exact ``beats`` [s] and the gain [dB] applied from each beat on."""

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
    """A drum song whose loudness changes every ``section_beats`` beats, to a level drawn
    uniformly (seeded) from ``level_range_db`` [dB] (both <= 0), with 5 ms ramps.
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
    padded = np.pad(env, (ramp, ramp), mode="edge")
    env = np.convolve(padded, np.ones(ramp) / ramp, "same")[ramp:-ramp]
    y = (y * env).astype(np.float32)
    return DrumSong(y=y, sr=int(sr), beats=beats, bpm=bpm, gain_db=gain_db)
