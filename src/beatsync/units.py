"""Time bases and validation shared by every stage.

Data contract
-------------
- Event times (beats, period boundaries, motion beats) are 1-D ``float64`` arrays in
  seconds, strictly increasing.
- Frames appear only inside a stage or at I/O; every conversion between frames and
  seconds goes through :func:`frames_to_time` and :func:`time_to_frames`.
- A frame rate ``fps`` is a finite number > 0 [Hz].
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import ParameterError

__all__ = [
    "frames_to_time",
    "time_to_frames",
    "check_fps",
    "check_times",
    "check_finite",
    "check_range",
    "check_positive",
    "MIN_PLAUSIBLE_FPS",
]

#: Frame rates below this [Hz] are refused as a likely frame period in seconds.
MIN_PLAUSIBLE_FPS = 1.0


def check_fps(fps: Any, *, name: str = "fps") -> float:
    """Return ``fps`` as a float after checking it is finite and > 0 [Hz].

    Raises
    ------
    ParameterError
        If ``fps`` is not a finite positive number.
    """
    try:
        value = float(fps)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={fps!r} is not a number; give a frame rate in Hz") from None
    if not np.isfinite(value) or value <= 0:
        raise ParameterError(
            f"{name}={fps!r} must be a finite frame rate > 0 [Hz] "
            "(did you pass a frame period in seconds, or zero?)"
        )
    if value < MIN_PLAUSIBLE_FPS:
        raise ParameterError(
            f"{name}={fps!r} Hz looks like a frame period in seconds, not a frame rate; "
            f"did you mean {name}={1.0 / value:.6g}?"
        )
    return value


def check_positive(value: Any, *, name: str, unit: str, allow_zero: bool = False) -> float:
    """Return ``value`` as a float after checking it is finite and > 0 (or >= 0) [unit].

    Use for durations, tempi, window lengths: anything positive that is not a frame
    rate (see :func:`check_fps`).
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} is not a number [{unit}]") from None
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name}={value!r} must be a finite number {bound} [{unit}]")
    return v


def frames_to_time(frames: Any, *, fps: float) -> np.ndarray:
    """Convert frame indices to times in seconds: ``t = frames / fps``.

    Parameters
    ----------
    frames : array_like [frames]
    fps : float > 0 [Hz]

    Returns
    -------
    times : np.ndarray [s], float64

    Examples
    --------
    >>> frames_to_time([0, 30, 60], fps=60.0)
    array([0. , 0.5, 1. ])
    """
    fps = check_fps(fps)
    return np.asarray(frames, dtype=np.float64) / fps


def time_to_frames(
    times: Any, *, fps: float, round_to_int: bool = True, mode: str = "round"
) -> np.ndarray:
    """Convert times in seconds to frame indices: ``frames = round(t * fps)``.

    Parameters
    ----------
    times : array_like [s]
    fps : float > 0 [Hz]
    round_to_int : bool
        Return integer frames (``int64``); otherwise fractional frames (``float64``).
    mode : {"round", "floor", "ceil"}
        How times between frames become integer frames: the nearest frame, the last
        frame at or before the time, or the first frame at or after it. A tolerance of
        1e-9 frames absorbs floating-point error (``ceil(3 * (1/3) * 3)`` is 3).

    Examples
    --------
    >>> time_to_frames([0.0, 0.5, 1.0], fps=60.0)
    array([ 0, 30, 60])
    """
    fps = check_fps(fps)
    frames = np.asarray(times, dtype=np.float64) * fps
    if not round_to_int:
        return frames
    if mode == "round":
        return np.rint(frames).astype(np.int64)
    if mode == "floor":
        return np.floor(frames + 1e-9).astype(np.int64)
    if mode == "ceil":
        return np.ceil(frames - 1e-9).astype(np.int64)
    raise ParameterError(f"mode={mode!r} must be 'round', 'floor' or 'ceil'")


def check_finite(values: Any, *, name: str) -> np.ndarray:
    """Return ``values`` as a float64 array, refusing NaN or infinite entries."""
    arr = np.asarray(values, dtype=np.float64)
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise ParameterError(
            f"{name} contains {int(bad.sum())} NaN or infinite value(s) "
            f"(first at index {tuple(int(i) for i in idx)}); "
            "fill gaps (e.g. interpolate missing markers) before calling"
        )
    return arr


def check_times(
    times: Any,
    *,
    name: str = "times",
    allow_empty: bool = True,
    duration: float | None = None,
) -> np.ndarray:
    """Validate event times: 1-D, finite, >= 0, strictly increasing, in seconds.

    Parameters
    ----------
    times : array_like [s]
    name : str
        Used in error messages.
    allow_empty : bool
    duration : float, optional [s]
        If given, times beyond it are refused (a hint that frames were passed).

    Raises
    ------
    ParameterError
        With the likely mistake: frames instead of seconds, milliseconds, unsorted.
    """
    arr = np.asarray(times, dtype=np.float64)
    if arr.ndim != 1:
        raise ParameterError(
            f"{name} must be a 1-D array of times in seconds, got shape {arr.shape}"
        )
    if arr.size == 0:
        if not allow_empty:
            raise ParameterError(f"{name} is empty: at least one event time [s] is needed")
        return arr
    arr = check_finite(arr, name=name)
    if arr[0] < 0:
        raise ParameterError(
            f"{name} has a negative time {arr[0]!r}; times are seconds from the start"
        )
    diffs = np.diff(arr)
    if np.any(diffs <= 0):
        i = int(np.argmax(diffs <= 0))
        raise ParameterError(
            f"{name} must be strictly increasing, but {name}[{i + 1}]={arr[i + 1]!r} "
            f"<= {name}[{i}]={arr[i]!r}; sort them and drop duplicates"
        )
    if duration is not None and arr[-1] > duration + 1e-9:
        hint = ""
        if arr[-1] > 2 * duration:
            hint = " (these look like frame indices or milliseconds, not seconds)"
        raise ParameterError(
            f"{name} ends at {arr[-1]:g} s, after the signal's duration {duration:.3f} s{hint}"
        )
    return arr


def check_range(lo: Any, hi: Any, *, name: str, unit: str) -> tuple[float, float]:
    """Validate an interval ``lo < hi``, both finite and > 0, in ``unit``."""
    try:
        lo_f, hi_f = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}=({lo!r}, {hi!r}) must be two numbers [{unit}]") from None
    if not (np.isfinite(lo_f) and np.isfinite(hi_f)) or lo_f <= 0 or hi_f <= 0:
        raise ParameterError(f"{name}=({lo!r}, {hi!r}) must be finite and > 0 [{unit}]")
    if lo_f >= hi_f:
        raise ParameterError(
            f"{name}=({lo!r}, {hi!r}) is reversed or empty: the lower bound must be "
            f"smaller than the upper bound [{unit}]"
        )
    return lo_f, hi_f


def check_whole(value: Any, *, name: str, minimum: int = 0) -> int:
    """Return ``value`` as an int after checking it is a whole number >= ``minimum``.

    Refuses bools, strings and non-integral floats (``2.5`` beats is a mistake, not 2).
    """
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )
    if not ok or not np.isfinite(value) or not float(value).is_integer():
        raise ParameterError(f"{name}={value!r} must be a whole number >= {minimum}")
    if value < minimum:
        raise ParameterError(f"{name}={value!r} must be a whole number >= {minimum}")
    return int(value)


def beat_phase(events: Any, beats: Any) -> np.ndarray:
    """Phase of each event inside the beat interval that holds it, in ``[0, 1)``.

    0 is on a beat, 0.5 half-way to the next. Events before the first beat or at/after
    the last one have no interval and are dropped. Inputs are event times [s], 1-D
    and increasing (checked by the caller: this is a unit conversion, seconds to beats).
    """
    e = np.asarray(events, dtype=np.float64)
    b = np.asarray(beats, dtype=np.float64)
    e = e[(e >= b[0]) & (e < b[-1])]
    i = np.searchsorted(b, e, side="right") - 1
    return (e - b[i]) / (b[i + 1] - b[i])
