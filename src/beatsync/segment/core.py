"""The public entry of the segmentation: :func:`segment`, :func:`segment_values`, the result.

Every argument is validated here, once, cheapest first (numbers, then the values, then
what the data allow: constant channels, clip length, whether the count fits); the
modules below trust their inputs. User mistakes raise
:class:`~beatsync.errors.ParameterError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import NotPeriodicError, ParameterError
from ..validation import (
    MAX_BPM,
    MIN_BPM,
    as_float,
    check_choice,
    check_finite,
    check_fps,
    check_interval,
    frames_to_time,
    time_to_frames,
)
from .channels import nonconstant_channels, select_channels, standardise, unwrap_rotations
from .checks import (
    check_alpha,
    check_n_periods,
    check_period_method,
    check_period_range,
    check_values,
)
from .period import (
    MAX_NORMALISED_ENERGY,
    MIN_PERIODICITY_CONTRAST,
    estimate_period,
    estimation_band,
    period_tiers,
    periodicity_contrast,
)
from .search import SEARCH_MEMORY_BUDGET, optimum, period_band, search_decimation

if TYPE_CHECKING:
    from ..motion import Motion

__all__ = [
    "DEFAULT_PERIOD_RANGE",
    "DANCE_PERIOD_RANGE",
    "MIN_CLIP_PERIODS",
    "SHORT_CLIP_MAX_ENERGY",
    "Segmentation",
    "PERIOD_BEATS",
    "period_range_from_beat",
    "segment",
    "segment_values",
    "estimate_period_count",
    "PeriodicityRefused",
    "NOT_PERIODIC_ADVICE",
]

DEFAULT_PERIOD_RANGE = (0.25, 1.25)
"""Periods [s] searched by default: the paper's (why not wider: ``docs/tuning.md``)."""

DANCE_PERIOD_RANGE = (0.25, 6.25)
"""Steps (0.25-1.25 s) and figures (1.25-6.25 s, a slow waltz box), shortest first."""

MIN_CLIP_PERIODS = 3
"""A clip shorter than this many of its estimated periods needs :data:`SHORT_CLIP_MAX_ENERGY`."""

SHORT_CLIP_MAX_ENERGY = 0.5
"""Largest mean Pearson distance of a clip shorter than :data:`MIN_CLIP_PERIODS` periods."""


@dataclass(frozen=True)
class Segmentation:
    """Result of :func:`segment`: ``boundaries`` [s] (``n_periods + 1``, increasing, within
    ``[0, (n_frames - 1) / fps]``), ``energy`` E of the optimum, the ``channels`` used (after
    selection and exclusion), ``period_method`` (``"energy"``, ``"fft"`` or ``"given"``) and
    ``search_decimation`` (1: the exact search at full rate).
    """

    boundaries: np.ndarray
    n_periods: int
    mean_period: float
    energy: float
    channels: tuple[str, ...]
    fps: float
    period_method: str
    search_decimation: int = 1

    @property
    def boundary_frames(self) -> np.ndarray:
        """Boundaries as frame indices (int64)."""
        return time_to_frames(self.boundaries, fps=self.fps)

    @property
    def periods(self) -> np.ndarray:
        """Period durations [s]."""
        return np.diff(self.boundaries)

    @property
    def normalised_energy(self) -> float:
        """Mean Pearson distance between consecutive periods, E / (channels * (p-1))."""
        return float(self.energy / (len(self.channels) * max(self.n_periods - 1, 1)))


def _motion_channels(vals: np.ndarray, names: tuple[str, ...]) -> tuple[np.ndarray, tuple]:
    """Standardised non-constant channels ``(C, n)`` and their names."""
    keep = nonconstant_channels(vals)
    if not keep.any():
        raise ParameterError(
            "every selected channel is constant: there is no motion to segment "
            "(choose other channels, e.g. channels='all')"
        )
    used = tuple(nm for nm, k in zip(names, keep, strict=True) if k)
    return standardise(vals[:, keep]), used


def _frame_band(n: int, fps: float, period_range: tuple[float, float]) -> tuple[float, float]:
    """Candidate periods [frames] for estimating the count, or a ParameterError."""
    lo_p, hi_p = time_to_frames(period_range, fps=fps, round_to_int=False)
    lo_f, hi_f = estimation_band(n, float(lo_p), float(hi_p))
    span = float(frames_to_time(n - 1, fps=fps))
    if span < MIN_CLIP_PERIODS * period_range[0]:
        raise NotPeriodicError(
            f"clip of {n} frames lasts {span:.3f} s at fps={fps:g}, shorter than "
            f"{MIN_CLIP_PERIODS} periods of the shortest requested period "
            f"{period_range[0]:g} s; give a longer clip, a shorter --period-range, or check "
            "fps (frames vs seconds)"
        )
    if hi_f < lo_f:
        raise ParameterError(
            f"no period of {period_range[0]:g}-{period_range[1]:g} s spans two frames and fits "
            f"twice in {n} frames at fps={fps:g}; give a longer period range or clip, or "
            "check fps"
        )
    return lo_f, hi_f


#: What the periodicity test's refusal advises a caller of :func:`segment` to try; a
#: caller without some of these settings says what it offers instead
#: (:func:`beatsync.sync.core.motion_periods`).
NOT_PERIODIC_ADVICE = "Try other channels, another period_range, or a clip with repeated movement"


class PeriodicityRefused(NotPeriodicError):
    """The periodicity test refused the optimum (a longer tier may still be periodic).

    :meth:`advised` gives the message with another caller's advice in place of
    :data:`NOT_PERIODIC_ADVICE`.
    """

    def __init__(self, finding: str, hint: str = "", searched: str = "") -> None:
        self.finding, self.hint, self.searched = finding, hint, searched
        super().__init__(self.advised(NOT_PERIODIC_ADVICE))

    def advised(self, advice: str) -> str:
        """The message with ``advice`` in place of :data:`NOT_PERIODIC_ADVICE`."""
        return f"{self.finding}{advice}{self.hint}{self.searched}"


def _segment(
    vals: np.ndarray,
    names: tuple[str, ...],
    *,
    fps: float,
    alpha: float,
    n_periods: int | None,
    period_range: tuple[float, float],
    method: str,
) -> Segmentation:
    """Segmentation of validated values; tiers of the period range searched shortest first."""
    n = vals.shape[0]
    if n_periods is not None:
        x, used = _motion_channels(vals, names)
        return _search(x, used, fps=fps, alpha=alpha, nominal=(n - 1) / n_periods,
                       count=n_periods, period_range=period_range)  # fmt: skip
    tiers = period_tiers(*period_range)
    _frame_band(n, fps, tiers[0])  # the clip's length first (cheap)
    x, used = _motion_channels(vals, names)
    refusal, tried = None, []
    for tier in tiers:
        lo_p, hi_p = time_to_frames(tier, fps=fps, round_to_int=False)
        lo_f, hi_f = estimation_band(n, float(lo_p), float(hi_p))
        if hi_f < lo_f:  # the clip cannot show two periods of this tier
            break
        tried.append(f"{tier[0]:g}-{tier[1]:g} s")
        nominal = estimate_period(x, lo_f, hi_f, method)
        try:
            return _search(x, used, fps=fps, alpha=alpha, nominal=nominal, count=None,
                           period_range=tier, method=method)  # fmt: skip
        except PeriodicityRefused as exc:
            refusal = exc
    searched = f" (period tiers searched, shortest first: {', '.join(tried)})"
    raise PeriodicityRefused(refusal.finding, refusal.hint, searched if len(tried) > 1 else "")


def _search(
    x: np.ndarray,
    used: tuple[str, ...],
    *,
    fps: float,
    alpha: float,
    nominal: float,
    count: int | None,
    period_range: tuple[float, float],
    method: str = "given",
) -> Segmentation:
    """The optimum around ``nominal`` [frames], the clip-length and periodicity tests."""
    n = x.shape[1]
    p = count if count is not None else max(2, int(np.floor((n - 1) / nominal + 1e-9)))
    lo, hi = period_band(nominal, alpha)
    if lo < 2:
        raise ParameterError(
            f"{p} periods in {n} frames is {nominal:.2f} frames per period: too short to "
            "segment (need >= 2 frames per period); fewer periods or a higher frame rate"
        )
    if lo > hi:
        raise ParameterError(
            f"alpha={alpha:g} allows no whole-frame period length around {nominal:.2f} "
            "frames; increase alpha"
        )
    factor = search_decimation(n, lo, hi, x.shape[0], count, SEARCH_MEMORY_BUDGET)
    if factor is None:
        raise ParameterError(
            f"the period of ~{(lo + hi) / 2:.0f} frames (band {lo}-{hi}) needs more than "
            f"{SEARCH_MEMORY_BUDGET / 2**20:.0f} MiB to search and cannot be decimated "
            "further; give a lower --fps or a shorter --period-range / more periods"
        )
    frames, energy = optimum(x, lo, hi, count, factor)
    n_found = frames.size - 1
    e_norm = energy / (x.shape[0] * max(n_found - 1, 1))
    if count is None and (n - 1) < MIN_CLIP_PERIODS * nominal and e_norm >= SHORT_CLIP_MAX_ENERGY:
        per = float(frames_to_time(nominal, fps=fps))
        span = float(frames_to_time(n - 1, fps=fps))
        raise NotPeriodicError(
            f"clip of {span:.3f} s holds only {(n - 1) / nominal:.1f} periods of its "
            f"estimated period {per:.3f} s, and they are not clearly alike (mean Pearson "
            f"distance {e_norm:.3f} >= {SHORT_CLIP_MAX_ENERGY}): too short to tell a "
            "repeating movement from a single one. Give a clip of at least "
            f"{MIN_CLIP_PERIODS} periods ({MIN_CLIP_PERIODS * per:.1f} s), or the period count "
            "(n_periods / --periods) if you know it"
        )
    contrast = periodicity_contrast(x, frames)
    if e_norm >= MAX_NORMALISED_ENERGY or (
        np.isfinite(contrast) and contrast < MIN_PERIODICITY_CONTRAST
    ):
        hint = ""
        if method == "given":
            lo_p, hi_p = time_to_frames(period_range, fps=fps, round_to_int=False)
            lo_f, hi_f = estimation_band(n, float(lo_p), float(hi_p))
            if lo_f <= hi_f:  # the count the data suggest, for the message
                est = estimate_period(x, lo_f, hi_f, "energy")
                hint = (
                    f"; n_periods={p} was given: is it right? The energy estimate of the "
                    f"count in {period_range[0]:g}-{period_range[1]:g} s periods is "
                    f"{max(2, int(np.floor((n - 1) / est + 1e-9)))}"
                )
            else:
                hint = f"; n_periods={p} was given: check the count"
        raise PeriodicityRefused(
            f"the motion is not periodic: the best segmentation into {n_found} periods of "
            f"~{float(frames_to_time((frames[-1] - frames[0]) / n_found, fps=fps)):.3f} s has "
            f"mean Pearson distance {e_norm:.3f} between consecutive periods, and uniform "
            f"segmentations at this period beat those at wrong periods by only {contrast:.3f} "
            f"(periodic needs < {MAX_NORMALISED_ENERGY} and a contrast >= "
            f"{MIN_PERIODICITY_CONTRAST}); no boundaries are reported. ",
            hint,
        )
    times = frames_to_time(frames, fps=fps)
    return Segmentation(
        boundaries=times,
        n_periods=int(n_found),
        mean_period=float((times[-1] - times[0]) / n_found),
        energy=float(energy),
        channels=used,
        fps=fps,
        period_method=method,
        search_decimation=factor,
    )


def segment_values(
    values: Any,
    *,
    fps: float,
    alpha: float = 0.1,
    n_periods: int | None = None,
    period_range: tuple[float, float] = DEFAULT_PERIOD_RANGE,
    period_method: str = "energy",
    channel_names: Sequence[str] | None = None,
) -> Segmentation:
    """Globally optimal segmentation of a periodic multi-channel signal (paper A, sec. 3).

    ``values`` ``(n_frames, n_channels)``: joint angles, any unit, already unwrapped;
    ``alpha``: allowed relative deviation of every period from the nominal one (eq. 3);
    ``n_periods``: the count if known; else it is estimated (``period_method``, see
    :func:`estimate_period_count`) in ``period_range`` [s]. A clip that is not periodic,
    or too short to tell, raises :class:`NotPeriodicError` (its own motion beats can
    still sync it: :func:`beatsync.sync.synchronize`, ``mode="beats"``).

    Examples
    --------
    >>> from beatsync.synth.motion import periodic_motion
    >>> s = periodic_motion(n_frames=300, n_periods=10, snr_db=30, seed=1)
    >>> seg = segment_values(s.motion.values, fps=25, n_periods=10)
    >>> int(abs(seg.boundary_frames - s.boundary_frames).max()) <= 1
    True
    """
    fps = check_fps(fps)
    alpha = check_alpha(alpha)
    p = check_n_periods(n_periods)
    lo_s, hi_s = check_period_range(period_range)
    method = check_period_method(period_method, p)
    vals = check_values(values)
    if channel_names is None:
        channel_names = [f"ch{i}" for i in range(vals.shape[1])]
    names = tuple(str(c) for c in channel_names)
    if len(names) != vals.shape[1]:
        raise ParameterError(
            f"{len(names)} channel names for {vals.shape[1]} value columns; is the array "
            "transposed (it must be frames x channels)?"
        )
    return _segment(vals, names, fps=fps, alpha=alpha, n_periods=p,
                    period_range=(lo_s, hi_s), method=method)  # fmt: skip


def segment(
    motion: Motion,
    *,
    alpha: float = 0.1,
    n_periods: int | None = None,
    period_range: tuple[float, float] = DEFAULT_PERIOD_RANGE,
    period_method: str = "energy",
    channels: str | Sequence[str] = "default",
) -> Segmentation:
    """Split a periodic motion into its periods, globally optimally (paper A, sec. 3).

    ``channels`` as in :func:`~beatsync.segment.select_channels`, the rest as in
    :func:`segment_values`.

    >>> from beatsync.synth.motion import periodic_motion
    >>> s = periodic_motion(n_frames=300, n_periods=10, seed=1)
    >>> seg = segment(s.motion, n_periods=10)
    >>> seg.n_periods, round(seg.mean_period, 3)
    (10, 1.196)
    """
    p = check_n_periods(n_periods)
    return _segment_motion(motion, alpha=check_alpha(alpha), n_periods=p,
                           period_range=check_period_range(period_range),
                           method=check_period_method(period_method, p),
                           channels=channels)  # fmt: skip


def _segment_motion(
    motion: Motion,
    *,
    alpha: float,
    n_periods: int | None,
    period_range: tuple[float, float],
    method: str,
    channels: str | Sequence[str] = "default",
) -> Segmentation:
    """:func:`segment` with its settings checked (the motion's data is checked here)."""
    names = select_channels(motion.channels, channels)
    idx = [motion.channel_index(nm) for nm in names]
    values = check_finite(motion.values[:, idx], name=f"motion {motion.name!r} values")
    if values.shape[0] < 3:
        raise ParameterError(
            f"motion {motion.name!r} has {values.shape[0]} frame(s); a segmentation needs more"
        )
    return _segment(unwrap_rotations(values, names), names, fps=motion.fps, alpha=alpha,
                    n_periods=n_periods, period_range=period_range, method=method)  # fmt: skip


def estimate_period_count(
    values: Any,
    *,
    fps: float,
    period_range: tuple[float, float] = DEFAULT_PERIOD_RANGE,
    method: str = "energy",
) -> int:
    """Number of whole periods ``p`` in a clip, by FFT peak or uniform-segmentation energy.

    The whole ``period_range`` [s] is searched at once (no tiers); ``method`` as in
    :func:`beatsync.segment.period.estimate_period`. Returns
    ``max(2, floor((n_frames - 1) / (T * fps)))``.
    """
    fps = check_fps(fps)
    lo_s, hi_s = check_period_range(period_range)
    check_choice(method, ("energy", "fft"), name="method")
    vals = check_values(values)
    n = vals.shape[0]
    lo_f, hi_f = _frame_band(n, fps, (lo_s, hi_s))
    x, _ = _motion_channels(vals, tuple(f"ch{i}" for i in range(vals.shape[1])))
    per = estimate_period(x, lo_f, hi_f, method)
    return max(2, int(np.floor((n - 1) / per + 1e-9)))


#: a dance cycle in music beats: one to eight, with room for one danced a little off the
#: tempo (``beatsync segment --bpm`` and ``beatsync sync --mode periods``)
PERIOD_BEATS = (0.9, 8.5)


def period_range_from_beat(
    beat_period: float, *, beats: tuple[float, float] = PERIOD_BEATS
) -> tuple[float, float]:
    """Period range [s] of a dance to music of this beat period [s]: ``beats`` beats.

    A dance cycle lasts a whole number of beats, from a step per beat to a figure of a
    few bars (a waltz box: 6 beats; a salsa basic: 8).

    >>> period_range_from_beat(0.5)
    (0.45, 4.25)
    """
    bp = as_float(beat_period, name="beat_period", unit="s", text=True)
    if not 60.0 / MAX_BPM <= bp <= 60.0 / MIN_BPM:
        raise ParameterError(
            f"beat_period={beat_period!r} must be in [{60.0 / MAX_BPM:g}, {60.0 / MIN_BPM:g}] "
            "[s] (a beat period in seconds is 60 / BPM; is it a tempo in BPM?)"
        )
    b_lo, b_hi = check_interval(beats, name="beats", unit="beats")
    return b_lo * bp, b_hi * bp
