"""Beats mode: land the motion beats a viewer sees, not only those the source showed.

A motion beat is a minimum of the Gaussian-smoothed mean joint speed
(:func:`beatsync.motion_beats.kinematic_beats`, sigma 0.1 s). The output's joint speed
is the source's times the playback speed ``1 / r`` (``r`` the warp's rate, music time
per source time), so the warp can fill a minimum in or move it:

- **A falling playback speed fills a shallow dip.** With ``V_min`` the smoothed speed
  at a landing, ``V_peak`` the highest in an interval beside it (``P = V_peak / V_min``)
  and ``m`` that interval's rate, the output shows ``V_peak / m`` beside ``V_min / r``
  at the landing: the dip keeps a depth ratio ``P r / m``. :func:`dip_floor` holds
  ``r >= m / sqrt(P)`` on both sides, so at least half of every dip's log depth stays.
- **The smoothing reaches past the held rate** (``LANDING_HOLD`` is one sigma), so
  the output's minimum can sit a frame or two off its beat. :func:`land_seen` finds
  the output's motion beats (to a sub-frame, the parabola through the minimum and its
  neighbours), pins the source time each one shows to its beat instead, and keeps
  for every landing the pin that lands closest over ``SEEN_ROUNDS`` rounds. No pin
  moves an interval's speed out of the band the beat counts aimed at.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import silenced
from ..graph.timescale import DEFAULT_SCALE_BOUND
from ..motion_beats import kinematic_beat_frames, motion_positions, speed_curve

__all__ = ["SEEN_ROUNDS", "SEEN_REACH", "source_speed", "dip_floor", "seen_landings", "land_seen"]

#: rounds of measuring the output's motion beats and moving the pins
SEEN_ROUNDS = 2
#: an output motion beat this close to a landing's beat [s] is that landing's
SEEN_REACH = 0.1
#: samples per interval when looking for its speed peak
_PEAK_SAMPLES = 33


def source_speed(pos: np.ndarray, fps: float, looped: Any) -> Callable:
    """The source's smoothed mean joint speed (:func:`speed_curve` of joint positions
    ``pos`` at ``fps``) as a function of (looped, :class:`.fill.LoopedClip` or None)
    source times [s]."""
    curve = speed_curve(pos, fps=fps)
    frame_t = np.arange(curve.size) / fps

    def speed_at(t: np.ndarray) -> np.ndarray:
        if looped is None:
            return np.interp(t, frame_t, curve)
        a, b, w = looped.locate(t)[:3]
        return (1.0 - w) * np.interp(a, frame_t, curve) + w * np.interp(b, frame_t, curve)

    return speed_at


def dip_floor(
    speed_at: Callable[[np.ndarray], np.ndarray], used: np.ndarray, targets: np.ndarray
) -> np.ndarray:
    """The lowest rate to hold at each landing (module docstring): ``speed_at`` gives the
    source's smoothed joint speed at (looped) source times, ``used`` [s] the landings'
    source times, ``targets`` [s] their beats."""
    grid = np.linspace(used[:-1], used[1:], _PEAK_SAMPLES, axis=1)
    peak = speed_at(grid.ravel()).reshape(grid.shape).max(axis=1)
    low = np.maximum(speed_at(used), 1e-12)
    m = np.diff(targets) / np.diff(used)
    floor = np.zeros(used.size)
    floor[:-1] = m / np.sqrt(np.maximum(peak / low[:-1], 1.0))  # the interval after
    floor[1:] = np.maximum(floor[1:], m / np.sqrt(np.maximum(peak / low[1:], 1.0)))
    return floor


def seen_landings(out_motion: Any, targets: np.ndarray, to_source) -> tuple[np.ndarray, ...]:
    """For every beat in ``targets`` [s]: how far [s] the output's nearest motion beat
    lies (inf beyond ``SEEN_REACH``) and the source time it shows (``to_source`` maps
    output times to it)."""
    pos = motion_positions(out_motion)
    fps = float(out_motion.fps)
    with silenced():
        frames = kinematic_beat_frames(pos, fps=fps)
    curve = speed_curve(pos, fps=fps)
    f = frames[(frames > 0) & (frames < curve.size - 1)]
    if f.size == 0:
        return np.full(targets.size, np.inf), np.asarray(targets, dtype=np.float64)
    c0, c1, c2 = curve[f - 1], curve[f], curve[f + 1]
    bend = c0 - 2.0 * c1 + c2
    vertex = np.where(bend > 0, 0.5 * (c0 - c2) / np.where(bend > 0, bend, 1.0), 0.0)
    seen = (f + np.clip(vertex, -0.5, 0.5)) / fps
    i = np.searchsorted(seen, targets)
    lo, hi = seen[np.clip(i - 1, 0, seen.size - 1)], seen[np.clip(i, 0, seen.size - 1)]
    near = np.where(np.abs(lo - targets) <= np.abs(hi - targets), lo, hi)
    d = np.abs(near - targets)
    return np.where(d <= SEEN_REACH, d, np.inf), to_source(near)


def _within(moved, kept, planned, targets, lo, hi):
    """``moved`` pins shortened towards ``kept`` until every interval's speed lies in
    ``[lo, hi]`` (per interval); failing that, the ``planned`` pins."""
    dur = np.diff(targets)
    frac = np.ones(moved.size)
    for _ in range(4):
        pins = kept + frac * (moved - kept)
        speed = np.diff(pins) / dur
        bad = np.nonzero((speed < lo) | (speed > hi))[0]
        if bad.size == 0:
            return pins
        # the share of the two ends' moves that puts the interval on the limit it crossed
        s0 = np.diff(kept)[bad] / dur[bad]
        limit = np.where(speed[bad] > hi[bad], hi[bad], lo[bad])
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.clip((limit - s0) / (speed[bad] - s0), 0.0, 1.0)
        share = np.where(np.isfinite(share), share, 0.0) * frac[bad].clip(max=1.0)
        frac[bad] = np.minimum(frac[bad], share)
        frac[bad + 1] = np.minimum(frac[bad + 1], share)
    pins = kept + frac * (moved - kept)
    speed = np.diff(pins) / dur
    bad = np.nonzero((speed < lo) | (speed > hi))[0]
    pins[bad], pins[bad + 1] = planned[bad], planned[bad + 1]
    return pins


def _figures(out: tuple, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per interval between ``targets``: output frames played outside the speed band,
    and the peak joint speed [unit / s]."""
    _, motion, out_times, src_times = out
    fps = float(motion.fps)
    speed = np.diff(src_times) * fps
    off = (speed < DEFAULT_SCALE_BOUND[0]) | (speed > DEFAULT_SCALE_BOUND[1])
    joints = np.linalg.norm(np.diff(motion_positions(motion), axis=0), axis=-1).max(axis=1) * fps
    k = np.searchsorted(targets, out_times[1:]) - 1
    inside = (k >= 0) & (k < targets.size - 1)
    n = targets.size - 1
    peak = np.zeros(n)
    np.maximum.at(peak, k[inside], joints[inside])
    return np.bincount(k[inside], weights=off[inside], minlength=n), peak


def _spoilt(out: tuple, targets: np.ndarray, planned: tuple, own_peak: float) -> np.ndarray:
    """Landings beside an interval with more output outside the speed band than the
    ``planned`` rendering's figures, or faster joints than both it and ``own_peak``."""
    off, peak = _figures(out, targets)
    worse = (off > planned[0]) | (peak > np.maximum(planned[1], own_peak))
    return np.concatenate([worse, [False]]) | np.concatenate([[False], worse])


def land_seen(
    render: Callable[[np.ndarray], tuple],
    used: np.ndarray,
    targets: np.ndarray,
    band: tuple[np.ndarray, np.ndarray],
    own_peak: float,
) -> tuple[np.ndarray, tuple]:
    """Move the landings' source pins ``used`` [s] so the output's motion beats fall on
    ``targets`` [s] (module docstring). ``render(pins)`` returns ``(warp, output motion,
    output times, source times)``; ``band`` the lowest and highest playback speed per
    interval the beat counts aimed at. A pin that leaves more output outside the speed
    band than the plan did, or joints faster than both the plan's and the dancer's own
    peak ``own_peak`` [unit / s], goes back. Returns the pins and their rendering."""
    planned = used
    speed = np.diff(used) / np.diff(targets)
    lo, hi = np.minimum(band[0], speed), np.maximum(band[1], speed)
    out = render(used)
    first = _figures(out, targets)
    best, best_err = used, np.full(used.size, np.inf)
    for round_ in range(SEEN_ROUNDS + 1):
        err, shown = seen_landings(out[1], targets, out[0].to_source)
        better = (err < best_err) & ~_spoilt(out, targets, first, own_peak)
        best = np.where(better, used, best)
        best_err = np.where(better, err, best_err)
        if round_ == SEEN_ROUNDS:
            break
        moved = np.where(better, shown, best)  # a landing that got worse goes back
        moved = _within(moved, best, planned, targets, lo, hi)
        if np.array_equal(moved, used) or not np.all(np.diff(moved) > 0):
            break
        used = moved
        out = render(used)
    best = _within(best, planned, planned, targets, lo, hi)
    if not np.array_equal(best, used):
        used, out = best, render(best)
        spoilt = _spoilt(out, targets, first, own_peak)
        if spoilt.any():
            used = np.where(spoilt, planned, used)
            out = render(used)
    return used, out
