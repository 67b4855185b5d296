"""Checks of every input, once at the public boundary, and the frames/seconds conversion.

The lowest layer but ``errors``. Each helper raises
:class:`~beatsync.errors.ParameterError` naming the value and the likely mistake (a
period for a rate, frames for seconds, kHz for Hz) and returns the value converted.
The ``check_*`` helpers accept a number written as text (``"2.5"``); :func:`as_float`
and :func:`as_int` only with ``text=True``. Event times are 1-D float64 seconds,
strictly increasing; frames and seconds convert only through :func:`frames_to_time`
and :func:`time_to_frames`.
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
    "check_choice",
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
    "nearest",
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
    """Return ``value`` as a float, refusing bools, text (unless ``text``), arrays, NaN/inf."""
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} is a bool, not a number{_unit(unit)}")
    if not text and isinstance(value, (str, bytes, np.str_, np.bytes_)):
        raise ParameterError(
            f"{name}={value!r} is text, not a number{_unit(unit)}; pass a number (convert "
            "values read from text first)"
        )
    if isinstance(value, (list, tuple, dict, set)) or getattr(value, "ndim", 0) > 0:
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
    """Return ``value`` as an int, refusing fractions (``2.5``) and values below ``minimum``."""
    v = as_float(value, name=name, unit=unit, text=text)
    if v != np.floor(v):
        raise ParameterError(f"{name}={value!r} must be a whole number{_unit(unit)}")
    i = int(v)
    if minimum is not None and i < minimum:
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}{_unit(unit)}")
    return i


def check_choice(value: Any, options: Any, *, name: str) -> str:
    """Return ``value`` if it is one of the strings ``options``, else refuse it naming them."""
    options = tuple(options)
    if not isinstance(value, str) or value not in options:
        raise ParameterError(f"{name}={value!r} must be one of {', '.join(map(repr, options))}")
    return value


def check_fps(fps: Any, *, name: str = "fps") -> float:
    """Return ``fps`` [Hz] as a float: finite, > 0, not a period in seconds (< 1 Hz)."""
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
    """Return ``value`` as a float: finite and > 0 (or >= 0) [unit]; for anything not a rate."""
    v = as_float(value, name=name, unit=unit, allow_nonfinite=True, text=True)
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name}={value!r} must be a finite number {bound} [{unit}]")
    return v


def frames_to_time(frames: Any, *, fps: float) -> np.ndarray:
    """Convert frame indices to times [s]: ``t = frames / fps``."""
    fps = check_fps(fps)
    return np.asarray(frames, dtype=np.float64) / fps


def time_to_frames(
    times: Any, *, fps: float, round_to_int: bool = True, mode: str = "round"
) -> np.ndarray:
    """Convert times [s] to frame indices: ``frames = round(t * fps)``.

    ``round_to_int=False`` gives fractional frames; ``mode`` "floor"/"ceil" give the
    frame at or before/after the time (1e-9 frames of tolerance for float error).
    """
    check_choice(mode, ("round", "floor", "ceil"), name="mode")
    fps = check_fps(fps)
    frames = np.asarray(times, dtype=np.float64) * fps
    if not round_to_int:
        return frames
    if mode == "round":
        return np.rint(frames).astype(np.int64)
    if mode == "floor":
        return np.floor(frames + 1e-9).astype(np.int64)
    return np.ceil(frames - 1e-9).astype(np.int64)


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
    """Return ``values`` as a float array (``dtype=None``: a float array's own dtype).

    Booleans, complex numbers, strings (numeric ones too: a text column usually means a
    header row or a wrong delimiter), dates, records and ragged lists are refused.
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
    """:func:`as_float_array`, refusing NaN or infinite entries."""
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
    """Event times [s]: 1-D, finite, >= 0, strictly increasing, not after ``duration``."""
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
        hint = " (frame indices or milliseconds, not seconds?)" if arr[-1] > 2 * duration else ""
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
    """Return a sample rate [Hz]: finite and at least :data:`MIN_PLAUSIBLE_SR` (not kHz)."""
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
    """Return a tempo [bpm] in [:data:`MIN_BPM`, :data:`MAX_BPM`]."""
    v = as_float(bpm, name=name, unit="bpm", text=True)
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
    """Check mono audio; return ``(y, sr)``, a float ``y`` as is (no copy).

    ``min_duration`` [s] refuses shorter audio; ``silence_peak`` refuses audio whose
    peak, or whose departure from its mean (a DC offset), is below it.
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
    # one pass when every sample is finite (unless the sum overflows)
    with np.errstate(over="ignore", invalid="ignore"):
        total = arr.sum()
    if not np.isfinite(total) and not np.isfinite(arr).all():
        bad = ~np.isfinite(arr)
        raise ParameterError(
            f"{name} contains {int(bad.sum())} NaN or infinite sample(s) "
            f"(first at sample {int(np.argmax(bad))}); repair or trim the audio"
        )
    if min_duration is not None and arr.size / sr_f < min_duration:
        raise ParameterError(
            f"the audio is only {arr.size / sr_f:.3f} s long ({arr.size} samples at sr={sr_f:g} "
            f"Hz); at least {min_duration:.3g} s is needed (give a longer excerpt, or check "
            "the sample rate)"
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
    """Phase in ``[0, 1)`` of each event [s] in its beat interval (0: on a beat).

    Events outside the beats are dropped; inputs are checked by the caller.
    """
    e = np.asarray(events, dtype=np.float64)
    b = np.asarray(beats, dtype=np.float64)
    e = e[(e >= b[0]) & (e < b[-1])]
    i = np.searchsorted(b, e, side="right") - 1
    return (e - b[i]) / (b[i + 1] - b[i])


def nearest(events: Any, reference: Any) -> np.ndarray:
    """The nearest of the increasing ``reference`` times to each event [s] (inputs are
    checked by the caller)."""
    e = np.asarray(events, dtype=np.float64)
    r = np.asarray(reference, dtype=np.float64)
    idx = np.searchsorted(r, e)
    lo = r[np.clip(idx - 1, 0, r.size - 1)]
    hi = r[np.clip(idx, 0, r.size - 1)]
    return np.where(np.abs(e - lo) <= np.abs(e - hi), lo, hi)


def check_interval(pair: Any, *, name: str, unit: str) -> tuple[float, float]:
    """:func:`check_range` of one pair ``(lo, hi)``, refusing what is not a pair."""
    if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
        raise ParameterError(
            f"{name}={pair!r} must be two numbers (lower, upper) [{unit}], e.g. (0.5, 2.0)"
        )
    lo, hi = pair
    return check_range(lo, hi, name=name, unit=unit)


#: Highest motion frame rate accepted by :func:`check_motion_fps` [Hz].
MAX_MOTION_FPS = 2000.0


def check_motion_fps(fps: Any, *, name: str = "fps") -> float:
    """:func:`check_fps` of a motion to compute, at most :data:`MAX_MOTION_FPS`.

    Capture runs at up to about 2000 Hz; a higher rate fills the memory.
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
    """``None`` or 1 to 16 workers per core (at least 64): a typo must not hang the machine."""
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
