"""Looping a clip's whole periods (or beat segments) so the dance covers a whole song.

A clip with events ``e_0 < ... < e_P`` (period boundaries, or motion beats) is played
once as it is up to ``e_P``, then its span ``[e_0, e_P]`` is repeated. The *looped
timeline* ``t`` runs on: repetition ``r >= 1`` covers ``[e_P + (r-1) L, e_P + r L]``,
``L = e_P - e_0``, and shows the clip at ``e_0 + (t - start_r)``. The events of the
looped timeline are the clip's events, then ``e_1 .. e_P`` shifted by ``r L`` per
repetition, so every repetition brings whole periods.

Joins are blended: within ``join/2`` of a join at ``J``, the pose is the blend of the
ending repetition's continuation (clip time ``e_P + (t - J)``) and the starting one's
lead (``e_0 + (t - J)``) with a raised-cosine weight going 0 -> 1 across the window
(quaternion slerp for rotations, linear for positions; see
:func:`beatsync.rotations.blend_values`). Clip times outside the clip are held at its
ends; the held part carries little weight near the window's edges. Period boundaries
are similar poses by construction, so the blend is short and gentle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..rotations import blend_values, sample_motion

__all__ = ["LoopedClip", "loop_events"]


@dataclass(frozen=True)
class LoopedClip:
    """A clip's span of events repeated ``repetitions`` times in a looped timeline.

    Attributes
    ----------
    events : np.ndarray [s]
        Events in the looped timeline (the clip's, then each repetition's).
    first : float [s]
        ``e_0``, the clip's first event.
    last : float [s]
        ``e_P``, the clip's last event (the first join).
    length : float [s]
        ``L = e_P - e_0``, the span repeated.
    repetitions : int >= 1
        Passes through the span (1: the clip as it is).
    join : float [s]
        Width of the blended window around each join.
    """

    events: np.ndarray
    first: float
    last: float
    length: float
    repetitions: int
    join: float

    def source_times(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Clip times for looped times ``t``: ``(a, b, w)``, pose = blend(a, b, w).

        ``w`` is 0 away from joins (pose at clip time ``a``).
        """
        t = np.asarray(t, dtype=np.float64)
        r = np.floor((t - self.last) / self.length) + 1.0  # repetition index (0: the clip)
        r = np.clip(r, 0.0, self.repetitions - 1.0)
        a = np.where(r == 0, t, self.first + (t - self.last - (r - 1.0) * self.length))
        b = a.copy()
        w = np.zeros_like(t)
        half = 0.5 * self.join
        if half > 0 and self.repetitions > 1:
            joins = self.last + np.arange(self.repetitions - 1) * self.length
            k = np.clip(np.searchsorted(joins, t), 0, joins.size - 1)
            for kk in (k, np.maximum(k - 1, 0)):
                d = t - joins[kk]
                near = np.abs(d) < half
                a = np.where(near, self.last + d, a)
                b = np.where(near, self.first + d, b)
                u = np.clip((d + half) / (2.0 * half), 0.0, 1.0)
                w = np.where(near, 0.5 - 0.5 * np.cos(np.pi * u), w)
        return a, b, w

    def sample(self, motion: object, t: np.ndarray) -> np.ndarray:
        """Values of ``motion`` at looped times ``t`` (blended at the joins)."""
        a, b, w = self.source_times(t)
        values = sample_motion(motion, a)
        blend = w > 0
        if blend.any():
            vb = sample_motion(motion, b[blend])
            values[blend] = blend_values(motion, values[blend], vb, w[blend])
        return values


def loop_events(events: np.ndarray, n_needed: int, *, join: float) -> LoopedClip:
    """Repeat the span of ``events`` until it has at least ``n_needed`` intervals.

    Parameters
    ----------
    events : np.ndarray [shape=(P+1,), P >= 1] [s]
        The clip's events (checked, increasing).
    n_needed : int >= 1
        Intervals (periods or beat segments) the looped timeline must hold.
    join : float >= 0 [s]
        Width of the blended window around each join (capped at half the shortest
        interval).

    Returns
    -------
    LoopedClip
    """
    p = events.size - 1
    reps = max(1, -(-int(n_needed) // p))  # ceil
    length = float(events[-1] - events[0])
    rel = events[1:] - events[0]
    parts = [events] + [events[-1] + (r - 1) * length + rel for r in range(1, reps)]
    join = float(min(join, 0.5 * np.min(np.diff(events))))
    return LoopedClip(
        events=np.concatenate(parts),
        first=float(events[0]),
        last=float(events[-1]),
        length=length,
        repetitions=reps,
        join=join,
    )
