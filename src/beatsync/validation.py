"""Validation of every input of beatsync, and its one frames/seconds conversion.

The lowest layer but ``errors``.

Every public entry of the package checks its inputs here, once; private functions
trust them. The ``check_*`` helpers accept a number written as text (``"2.5"``, as
the checks they replaced did); :func:`as_float` and :func:`as_int` refuse text unless
``text=True`` (a count passed as ``"2"`` is a likely mistake in a call). Each helper
raises :class:`~beatsync.errors.ParameterError` naming the value and the likely
mistake (a period given for a rate, frames for seconds, kHz for Hz, a percentage for a
fraction) and returns the value converted to its working type.

Helpers
-------
- numbers: :func:`as_float`, :func:`as_int`, :func:`check_positive`,
  :func:`check_range`, :func:`check_interval` (one pair);
- rates: :func:`check_fps` [Hz], :func:`check_sample_rate` [Hz], :func:`check_bpm`
  [bpm] (one range, :data:`MIN_BPM`-:data:`MAX_BPM`);
- arrays: :func:`check_finite`, :func:`check_times` [s], :func:`check_audio`;
- parallel runs: :func:`check_workers`, :func:`check_cluster_options`.

Data contract
-------------
- Event times (beats, period boundaries, motion beats) are 1-D ``float64`` arrays in
  seconds, strictly increasing.
- Frames appear only inside a stage or at I/O; every conversion between frames and
  seconds goes through :func:`frames_to_time` and :func:`time_to_frames`.
- A frame rate ``fps`` is a finite number > 0 [Hz].
"""

from __future__ import annotations

import numbers
import os
from typing import Any

import numpy as np

from .errors import ParameterError

__all__ = [
    "frames_to_time",
    "time_to_frames",
    "as_float",
    "as_int",
    "check_fps",
    "check_times",
    "check_finite",
    "check_range",
    "check_positive",
    "check_sample_rate",
    "check_bpm",
    "check_audio",
    "as_float_array",
    "check_interval",
    "MIN_PLAUSIBLE_FPS",
    "MIN_PLAUSIBLE_SR",
    "MIN_BPM",
    "MAX_BPM",
    "beat_phase",
    "MAX_MOTION_FPS",
    "check_motion_fps",
    "default_workers",
    "check_workers",
    "check_cluster_options",
]

#: Frame rates below this [Hz] are refused as a likely frame period in seconds.
MIN_PLAUSIBLE_FPS = 1.0
#: Sample rates below this [Hz] are refused as a likely rate in kHz (``sr=44.1``).
MIN_PLAUSIBLE_SR = 1000.0
#: The one range of plausible tempi [bpm]: below it a beat period in seconds or beats
#: per second was likely given, above it a rate in beats per minute of a sub-beat.
MIN_BPM = 20.0
MAX_BPM = 400.0


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def as_float(
    value: Any, *, name: str, unit: str = "", allow_nonfinite: bool = False, text: bool = False
) -> float:
    """Return ``value`` as a Python float, refusing what is not one finite number.

    Parameters
    ----------
    value : number
        A bool, a string or an array (even of one element) is refused: all are likely
        mistakes in a call.
    name : str
        The parameter's name, used in messages.
    unit : str
        Its unit (``"s"``, ``"Hz"``, ``"bpm"``), used in messages.
    allow_nonfinite : bool
        Accept NaN and +-inf (default: refused).
    text : bool
        Accept a number written as text (``"0.5"``), as when reading a file.

    Raises
    ------
    ParameterError
        Not a number, or not finite.

    Examples
    --------
    >>> as_float(0.5, name="delta", unit="s")
    0.5
    >>> as_float("0.5", name="delta", unit="s", text=True)
    0.5
    """
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} is a bool, not a number{_unit(unit)}")
    if not text and isinstance(value, (str, bytes, np.str_, np.bytes_)):
        raise ParameterError(
            f"{name}={value!r} is text, not a number{_unit(unit)}; pass a number (convert "
            "values read from text first)"
        )
    if isinstance(value, np.ndarray) and value.ndim > 0:
        raise ParameterError(
            f"{name} must be a single number{_unit(unit)}, got an array of shape {value.shape}"
        )
    if isinstance(value, (list, tuple, dict, set)):
        raise ParameterError(
            f"{name}={value!r} must be a single number{_unit(unit)}, not a {type(value).__name__}"
        )
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name}={value!r} is not a number{_unit(unit)}") from None
    if not allow_nonfinite and not np.isfinite(v):
        raise ParameterError(f"{name}={value!r} must be a finite number{_unit(unit)}")
    return v


def as_int(
    value: Any, *, name: str, unit: str = "", minimum: int | None = None, text: bool = False
) -> int:
    """Return ``value`` as an int, refusing fractions (``2.5``) and values below ``minimum``.

    Integral floats (``3.0``) are accepted; text only with ``text=True`` (see
    :func:`as_float`). Raises :class:`ParameterError`.
    """
    v = as_float(value, name=name, unit=unit, text=text)
    if v != np.floor(v):
        raise ParameterError(f"{name}={value!r} must be a whole number{_unit(unit)}")
    i = int(v)
    if minimum is not None and i < minimum:
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}{_unit(unit)}")
    return i


def check_fps(fps: Any, *, name: str = "fps") -> float:
    """Return ``fps`` as a float after checking it is finite and > 0 [Hz].

    Raises
    ------
    ParameterError
        If ``fps`` is not a finite positive number.
    """
    value = as_float(fps, name=name, unit="Hz", allow_nonfinite=True, text=True)
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

    Use for durations, widths, window lengths: anything positive that is not a rate
    (see :func:`check_fps`, :func:`check_sample_rate`, :func:`check_bpm`).
    """
    v = as_float(value, name=name, unit=unit, allow_nonfinite=True, text=True)
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


_KIND_NAMES = {
    "b": "booleans",
    "c": "complex numbers (take .real or abs() first)",
    "U": "strings",
    "S": "bytes",
    "O": "Python objects",
    "M": "dates (datetime64)",
    "m": "time deltas (timedelta64); convert them to seconds first",
    "V": "records (a structured array); select one numeric field",
}


def as_float_array(values: Any, *, name: str, dtype: Any = np.float64) -> np.ndarray:
    """Return ``values`` as a floating-point array, refusing non-numeric data.

    Parameters
    ----------
    values : array_like
        Integers or floats. Booleans, complex numbers, strings, bytes, dates and
        structured records are refused (numeric strings are not parsed: a text column
        usually means a header row or a wrong delimiter).
    name : str
        Used in messages.
    dtype : numpy dtype or None
        The result's dtype; ``None`` keeps a floating array's dtype (no copy) and
        converts integers to float64.

    Raises
    ------
    ParameterError
        Ragged nested lists, or an array of a non-numeric kind.
    """
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError):
        raise ParameterError(
            f"{name} must be a numeric array; nested lists of unequal length (ragged) cannot be one"
        ) from None
    if arr.dtype.kind == "O":
        try:
            if any(v is None or isinstance(v, (str, bytes)) for v in arr.flat):
                raise TypeError
            arr = arr.astype(np.float64)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{name} must be a numeric array, but it holds {_KIND_NAMES['O']} "
                "(None, strings or nested sequences?)"
            ) from None
    if arr.dtype.kind not in "iuf":
        what = _KIND_NAMES.get(arr.dtype.kind, f"values of dtype {arr.dtype}")
        raise ParameterError(f"{name} must be a numeric array, but it holds {what}")
    if dtype is None:
        return arr if arr.dtype.kind == "f" else arr.astype(np.float64)
    return arr.astype(dtype, copy=False)


def check_finite(values: Any, *, name: str, dtype: Any = np.float64) -> np.ndarray:
    """Return ``values`` as a float array, refusing NaN or infinite entries.

    ``dtype=None`` keeps a floating array's dtype (no conversion), see
    :func:`as_float_array`, which also refuses non-numeric arrays.
    """
    arr = as_float_array(values, name=name, dtype=dtype)
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
    arr = as_float_array(times, name=name)
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
            f"{name} has a negative time {float(arr[0])!r}; times are seconds from the start"
        )
    diffs = np.diff(arr)
    if np.any(diffs <= 0):
        i = int(np.argmax(diffs <= 0))
        raise ParameterError(
            f"{name} must be strictly increasing, but time #{i + 1} ({float(arr[i + 1])!r} s) "
            f"<= time #{i} ({float(arr[i])!r} s); sort them and drop duplicates"
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
        lo_f = as_float(lo, name=name, unit=unit, allow_nonfinite=True, text=True)
        hi_f = as_float(hi, name=name, unit=unit, allow_nonfinite=True, text=True)
    except ParameterError:
        raise ParameterError(f"{name}=({lo!r}, {hi!r}) must be two numbers [{unit}]") from None
    if not (np.isfinite(lo_f) and np.isfinite(hi_f)) or lo_f <= 0 or hi_f <= 0:
        raise ParameterError(f"{name}=({lo!r}, {hi!r}) must be finite and > 0 [{unit}]")
    if lo_f >= hi_f:
        raise ParameterError(
            f"{name}=({lo!r}, {hi!r}) is reversed or empty: the lower bound must be "
            f"smaller than the upper bound [{unit}]"
        )
    return lo_f, hi_f


def check_sample_rate(sr: Any, *, name: str = "sr") -> float:
    """Return an audio sample rate as a float after checking it is plausible [Hz].

    A sample rate must be finite, > 0 and at least :data:`MIN_PLAUSIBLE_SR` (1000 Hz):
    a smaller value is most likely a rate in kHz (``sr=44.1``) or a sample period.

    Raises
    ------
    ParameterError
        Not a number, not finite, <= 0, or implausibly small.

    Examples
    --------
    >>> check_sample_rate(22050)
    22050.0
    """
    v = as_float(sr, name=name, unit="Hz", allow_nonfinite=True, text=True)
    if not np.isfinite(v) or v <= 0:
        raise ParameterError(
            f"{name}={sr!r} must be a finite sample rate > 0 [Hz] (a file header saying 0 "
            "is broken: re-export the file)"
        )
    if v < MIN_PLAUSIBLE_SR:
        guess = f"; did you mean {name}={v * 1000:g}?" if v >= 1 else ""
        raise ParameterError(
            f"{name}={sr!r} Hz is implausibly low for audio: a sample rate is given in Hz, "
            f"not kHz{guess}"
        )
    return v


def check_bpm(bpm: Any, *, name: str = "bpm") -> float:
    """Return a tempo as a float after checking it is in [:data:`MIN_BPM`, :data:`MAX_BPM`].

    Raises
    ------
    ParameterError
        Not a number, or outside the one plausible range (20-400 BPM); the message
        names the likely mistake (a beat period in seconds, beats per second).

    Examples
    --------
    >>> check_bpm(120)
    120.0
    """
    v = as_float(bpm, name=name, unit="bpm", allow_nonfinite=True, text=True)
    if not np.isfinite(v):
        raise ParameterError(
            f"{name}={bpm!r} is not a finite number; give a tempo in BPM from "
            f"{MIN_BPM:g} to {MAX_BPM:g}"
        )
    if not MIN_BPM <= v <= MAX_BPM:
        hint = "did you give a beat period in seconds, or beats per second?"
        if v > MAX_BPM:
            hint = "did you give a rate of sub-beats, or a tempo in another unit?"
        elif v <= 0:
            hint = "a tempo is a positive number of beats per minute"
        raise ParameterError(
            f"{name}={bpm!r} is outside the plausible range {MIN_BPM:g}-{MAX_BPM:g} BPM ({hint})"
        )
    return v


def check_audio(
    y: Any,
    sr: Any,
    *,
    name: str = "y",
    min_duration: float | None = None,
    silence_peak: float | None = None,
) -> tuple[np.ndarray, float]:
    """Validate mono audio; return ``(y, sr)`` with ``y`` as a float array, unconverted.

    A float32 (or float64) ``y`` is returned as is, without a copy; integers become
    float64. Call it once at a public entry; private functions trust its result.

    Parameters
    ----------
    y : array_like [shape=(n,)]
        Mono samples, finite.
    sr : float > 0 [Hz]
        See :func:`check_sample_rate`.
    name : str
        Used in messages.
    min_duration : float, optional [s]
        Refuse audio shorter than this (the message gives the length).
    silence_peak : float, optional
        Refuse audio whose peak magnitude is below this (all silent), or that departs
        from its mean by less than this (constant: a DC offset and no sound).

    Raises
    ------
    ParameterError
        Not 1-D (the message says how to mix down), empty, NaN/inf samples, a bad
        sample rate, too short, silent or constant.
    """
    sr_f = check_sample_rate(sr)
    arr = as_float_array(y, name=f"{name} (audio samples)", dtype=None)
    if arr.ndim != 1:
        raise ParameterError(
            f"{name} must be mono (1-D), got shape {arr.shape}; mix down with y.mean(axis=0) "
            "(librosa layout) or y.mean(axis=1) (soundfile layout)"
        )
    if arr.size == 0:
        raise ParameterError(f"{name} is empty: the audio has zero samples")
    # one pass when every sample is finite (the sum is, unless it overflows: then the
    # samples are checked one by one)
    with np.errstate(over="ignore", invalid="ignore"):
        total = arr.sum()
    if not np.isfinite(total) and not np.isfinite(arr).all():
        bad = ~np.isfinite(arr)
        raise ParameterError(
            f"{name} contains {int(bad.sum())} NaN or infinite sample(s) "
            f"(first at sample {int(np.argmax(bad))}); repair or trim the audio"
        )
    if min_duration is not None:
        duration = arr.size / sr_f
        if duration < min_duration:
            raise ParameterError(
                f"the audio is only {duration:.3f} s long ({arr.size} samples at sr={sr_f:g} "
                f"Hz); at least {min_duration:.3g} s is needed (give a longer excerpt, or "
                "check the sample rate)"
            )
    if silence_peak is not None:
        top, bottom = float(arr.max()), float(arr.min())
        peak = max(top, -bottom)  # the largest magnitude, without an array of them
        if not peak >= silence_peak:
            raise ParameterError(
                f"the audio is all silent (peak below {silence_peak:g}): check the file and gain"
            )
        with np.errstate(over="ignore", invalid="ignore"):
            level = float(np.mean(arr, dtype=np.float64))  # float32 sums can overflow
        if not np.isfinite(level):  # so can float64 ones, near 1.8e308
            level = peak * float(np.mean(arr / peak, dtype=np.float64))
        if not max(top - level, level - bottom) >= silence_peak:
            raise ParameterError(
                f"the audio is constant at {level:.6g} (a DC offset, no sound; it varies by "
                f"less than {silence_peak:g}): check the file and the recording chain"
            )
    return arr, sr_f


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


def check_interval(pair: Any, *, name: str, unit: str) -> tuple[float, float]:
    """Validate an interval given as one pair ``(lo, hi)``: see :func:`check_range`.

    Refuses what is not a pair (a single number, three values, a string) with the
    expected form in the message, so callers need no ``lo, hi = pair`` of their own.

    Examples
    --------
    >>> check_interval((0.5, 2.0), name="period_range", unit="s")
    (0.5, 2.0)
    """
    if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
        raise ParameterError(
            f"{name}={pair!r} must be two numbers (lower, upper) [{unit}], e.g. (0.5, 2.0)"
        )
    lo, hi = pair
    return check_range(lo, hi, name=name, unit=unit)


#: Highest motion frame rate accepted by :func:`check_motion_fps` [Hz].
MAX_MOTION_FPS = 2000.0


def check_motion_fps(fps: Any, *, name: str = "fps") -> float:
    """:func:`check_fps` for the frame rate of a motion to be computed, with an upper bound.

    Motion capture runs at a few hundred Hz (high-speed systems at about 2000); a motion
    resampled to a much higher rate fills the memory (a 30 s song at 100 kHz is 3 million
    frames), so rates above :data:`MAX_MOTION_FPS` are refused. (:func:`check_fps` itself
    has no upper bound: it also checks audio sample rates.)
    """
    value = check_fps(fps, name=name)
    if value > MAX_MOTION_FPS:
        raise ParameterError(
            f"{name}={fps!r} Hz is implausibly high for a motion frame rate (at most "
            f"{MAX_MOTION_FPS:g} Hz): is it an audio sample rate, or a rate in another unit?"
        )
    return value


def default_workers() -> int:
    """Workers of a local cluster when none are asked for: one per core."""
    return os.cpu_count() or 1


def check_workers(n_workers: Any) -> int | None:
    """``None`` or a whole number of workers from 1 to 16 per core (at least 64: a typo
    such as 10**12 would start workers until the machine hangs)."""
    most = max(16 * default_workers(), 64)
    if n_workers is not None and (
        isinstance(n_workers, bool)
        or not isinstance(n_workers, numbers.Integral)
        or not 1 <= n_workers <= most
    ):
        raise ParameterError(
            f"--workers={n_workers!r} must be a whole number of workers >= 1 and at most {most} "
            "here; for a larger cluster give its address with --scheduler"
        )
    return None if n_workers is None else int(n_workers)


def check_cluster_options(scheduler: Any, n_workers: Any) -> int | None:
    """Check ``--scheduler`` and ``--workers`` together; return the worker count."""
    n = check_workers(n_workers)
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ParameterError(f"--scheduler={scheduler!r} is not an address (tcp://host:port)")
    if scheduler is not None and n is not None:
        raise ParameterError(
            f"--workers {n} sizes a local cluster; --scheduler {scheduler!r} has its own "
            "workers: give one or the other"
        )
    return n
