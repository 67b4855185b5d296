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

Travel is carried across joins: repetition ``r`` is moved along the floor by ``r``
times the clip's ground travel over its span (root position at ``e_P`` minus at
``e_0``), so a dancer who moves across the floor goes on from where the previous pass
ended instead of jumping back to the start (a walk looped without it teleported 3.45 m
at every join, at up to 28 m/s). The floor is the plane of the non-vertical axes: y is
up in skeleton (BVH) motion, z in position-only motion (see :mod:`beatsync.motion`);
the travel of position-only motion is that of the joints' centroid, and every joint is
moved. A turn over the span is not carried on (each pass starts at the clip's
heading), and motion without positions (angle tables) is looped as it is.
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
        return self._locate(t)[:3]

    def _locate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(a, b, w, ra, rb)``: clip times, blend weight and repetitions at ``t``."""
        t = np.asarray(t, dtype=np.float64)
        r = np.floor((t - self.last) / self.length) + 1.0  # repetition index (0: the clip)
        r = np.clip(r, 0.0, self.repetitions - 1.0)
        a = np.where(r == 0, t, self.first + (t - self.last - (r - 1.0) * self.length))
        b = a.copy()
        w = np.zeros_like(t)
        ra, rb = r, r.copy()
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
                ra = np.where(near, kk, ra)  # join kk ends repetition kk, starts kk + 1
                rb = np.where(near, kk + 1.0, rb)
        return a, b, w, ra, rb

    def sample(self, motion: object, t: np.ndarray) -> np.ndarray:
        """Values of ``motion`` at looped times ``t`` (moved by the travel of the
        repetitions before, blended at the joins)."""
        a, b, w, ra, rb = self._locate(t)
        travel = _floor_travel(motion, self.first, self.last)
        values = sample_motion(motion, a)
        if travel is not None:
            values[:, travel[0]] += ra[:, None] * travel[1]
        blend = w > 0
        if blend.any():
            vb = sample_motion(motion, b[blend])
            if travel is not None:
                vb[:, travel[0]] += rb[blend, None] * travel[1]
            values[blend] = blend_values(motion, values[blend], vb, w[blend])
        return values


def _floor_travel(
    motion: object, start: float, stop: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """Ground travel of ``motion`` from clip time ``start`` to ``stop`` [s].

    Returns ``(columns, step)``: the value columns holding floor coordinates and what
    to add to them per repetition; None for motion without positions. Skeleton motion:
    the root's two horizontal position channels (y up); position-only motion: every
    joint's x and y (z up), moved by the travel of the joints' centroid.
    """
    ends = sample_motion(motion, np.array([start, stop], dtype=np.float64))
    if motion.is_positional:
        n_joints = ends.shape[1] // 3
        xy = ends.reshape(2, n_joints, 3)[:, :, :2].mean(axis=1)  # centroid on the floor
        cols = (3 * np.arange(n_joints)[:, None] + np.arange(2)[None, :]).ravel()
        return cols, np.tile(xy[1] - xy[0], n_joints)
    skeleton = motion.skeleton
    if skeleton is None:
        return None
    root = skeleton.joints[0].name
    names = (f"{root}_Xposition", f"{root}_Zposition")
    if not all(n in motion.channels for n in names):
        return None
    cols = np.array([motion.channels.index(n) for n in names])
    return cols, ends[1, cols] - ends[0, cols]


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
