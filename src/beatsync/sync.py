"""Beat-synchronous resampling of periodic motion (paper A, section 5).

Make every period of a dance land on the music's beats: each motion period is mapped
to a group of ``m`` consecutive music beats, its playback rate is set so that it lasts
exactly as long as that group, the per-period rates are blended into a smoothly
varying rate with Gaussian weights (paper A, eq. 9), and the rate is integrated into a
monotonic time warp on which the motion is resampled (quaternion slerp for rotations,
linear interpolation for positions).

Data contract
-------------
- Event times (period ``boundaries``, music ``beats``) are 1-D float64 arrays in
  seconds, strictly increasing. Boundaries are in the *source* motion's timeline,
  beats in the *music* timeline.
- The synchronised motion's frame ``k`` is shown at music time ``k / out_fps``: its
  time axis *is* the music's, so it can be played together with the song from the
  start. Frames before the first warped frame hold the first pose.
- Rates are dimensionless: ``rate = target duration / source duration`` (> 1 slows
  the dance down). The report's ``tempo_ratio`` is its inverse, the playback speed.
- All frame/second conversion goes through :mod:`beatsync.units`.

Method (what the paper leaves open, and our choices)
----------------------------------------------------
1. Beats per period (:func:`beats_per_period`): ``m = max(1, round(P / b))`` with
   ``P`` the mean motion period and ``b`` the median inter-beat interval, so a 1 s
   salsa step on a 120 BPM song spans 2 beats, a 6-beat figure 6 beats. Override
   with ``beats_per_period=``.
2. Period ``i`` (source ``[s_i, s_{i+1}]``) is mapped to beats
   ``B_i = beats[first_beat + i*m]`` and ``B_{i+1}``. Per-period rate
   ``r_i = (B_{i+1} - B_i) / (s_{i+1} - s_i)``.
3. Eq. 9 (our reading): the continuous rate is the Gaussian-weighted mean of the
   period rates, ``r(t) = sum_i w_i(t) r_i / sum_i w_i(t)``,
   ``w_i(t) = exp(-(t - c_i)^2 / (2 delta^2))``, ``c_i`` the centre of period ``i``
   in source time and ``delta`` the mean motion period (default).
4. The blended rate alone does not make boundaries land on beats (it smears each
   period's rate into its neighbours; with ``delta`` = one period the blend is
   nearly the running mean). We correct each period by a bump ``h(u)`` that
   vanishes at both of its ends, ``r~(t) = r(t) (1 + a_i h(u))``, ``u`` the phase in
   the period, with ``a_i`` chosen so that the integral over the period equals
   ``B_{i+1} - B_i`` exactly. ``h`` is a plateau with raised-cosine ramps over a
   quarter period at each end (a Tukey window): inside a period the rate then
   approaches that period's own ``r_i``, and it passes smoothly through the blended
   eq. 9 value at every boundary. (A ``sin^2`` bump would need twice the
   amplitude and overshoot ``r_i``.) The rate stays continuous across boundaries
   (if a correction would need ``a_i <= -0.9`` we fall back to scaling the period's
   rate, which makes the rate jump there; the report counts these).
5. The warp ``tau(t)`` integrates ``r~`` (trapezoid on a fine grid whose knots
   include every boundary, so ``tau(s_i) = B_i`` to rounding). Before the first
   boundary and after the last one the rate is held constant at its boundary value.
   If the music has fewer beats than the motion has periods, the periods that do not
   fit are dropped and the output ends at the last boundary used.
6. Output frames at ``k / out_fps`` are mapped back to source times by inverting the
   warp, and the motion is evaluated there with :func:`beatsync.rotations.sample_motion`.
   Output frames run from music time 0 to the first frame at or after the warp's end
   (motion warped to negative music times, before the song starts, is dropped).
7. ``phase_offset`` [s] lands the boundaries that long after their beats, e.g. to put
   the dancer's accents rather than the segmentation's boundaries on the beat.

The residual of a boundary is measured twice in the report: on the warp as realised
by the output frames (``residual_ms``: the music time at which the resampled motion
passes the boundary pose, minus its beat) and as the distance from the beat to the
output frame nearest to that crossing, i.e. the frame that shows the boundary
(``residual_nearest_frame_ms``, at most half a frame plus the warp residual).

Notebooks: ``notebooks/paper_a_tab01_frame_counts.ipynb``,
``notebooks/paper_a_fig03_animation_frames.ipynb``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import BeatsyncWarning, ParameterError
from .units import check_fps, check_times, frames_to_time, time_to_frames

__all__ = [
    "SyncResult",
    "TimeWarp",
    "beats_per_period",
    "blended_rate",
    "time_warp",
    "synchronize",
]

#: knots of the warp grid inside each period
_GRID_PER_PERIOD = 128
#: fraction of a period over which the correction ramps in (and out) at each end
_TAPER = 0.25
#: below this bump amplitude the correction would make the rate near zero: scale instead
_MIN_BUMP = -0.9


def _is_whole(x: Any) -> bool:
    """True for an integer-valued number (not a bool, not a string)."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        return False
    return bool(np.isfinite(x)) and float(x).is_integer()


def _bump(u: np.ndarray, taper: float | None = None) -> np.ndarray:
    """Correction shape on the period phase ``u`` in [0, 1]: 0 at both ends, 1 in the
    middle, with raised-cosine ramps over ``taper`` of the period at each end."""
    taper = _TAPER if taper is None else taper
    ramp = np.minimum(u, 1.0 - u) / taper
    return np.where(ramp >= 1.0, 1.0, np.sin(0.5 * np.pi * np.clip(ramp, 0.0, 1.0)) ** 2)


def beats_per_period(
    mean_period: float,
    beats: Any,
    *,
    override: int | None = None,
) -> int:
    """Number of music beats one motion period spans.

    Rule: ``m = max(1, round(mean_period / beat_period))`` with ``beat_period`` the
    median inter-beat interval. A period of a 1 s salsa step on 120 BPM music spans 2
    beats; a motion period shorter than one beat interval is slowed to one beat.

    Parameters
    ----------
    mean_period : float > 0 [s]
        Mean duration of one motion period (e.g. ``Segmentation.mean_period``).
    beats : np.ndarray [shape=(n,), n >= 2] [s]
        Music beat times.
    override : int >= 1, optional
        Use this count instead of the rule.

    Returns
    -------
    m : int >= 1 [beats]

    Raises
    ------
    ParameterError
        Fewer than two beats, a non-positive period, or a bad override.

    Examples
    --------
    >>> beats_per_period(1.0, np.arange(0, 10, 0.5))
    2
    """
    if override is not None:
        if not _is_whole(override) or override < 1:
            raise ParameterError(
                f"beats_per_period={override!r} must be a whole number of beats >= 1"
            )
        return int(override)
    beats = check_times(beats, name="beats")
    if beats.size < 2:
        raise ParameterError(
            f"need at least 2 music beats to know the beat period, got {beats.size}; "
            "the music may be silent or have no detectable beats (give --bpm or a beats file)"
        )
    try:
        mean_period = float(mean_period)
    except (TypeError, ValueError):
        raise ParameterError(f"mean_period={mean_period!r} must be a number [s]") from None
    if not np.isfinite(mean_period) or mean_period <= 0:
        raise ParameterError(f"mean_period={mean_period!r} must be a finite duration > 0 [s]")
    beat_period = float(np.median(np.diff(beats)))
    return max(1, int(np.rint(mean_period / beat_period)))


def blended_rate(
    t: Any,
    centres: Any,
    rates: Any,
    *,
    delta: float,
) -> np.ndarray:
    """Gaussian-blended playback rate (paper A, eq. 9, our reading).

    ``r(t) = sum_i w_i(t) r_i / sum_i w_i(t)``, ``w_i(t) = exp(-(t - c_i)^2 / (2 delta^2))``.

    Parameters
    ----------
    t : np.ndarray [shape=(n,)] [s]
        Source times at which to evaluate the rate.
    centres : np.ndarray [shape=(p,)] [s]
        Centre of each period in source time.
    rates : np.ndarray [shape=(p,)] [dimensionless]
        Per-period rate ``target / source``.
    delta : float > 0 [s]
        Width of the Gaussian weights (default in :func:`time_warp`: the mean period).

    Returns
    -------
    r : np.ndarray [shape=(n,)]
    """
    t = np.asarray(t, dtype=np.float64)
    c = np.asarray(centres, dtype=np.float64)
    r = np.asarray(rates, dtype=np.float64)
    z = (t[:, None] - c[None, :]) / delta
    # subtract the row maximum of the log weights so far-away times do not underflow
    logw = -0.5 * z * z
    logw -= logw.max(axis=1, keepdims=True)
    w = np.exp(logw)
    return (w @ r) / w.sum(axis=1)


@dataclass(frozen=True)
class TimeWarp:
    """A monotonic, piecewise-linear map from source time to music time.

    Attributes
    ----------
    src : np.ndarray [shape=(k,)] [s]
        Knots in the source motion's time, strictly increasing.
    tgt : np.ndarray [shape=(k,)] [s]
        Music time of each knot, strictly increasing.
    boundaries : np.ndarray [shape=(p+1,)] [s]
        Source period boundaries used.
    targets : np.ndarray [shape=(p+1,)] [s]
        Music beat each boundary is mapped to.
    period_rates : np.ndarray [shape=(p,)]
        ``r_i`` per period (target / source).
    rate : np.ndarray [shape=(k,)]
        Corrected continuous rate ``r~`` at the knots.
    n_scaled : int
        Periods whose correction fell back to scaling (rate jumps at their ends).
    delta : float [s]
    """

    src: np.ndarray
    tgt: np.ndarray
    boundaries: np.ndarray
    targets: np.ndarray
    period_rates: np.ndarray
    rate: np.ndarray
    n_scaled: int
    delta: float

    def to_target(self, t: Any) -> np.ndarray:
        """Music time [s] of source times ``t`` [s] (linear beyond the ends)."""
        t = np.asarray(t, dtype=np.float64)
        out = np.interp(t, self.src, self.tgt)
        lo, hi = t < self.src[0], t > self.src[-1]
        out[lo] = self.tgt[0] + (t[lo] - self.src[0]) * self.rate[0]
        out[hi] = self.tgt[-1] + (t[hi] - self.src[-1]) * self.rate[-1]
        return out

    def to_source(self, tau: Any) -> np.ndarray:
        """Source time [s] of music times ``tau`` [s], clipped to the warp's source span."""
        return np.interp(np.asarray(tau, dtype=np.float64), self.tgt, self.src)


def time_warp(
    boundaries: Any,
    targets: Any,
    *,
    start: float | None = None,
    end: float | None = None,
    delta: float | None = None,
) -> TimeWarp:
    """Integrate the blended, boundary-corrected rate into a time warp.

    Parameters
    ----------
    boundaries : np.ndarray [shape=(p+1,), p >= 1] [s]
        Source period boundaries, strictly increasing.
    targets : np.ndarray [shape=(p+1,)] [s]
        Music times the boundaries must land on, strictly increasing.
    start, end : float, optional [s]
        Source span to cover before the first / after the last boundary, at the rate
        the blended curve has there (default: no extension).
    delta : float > 0, optional [s]
        Gaussian width of eq. 9; default the mean period ``mean(diff(boundaries))``.

    Returns
    -------
    TimeWarp
        ``warp.to_target(boundaries) == targets`` to rounding.

    Raises
    ------
    ParameterError
        Mismatched lengths, fewer than two boundaries, unsorted times, bad ``delta``.

    Examples
    --------
    >>> w = time_warp([0.0, 1.0, 2.0], [0.0, 0.5, 1.0])
    >>> w.to_target([0.5, 1.5]).round(6)
    array([0.25, 0.75])
    """
    s = check_times(boundaries, name="boundaries")
    b = np.asarray(targets, dtype=np.float64)
    if s.size < 2:
        raise ParameterError(
            f"need at least 2 period boundaries (one period), got {s.size}; "
            "is the motion periodic?"
        )
    if b.shape != s.shape:
        raise ParameterError(
            f"targets has shape {b.shape} but boundaries has {s.shape}: one music time per boundary"
        )
    b = check_times(b, name="targets")
    src_len = np.diff(s)
    tgt_len = np.diff(b)
    mean_period = float(src_len.mean())
    if delta is None:
        delta = mean_period
    try:
        delta = float(delta)
    except (TypeError, ValueError):
        raise ParameterError(f"delta={delta!r} must be a duration in seconds") from None
    if not np.isfinite(delta) or delta <= 0:
        raise ParameterError(f"delta={delta!r} must be a finite Gaussian width > 0 [s]")

    p = src_len.size
    k = _GRID_PER_PERIOD
    u = np.linspace(0.0, 1.0, k + 1)
    # grid (p, k+1): period i from s_i to s_{i+1}; shared endpoints duplicated per row
    grid = s[:-1, None] + u[None, :] * src_len[:, None]
    rates = tgt_len / src_len
    centres = 0.5 * (s[:-1] + s[1:])
    r = blended_rate(grid.ravel(), centres, rates, delta=delta).reshape(p, k + 1)
    # exact landing: r~ = r (1 + a_i h), h vanishes at both ends
    h = _bump(u)
    dt = src_len[:, None] * np.diff(u)[None, :]
    integ = ((r[:, :-1] + r[:, 1:]) * 0.5 * dt).sum(axis=1)
    rh = r * h[None, :]
    integ_h = ((rh[:, :-1] + rh[:, 1:]) * 0.5 * dt).sum(axis=1)
    a = (tgt_len - integ) / integ_h
    scaled = a <= _MIN_BUMP
    rc = r * (1.0 + a[:, None] * h[None, :])
    if scaled.any():
        rc[scaled] = r[scaled] * (tgt_len[scaled] / integ[scaled])[:, None]
    seg = (rc[:, :-1] + rc[:, 1:]) * 0.5 * dt  # (p, k)
    # cumulative music time within each period, anchored on its own target beat so
    # rounding does not accumulate across periods
    tau = np.empty((p, k + 1))
    tau[:, 0] = b[:-1]
    tau[:, 1:] = b[:-1, None] + np.cumsum(seg, axis=1)
    tau[:, -1] = b[1:]
    src_knots = np.concatenate([grid[:, :-1].ravel(), s[-1:]])
    tgt_knots = np.concatenate([tau[:, :-1].ravel(), b[-1:]])
    rate_knots = np.concatenate([rc[:, :-1].ravel(), rc[-1:, -1]])
    if start is not None and start < s[0]:
        src_knots = np.concatenate([[start], src_knots])
        tgt_knots = np.concatenate([[b[0] - (s[0] - start) * rate_knots[0]], tgt_knots])
        rate_knots = np.concatenate([rate_knots[:1], rate_knots])
    if end is not None and end > s[-1]:
        src_knots = np.concatenate([src_knots, [end]])
        tgt_knots = np.concatenate([tgt_knots, [b[-1] + (end - s[-1]) * rate_knots[-1]]])
        rate_knots = np.concatenate([rate_knots, rate_knots[-1:]])
    return TimeWarp(
        src=src_knots,
        tgt=tgt_knots,
        boundaries=s,
        targets=b,
        period_rates=rates,
        rate=rate_knots,
        n_scaled=int(scaled.sum()),
        delta=delta,
    )


@dataclass(frozen=True)
class SyncResult:
    """Output of :func:`synchronize`.

    Attributes
    ----------
    motion : Motion
        The beat-synchronous motion at ``out_fps``; frame ``k`` plays at music time
        ``k / out_fps`` [s].
    warp_src_times : np.ndarray [shape=(n_out,)] [s]
        Source time shown by each output frame (non-decreasing).
    report : dict
        ``input_frames``, ``output_frames``, ``input_fps``, ``output_fps``,
        ``periods_available``, ``periods_used``, ``beats_per_period``,
        ``beats_per_period_rule``, ``first_beat``, ``mean_motion_period_s``,
        ``beat_period_s``, ``delta_s``, ``rate_range`` (target/source),
        ``tempo_ratio_range`` (playback speed, source/target),
        ``target_beats_s``, ``residual_ms`` (one per boundary),
        ``residual_nearest_frame_ms``, ``max_abs_residual_ms``,
        ``max_abs_residual_frames``, ``lead_in_hold_frames``, ``n_scaled_periods``.
    warp : TimeWarp
        The warp itself (for plots).
    """

    motion: Any
    warp_src_times: np.ndarray
    report: dict = field(default_factory=dict)
    warp: TimeWarp | None = None


def _sample_motion(motion: Any, times: np.ndarray) -> np.ndarray:
    from .rotations import sample_motion

    return sample_motion(motion, times)


def synchronize(
    motion: Any,
    boundaries: Any,
    beats: Any,
    *,
    beats_per_period: int | None = None,
    first_beat: int = 0,
    out_fps: float | None = None,
    delta: float | None = None,
    phase_offset: float = 0.0,
) -> SyncResult:
    """Resample periodic motion so that its period boundaries land on music beats.

    Parameters
    ----------
    motion : beatsync.motion.Motion
        Source motion (joint angles in degrees and/or positions), ``fps`` [Hz].
    boundaries : np.ndarray [shape=(p+1,), p >= 1] [s]
        Period boundaries in the source's time (e.g. ``segment(motion).boundaries``).
    beats : np.ndarray [shape=(n,), n >= 2] [s]
        Music beat times (e.g. ``track_beats(y, sr).beats``).
    beats_per_period : int >= 1, optional
        Beats one period spans; default from the rule of :func:`beats_per_period`.
    first_beat : int >= 0
        Index of the beat the first boundary lands on.
    out_fps : float > 0, optional [Hz]
        Output frame rate; default ``motion.fps``.
    delta : float > 0, optional [s]
        Gaussian width of eq. 9; default the mean motion period.
    phase_offset : float [s]
        Land the boundaries this long after their beats (negative: before). Use it to
        put the dancer's accents, rather than the segmentation's boundaries, on the
        beat (see :func:`beatsync.evaluate.alignment.kinematic_phase_offset`).

    Returns
    -------
    SyncResult

    Raises
    ------
    ParameterError
        Boundaries outside the motion (frames instead of seconds?), fewer than two
        boundaries (motion not periodic), fewer than two beats (no detectable beats),
        music too short for one period after ``first_beat``, bad ``out_fps``.

    Examples
    --------
    >>> res = synchronize(motion, seg.boundaries, track.beats)  # doctest: +SKIP
    >>> res.report["max_abs_residual_ms"]  # doctest: +SKIP
    0.0
    """
    fps = check_fps(motion.fps, name="motion.fps")
    out_fps = fps if out_fps is None else check_fps(out_fps, name="out_fps")
    n_frames = int(motion.n_frames)
    if n_frames < 2:
        raise ParameterError(f"motion has {n_frames} frame(s); at least 2 are needed to resample")
    # last frame time: sample_motion clips there
    duration = float(frames_to_time(n_frames - 1, fps=fps))
    s = check_times(boundaries, name="boundaries", duration=float(motion.duration))
    if s.size < 2:
        raise ParameterError(
            f"got {s.size} period boundary(ies): the motion does not look periodic "
            "(segmentation found no full period); nothing to synchronise"
        )
    beats = check_times(beats, name="beats")
    if beats.size < 2:
        raise ParameterError(
            f"the music has {beats.size} detectable beat(s); at least 2 are needed "
            "(is it silent or without rhythm? give the tempo with bpm / --bpm)"
        )
    if not _is_whole(first_beat) or first_beat < 0:
        raise ParameterError(f"first_beat={first_beat!r} must be a beat index >= 0")
    first_beat = int(first_beat)
    if first_beat >= beats.size:
        raise ParameterError(
            f"first_beat={first_beat} but the music has only {beats.size} beats (indices from 0)"
        )
    src_len = np.diff(s)
    mean_period = float(src_len.mean())
    beat_period = float(np.median(np.diff(beats)))
    rule = "override" if beats_per_period is not None else "round(mean_period / beat_period)"
    m = _beats_per_period_fn(mean_period, beats, override=beats_per_period)
    n_periods = src_len.size
    n_fit = (beats.size - 1 - first_beat) // m
    if n_fit < 1:
        raise ParameterError(
            f"the music is too short: {beats.size - first_beat} beat(s) from beat {first_beat} "
            f"(last at {beats[-1]:.2f} s) cannot hold one motion period of {m} beat(s) "
            f"({mean_period:.2f} s of motion); use a longer song, an earlier first_beat "
            "or fewer beats_per_period"
        )
    p = min(n_periods, n_fit)
    try:
        phase_offset = float(phase_offset)
    except (TypeError, ValueError):
        raise ParameterError(f"phase_offset={phase_offset!r} must be a time in seconds") from None
    if not np.isfinite(phase_offset):
        raise ParameterError(f"phase_offset={phase_offset!r} must be finite [s]")
    targets = beats[first_beat : first_beat + m * p + 1 : m] + phase_offset
    if targets[0] < 0:
        raise ParameterError(
            f"phase_offset={phase_offset:.3f} s puts the first boundary at {targets[0]:.3f} s, "
            "before the music starts; use first_beat >= 1 or a smaller offset"
        )
    used = s[: p + 1]
    ratio = mean_period / beat_period / m
    if ratio > 2.0 or ratio < 0.5:
        warnings.warn(
            f"motion periods ({mean_period:.3f} s) become {m} beat(s) of {beat_period:.3f} s: "
            f"the dance is played {ratio:.2f}x its speed; check the beats or set "
            "beats_per_period",
            BeatsyncWarning,
            stacklevel=2,
        )
    end = duration if p == n_periods and duration > used[-1] else None
    warp = time_warp(used, targets, start=0.0, end=end, delta=delta)
    tau_end = float(warp.tgt[-1])
    if tau_end <= 0:
        raise ParameterError(
            f"the warped motion ends at music time {tau_end:.3f} s <= 0: first_beat={first_beat} "
            "is too early for the motion before the first boundary"
        )
    # the last frame is the first one at or after the last warped time, so the frame
    # nearest to the last boundary exists (the source is clipped there)
    n_out = int(np.ceil(tau_end * out_fps - 1e-6)) + 1
    out_times = frames_to_time(np.arange(n_out), fps=out_fps)
    src_times = warp.to_source(out_times)
    values = _sample_motion(motion, src_times)
    out_motion = motion.with_values(values, fps=out_fps)

    # residuals: realised warp (interpolated between output frames) and nearest frame
    live = (out_times > warp.tgt[0]) & (out_times < warp.tgt[-1])
    # the realised warp: output frames joined by straight lines, plus the warp's ends
    # (a boundary may sit exactly where a held lead-in or the clipped tail starts)
    xs = np.concatenate([warp.src[:1], src_times[live], warp.src[-1:]])
    ys = np.concatenate([warp.tgt[:1], out_times[live], warp.tgt[-1:]])
    realised = np.interp(used, xs, ys)
    residual = (realised - targets) * 1e3
    nearest = np.clip(time_to_frames(realised, fps=out_fps), 0, n_out - 1)
    nearest_res = (frames_to_time(nearest, fps=out_fps) - targets) * 1e3
    frame_ms = 1e3 / out_fps
    lead_in = int(np.count_nonzero(out_times < warp.tgt[0]))
    report: dict[str, Any] = {
        "input_frames": n_frames,
        "output_frames": n_out,
        "input_fps": fps,
        "output_fps": out_fps,
        "input_duration_s": duration,
        "output_duration_s": float(frames_to_time(n_out - 1, fps=out_fps)),
        "periods_available": int(n_periods),
        "periods_used": int(p),
        "beats_per_period": int(m),
        "beats_per_period_rule": rule,
        "first_beat": first_beat,
        "phase_offset_s": phase_offset,
        "mean_motion_period_s": mean_period,
        "beat_period_s": beat_period,
        "delta_s": float(warp.delta),
        "rate_range": [float(warp.period_rates.min()), float(warp.period_rates.max())],
        "continuous_rate_range": [float(warp.rate.min()), float(warp.rate.max())],
        "tempo_ratio_range": [
            float(1.0 / warp.period_rates.max()),
            float(1.0 / warp.period_rates.min()),
        ],
        "target_beats_s": targets,
        "boundaries_s": used,
        "residual_ms": residual,
        "residual_nearest_frame_ms": nearest_res,
        "max_abs_residual_ms": float(np.abs(residual).max()),
        "max_abs_residual_frames": float(np.abs(nearest_res).max() / frame_ms),
        "output_frame_ms": frame_ms,
        "lead_in_hold_frames": lead_in,
        "n_scaled_periods": int(warp.n_scaled),
    }
    # the first boundary frame index in the output, for users who trim
    report["first_boundary_frame"] = int(time_to_frames(targets[0], fps=out_fps))
    return SyncResult(motion=out_motion, warp_src_times=src_times, report=report, warp=warp)


_beats_per_period_fn = beats_per_period
