"""Beats mode: land the motion beats a viewer sees, not only those the source showed.

A motion beat is a minimum of the Gaussian-smoothed mean joint speed
(:func:`beatsync.motion_beats.kinematic_beats`, sigma 0.1 s). The output's joint speed
is the source's times the playback speed ``1 / r`` (``r`` the warp's rate, music time
per source time), so the warp can fill a minimum in or move it:

- **A falling playback speed fills a shallow dip.** With ``V_min`` the smoothed speed
  at a landing, ``V_peak`` the highest in an interval beside it (``P = V_peak / V_min``)
  and ``m`` that interval's rate, the output shows about ``V_peak / m`` beside
  ``V_min / r`` at the landing: the dip keeps a depth ratio of about ``P r / m``.
  :func:`dip_floor` holds ``r >= m / sqrt(P)`` on both sides, so about half of every
  dip's log depth stays (exactly, were the peak played at the interval's mean rate).
  Where that makes an interval play faster than the band's top in its middle,
  :func:`release_floor` gives the band priority.
- **The smoothing reaches past the held rate** (``LANDING_HOLD`` is one sigma), so
  the output's minimum can sit a frame or two off its beat. :func:`land_seen` finds
  the output's motion beats (to a sub-frame, the parabola through the minimum and its
  neighbours) and moves each landing's source pin so that its minimum falls on the
  output frame nearest its beat (the frame a viewer can see it on; aimed at the beat
  itself, a minimum a little off lands on the wrong frame), over ``SEEN_ROUNDS``
  rounds; each landing keeps the best of its pins. A move is shortened so that no
  interval's mean speed leaves the band the beat counts aimed at (their peak headroom
  included), and a landing beside an interval that the move left with more output
  outside 0.8-1.25 keeps its pin. Every round, and the landings' best pins together,
  are measured; of those with no more output outside the band than the plan (counted
  per interval, the lead-in and the run-on included), the one with the most minima
  within half a frame of their frames, then the best music-side alignment Gaussian
  (summed), wins.
- **Neighbours on shallow dips push each other off.** Moving a landing onto its frame
  can move its neighbour's minimum off, so the rounds stop there. Then the pin of each
  landing still off its frame, and its neighbours', move one at a time: a half frame,
  then a frame, ... up to ``REFINE_STEPS`` half frames in one direction while each move
  is better, then the other, each kept when the output around it (eq. 9's reach,
  ``REFINE_REACH`` widths, on the warp of the landings within it) scores better with no
  more output off the band; the pins so moved are kept when the whole output measures
  better too.

The rounds are judged on a cheap view of the output, the source's joint positions
sampled linearly (:func:`position_view`); the output itself is made once, at the end.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..graph.distance import ground_axes
from ..graph.timescale import DEFAULT_SCALE_BOUND
from .positions import interp_frames
from .quality import live_steps, seen_landings

__all__ = [
    "SEEN_ROUNDS",
    "source_speed",
    "position_view",
    "dip_floor",
    "release_floor",
    "land_seen",
]

#: rounds of measuring the output's motion beats and moving the pins
SEEN_ROUNDS = 2
#: then each pin beside a landing still off its frame tries moves of up to this many
#: half output frames either way, over at most ``REFINE_SWEEPS`` passes
REFINE_STEPS = 4
REFINE_SWEEPS = 3
#: a move is judged on the output within this many of eq. 9's widths of the landings
#: beside it, on the warp of the landings within as many again and one more on each
#: side: eq. 9's Gaussian weights fall below exp(-4.5) of their own there (the widths
#: are source seconds, taken here as music seconds) ...
REFINE_REACH = 3.0
#: ... and the motion-beat detector's reach [s] (its smoothing and prominence window)
REFINE_EDGE = 0.5
#: width of the landings' score [s]: the published alignment scores' (3 frames at 60 fps)
SCORE_SIGMA = 0.05
#: samples per interval when looking for its speed peak
_PEAK_SAMPLES = 33


def source_speed(curve: np.ndarray, fps: float, looped: Any) -> Callable:
    """The source's smoothed mean joint speed (its :func:`speed_curve` at ``fps``) as a
    function of (looped, :class:`.fill.LoopedClip` or None) source times [s]."""

    def speed_at(t: np.ndarray) -> np.ndarray:
        if looped is None:
            return interp_frames(curve, fps, t)
        a, b, w = looped.locate(t)[:3]
        return (1.0 - w) * interp_frames(curve, fps, a) + w * interp_frames(curve, fps, b)

    return speed_at


def position_view(pos: np.ndarray, up: int, fps: float, looped: Any) -> Callable:
    """The output's joint positions at (looped) source times [s], sampled linearly from
    the source's ``pos`` (vertical axis ``up``) and, looped, moved and blended as the
    loop moves them; axes reordered (speeds do not change)."""
    g0, g1 = ground_axes(up)
    floor_first = pos[..., [g0, g1, up]]  # the loop's moves turn the first two axes

    def at(t: np.ndarray) -> np.ndarray:
        if looped is None:
            return interp_frames(pos, fps, t)
        return looped.sample_positions(floor_first, fps, t)

    return at


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


def release_floor(
    warp: Any, pins: np.ndarray, targets: np.ndarray, floor: np.ndarray, top: np.ndarray
) -> np.ndarray | None:
    """``floor`` lowered to an interval's own rate at both its ends wherever ``warp``
    plays the interval faster than its ``top`` (per interval) somewhere: held at a slower
    neighbour's rate, a landing makes the interval beside it make up its time in its
    middle, and the speed band comes before a dip's depth. None when no interval does."""
    k = np.searchsorted(pins, warp.src, side="right") - 1
    inside = (k >= 0) & (k < pins.size - 1)
    fastest = np.zeros(pins.size - 1)
    np.maximum.at(fastest, k[inside], 1.0 / warp.rate[inside])
    over = np.nonzero(fastest > top)[0]
    if over.size == 0:
        return None
    rate = np.diff(targets) / np.diff(pins)
    lower = floor.copy()
    np.minimum.at(lower, over, rate[over])
    np.minimum.at(lower, over + 1, rate[over])
    return lower


def _within(moved, kept, planned, targets, lo, hi):
    """``moved`` pins shortened towards ``kept`` until every interval's speed lies in
    ``[lo, hi]`` (per interval); the ends of an interval that still does not, back to
    the ``planned`` pins (whose speeds do)."""
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
        share = np.where(np.isfinite(share), share, 0.0) * frac[bad]
        frac[bad] = np.minimum(frac[bad], share)
        frac[bad + 1] = np.minimum(frac[bad + 1], share)
    for _ in range(moved.size):
        speed = np.diff(pins) / dur
        bad = np.nonzero((speed < lo) | (speed > hi))[0]
        if bad.size == 0:
            break
        pins[bad], pins[bad + 1] = planned[bad], planned[bad + 1]
    return pins


def _off_band(view: tuple, fps: float, targets: np.ndarray) -> np.ndarray:
    """Output frames per interval between ``targets`` played outside the speed band,
    wherever the warp plays (its lead-in in the first interval, its run-on in the last;
    ``view``: positions, output and source times of consecutive output frames, the
    warp)."""
    _, out_times, src_times, warp = view
    live = live_steps(out_times, (warp.tgt[0], warp.tgt[-1]))
    speed = np.diff(src_times)[live] * fps
    off = (speed < DEFAULT_SCALE_BOUND[0]) | (speed > DEFAULT_SCALE_BOUND[1])
    k = np.clip(np.searchsorted(targets, out_times[1:][live]) - 1, 0, targets.size - 2)
    return np.bincount(k, weights=off, minlength=targets.size - 1)


def land_seen(
    view: Callable[..., tuple],
    fps: float,
    used: np.ndarray,
    targets: np.ndarray,
    band: tuple[float, np.ndarray],
) -> tuple[np.ndarray, Any]:
    """The landings' source pins (from ``used`` [s]) whose output shows its motion beats
    on ``targets`` [s] (module docstring), and their warp. ``view(pins, span=None,
    part=None)`` returns the output's joint positions, output times and source times at
    ``fps`` (of the frames within ``span`` [s]), and the warp (of the landings ``part``,
    ``(a, b)``, only); ``band`` the lowest and highest playback speed per interval the
    beat counts aimed at."""
    speed = np.diff(used) / np.diff(targets)
    lo, hi = np.minimum(band[0], speed), np.maximum(band[1], speed)

    def measure(pins):
        """Landing errors, the source times to pin (those that put the seen minima on
        their frames), output frames outside the band, the warp."""
        look = view(pins)
        err, off_aim = seen_landings(look[0], fps, targets)
        shown = np.interp(targets + off_aim, look[1], look[2])
        return err, shown, _off_band(look, fps, targets), look[3]

    def score(err):
        """Minima on their frames (within half a frame), then the music-side alignment
        score's Gaussian, summed."""
        hits = int(np.count_nonzero(err <= 0.5 / fps))
        return hits, float(np.sum(np.exp(-(err * err) / (2.0 * SCORE_SIGMA**2))))

    err, shown, off0, warp = measure(used)
    rounds = [(score(err), used, warp)]  # measured pins with no more output off the band
    best, best_err, better, pins = used, err, np.isfinite(err), used  # per landing
    for _ in range(SEEN_ROUNDS):
        moved = _within(np.where(better, shown, best), best, used, targets, lo, hi)
        if np.array_equal(moved, pins) or not np.all(np.diff(moved) > 0):
            break
        pins = moved
        err, shown, off, warp = measure(pins)
        if off.sum() <= off0.sum():
            rounds.append((score(err), pins, warp))
        worse = off > off0  # a landing beside such an interval keeps its pin
        better = (err < best_err) & ~np.concatenate([worse, [False]])
        better &= ~np.concatenate([[False], worse])
        best = np.where(better, pins, best)
        best_err = np.where(better, err, best_err)
    # the landings' best pins together, measured too: pins act on their neighbours
    mix = _within(best, used, used, targets, lo, hi)
    if not any(np.array_equal(mix, r[1]) for r in rounds) and np.all(np.diff(mix) > 0):
        err, _, off, warp = measure(mix)
        if off.sum() <= off0.sum():
            rounds.append((score(err), mix, warp))
    chosen, pins, warp = max(rounds, key=lambda r: r[0])
    refined = _refine(view, fps, pins, targets, warp.delta, score, off0.sum())
    if refined is not None:  # the whole output decides, as it does for the rounds
        err, _, off, r_warp = measure(refined)
        if off.sum() <= off0.sum() and score(err) > chosen:
            return refined, r_warp
    return pins, warp


def _refine(view, fps, pins, targets, delta, score, off_budget):
    """The rounds' ``pins`` refined one at a time (module docstring): each pin of, or
    beside, a landing still off its frame moves by a half frame, then a frame, ... up to
    ``REFINE_STEPS`` half frames in one direction while each move measures better
    (``score``: minima on their frames, then the Gaussian) with no more output off the
    band than ``off_budget`` frames in all, then in the other; a direction is given up
    when a whole frame brings nothing. None if no move helped.

    Moving a pin changes the warp only within a few of eq. 9's widths (``delta`` [s]) of
    it, so each move is measured there, on the warp of the landings within as many widths
    again (the whole output's, away from its ends)."""
    blend = REFINE_REACH * delta
    reach = blend + REFINE_EDGE
    half = 0.5 / fps

    def window(p, span):
        """Score, frames off the band and landing errors of the output within ``span``."""
        part = None
        if span[0] > targets[0] - reach or span[1] < targets[-1] + reach:
            a = max(int(np.searchsorted(targets, span[0] - blend)) - 1, 0)
            b = min(int(np.searchsorted(targets, span[1] + blend, side="right")) + 1, p.size)
            part = (a, b)
        look = view(p, span, part)
        inside = (targets >= span[0] + REFINE_EDGE) & (targets <= span[1] - REFINE_EDGE)
        first = int(round(look[1][0] * fps))
        err, _ = seen_landings(look[0], fps, targets[inside], first)
        return score(err), int(_off_band(look, fps, targets).sum()), err

    start = pins
    for _ in range(REFINE_SWEEPS):
        _, off, err = window(pins, (-np.inf, np.inf))
        spare, moved = off_budget - off, False
        far = np.nonzero(err > half)[0]
        for i in sorted({j for k in far for j in (k - 1, k, k + 1) if 0 <= j < pins.size}):
            span = (targets[max(i - 1, 0)] - reach, targets[min(i + 1, pins.size - 1)] + reach)
            base, base_off, _ = window(pins, span)
            origin = pins[i]
            for sign in (1.0, -1.0):
                went = False
                for m in range(1, REFINE_STEPS + 1):
                    p = pins.copy()
                    p[i] = origin + sign * m * half
                    if not np.all(np.diff(p) > 0):
                        break
                    got, got_off, _ = window(p, span)
                    if got > base and got_off - base_off <= spare:
                        spare -= got_off - base_off
                        pins, base, base_off, moved, went = p, got, got_off, True, True
                    elif went or m >= 2:
                        break
                if went:
                    break
        if not moved:
            break
    return None if pins is start else pins
