"""How many music beats a motion period (or motion beat) spans, and where accents sit.

- :func:`beats_per_period`: ``m = round(P / b)`` (paper A's reading); with meters, a
  count that respects both the dance's (a multiple of its motion beats per period, or
  that halved: a 3-beat waltz step spans 3 or 6 beats, never 5) and the music's
  (dividing the bar or whole bars). When none fits both within x2 of ``P / b``, the
  dance's wins and the report says the meters do not fit.
- :func:`beats_per_unit`: ``m`` for the median interval and proportional whole counts
  for the others (a missed motion beat leaves an interval twice as long).
- :func:`accent_lag`: the mean lag of motion beats behind music beats, for
  ``land="accents"``.

Times in seconds; counts in whole beats.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validation import as_int, beat_phase, check_positive, check_times

__all__ = [
    "BeatCount",
    "accent_lag",
    "beats_per_period",
    "beats_per_unit",
    "choose_count",
    "count_or_none",
    "lag_of",
]

#: farthest a meter-respecting count may be from the plain rule, as a ratio
METER_REACH = 2.0


@dataclass(frozen=True)
class BeatCount:
    """A choice of ``m`` beats per period (or motion beat), the ``rule`` that chose it,
    the ``ideal`` ratio ``P / b``, whether it respects both meters (``meter_fit``, None
    without meters) and the ``note`` saying why they do not fit."""

    m: int
    rule: str
    ideal: float
    meter_fit: bool | None = None
    note: str = ""


def count_or_none(value: Any, name: str) -> int | None:
    """A count given by the user (an int >= 1; ParameterError naming it), or None."""
    return None if value is None else as_int(value, name=name, minimum=1)


def _candidates(dance: int | None, bar: int | None, limit: int) -> list[int]:
    """Counts respecting the dance's meter (multiples of it, or it halved by 2s) and
    the bar (dividing it, or whole bars), up to ``limit``."""
    out = []
    for m in range(1, limit + 1):
        halved = dance is not None and dance % m == 0 and (dance // m) & (dance // m - 1) == 0
        dance_ok = dance is None or m % dance == 0 or halved
        bar_ok = bar is None or m % bar == 0 or bar % m == 0
        if dance_ok and bar_ok:
            out.append(m)
    return out


def _nearest(cands: list[int], ideal: float) -> int:
    # nearest on a log scale (3 vs 6 beats are equally far from 4.24); ties to the larger
    return min(cands, key=lambda m: (abs(np.log(m / ideal)), -m))


def choose_count(ideal: float, *, dance: int | None = None, bar: int | None = None) -> BeatCount:
    """:func:`beats_per_period` on checked inputs (``ideal = P / b > 0``)."""
    plain = max(1, int(np.rint(ideal)))
    if dance is None and bar is None:
        return BeatCount(plain, "round(P / b)", ideal)
    limit = max(2 * plain + 2, 2 * (dance or 1), 2 * (bar or 1))
    both = [
        m for m in _candidates(dance, bar, limit) if abs(np.log(m / ideal)) <= np.log(METER_REACH)
    ]
    if plain in both:  # the plain rule already respects the meters
        return BeatCount(plain, "round(P / b), fits the meter", ideal, True)
    if both:
        return BeatCount(_nearest(both, ideal), "meter", ideal, True)
    # the meters do not fit: keep the dance's own meter (its steps stay whole)
    own = _candidates(dance, None, limit) if dance is not None else _candidates(None, bar, limit)
    m = _nearest(own, ideal)
    note = (
        f"the dance's meter ({dance} motion beats per period) and the music's "
        f"({bar} beats per bar) do not fit within x{METER_REACH:g} of the tempo ratio "
        f"{ideal:.2f}: {m} beats per period keeps the dance's steps whole but not its "
        "bars on the music's bars"
        if dance is not None and bar is not None
        else f"no count fitting the meter is within x{METER_REACH:g} of {ideal:.2f}"
    )
    return BeatCount(m, "meter", ideal, False, note)


def beats_per_period(
    mean_period: float,
    beats: Any,
    *,
    override: int | None = None,
    dance_beats_per_period: int | None = None,
    beats_per_bar: int | None = None,
) -> int:
    """Number of music beats one motion period spans (see the module docstring): the
    count nearest ``P / b`` on a log scale among those that respect the meters given.

    ``mean_period`` [s] is ``P``; ``beats`` [s] (at least 2) give ``b``, their median
    interval; ``override`` replaces the rule; ``dance_beats_per_period`` (3 for a waltz
    step) and ``beats_per_bar`` are the meters. ParameterError on a bad value.

    Examples
    --------
    >>> beats_per_period(1.0, np.arange(0, 10, 0.5))
    2
    >>> beats_per_period(2.1, np.arange(0, 10, 0.5), dance_beats_per_period=3, beats_per_bar=3)
    3
    """
    if override is not None:
        return as_int(override, name="beats_per_period", minimum=1)
    beats = check_times(beats, name="beats")
    if beats.size < 2:
        raise ParameterError(
            f"need at least 2 music beats to know the beat period, got {beats.size}; "
            "the music may be silent or have no detectable beats (give --bpm or a beats file)"
        )
    mean_period = check_positive(mean_period, name="mean_period", unit="s")
    dance = count_or_none(dance_beats_per_period, "dance_beats_per_period")
    bar = count_or_none(beats_per_bar, "beats_per_bar")
    beat_period = float(np.median(np.diff(beats)))
    return choose_count(mean_period / beat_period, dance=dance, bar=bar).m


def beats_per_unit(intervals: np.ndarray, m: int) -> np.ndarray:
    """Whole music beats for each interval between motion events (checked inputs):
    ``max(1, round(m * interval / median))`` (see the module docstring)."""
    med = float(np.median(intervals))
    return np.maximum(1, np.rint(m * intervals / med)).astype(np.int64)


def accent_lag(motion_beats: Any, music_beats: Any) -> float:
    """Mean lag [s] of ``motion_beats`` [s] behind ``music_beats`` [s] (at least 2), in
    ``(-T/2, T/2]``: the circular mean of their phases in the beat intervals, times the
    median beat period ``T``. ``phase_offset=-lag`` puts the accents on the beats
    (``land="accents"``). ParameterError when no motion beat falls inside the beats.

    Examples
    --------
    >>> round(accent_lag(np.arange(0.6, 5, 0.5), np.arange(0.5, 6, 0.5)), 3)
    0.1
    """
    mb = check_times(motion_beats, name="motion_beats")
    yb = check_times(music_beats, name="music_beats")
    if yb.size < 2:
        raise ParameterError("accent_lag needs at least 2 music beats to know the beat period")
    return lag_of(mb, yb)


def lag_of(mb: np.ndarray, yb: np.ndarray) -> float:
    """:func:`accent_lag` on checked inputs."""
    phase = beat_phase(mb, yb)
    if phase.size == 0:
        raise ParameterError(
            "no motion beat falls inside the music's beats: no accent phase to measure "
            "(is the motion still, or the music after it?)"
        )
    mean = np.angle(np.mean(np.exp(2j * np.pi * phase))) / (2 * np.pi)  # (-0.5, 0.5]
    return float(mean * np.median(np.diff(yb)))
