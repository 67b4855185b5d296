"""Seamless loops: repeating a span of a clip so the dance covers a whole song.

Where to loop (:func:`choose_loop`)
    A clip with events ``e_0 < ... < e_P`` (period boundaries, or motion beats) is
    played once up to ``e_b`` and then its span ``[e_a, e_b]`` is repeated. The pair
    ``(a, b)`` is the one whose poses are most alike by paper B's motion-graph
    distance (:func:`beatsync.graph.distance.aligned_distance_matrix`, after Kovar et
    al. 2002: the joints' point clouds over a window around both events compared after
    the best rotation about the vertical axis and translation on the floor), among the
    pairs whose span holds at least ``MIN_SPAN`` of the clip's events (so the loop keeps
    most of the dance) and with half a blend window of clip on both sides (with none,
    the pair with room for the widest blend, the blend shrunk to it). With a dance meter
    of ``N`` motion beats, ``a`` and ``b - a`` are multiples of ``N`` (a loop starts a
    dance bar and holds whole bars).

The looped timeline
    ``t`` runs on from the clip: repetition ``r >= 1`` covers
    ``[e_b + (r-1) L, e_b + r L]``, ``L = e_b - e_a``, and shows the clip at
    ``e_a + (t - start_r)``. Its events are the clip's up to ``e_b``, then
    ``e_{a+1} .. e_b`` shifted by ``r L`` per repetition (whole intervals).

Aligned and blended joins
    Repetition ``r`` is moved by ``M^r``, ``M`` the rigid floor transform (rotation
    about the vertical axis, translation on the floor) that carries the pose at
    ``e_a`` onto the pose at ``e_b``: each pass starts where and facing where the
    previous one ended, so a dancer who travels or turns goes on instead of jumping
    back. Within ``join / 2`` of a join the pose blends the ending pass's continuation
    (clip time ``e_b + d``, moved by ``M^(r-1)``) into the starting pass's lead
    (``e_a + d``, moved by ``M^r``) with :func:`join_weight`. A skeleton's root is
    turned and moved (rotation channels and floor position), joint positions rotated
    and translated; rotations are blended by slerp, positions linearly.

Data contract: times in seconds of the clip (``e``) or of the looped timeline
(``t``); positions ``(frames, joints, 3)`` with z up (position-only motion) or the
skeleton's root channels with y up (BVH).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import ParameterError
from ..graph.distance import aligned_distance_matrix, ground_axes, point_clouds
from ..motion_beats import motion_positions
from ..rotations import blend_values, euler_to_rotation, rotation_to_euler, sample_motion
from .positions import interp_frames

__all__ = [
    "LoopedClip",
    "choose_loop",
    "join_weight",
    "joint_positions",
    "loop_events",
    "with_center",
]

#: width of the blended window at each join [s]
LOOP_BLEND_S = 0.6
#: shortest loop, as a share of the clip's events
MIN_SPAN = 0.5


@dataclass(frozen=True)
class LoopedClip:
    """A clip's span ``[first, last]`` [s] (``e_a``, ``e_b``; ``length`` ``L``) repeated
    ``repetitions`` times: the looped timeline's ``events`` [s] and each one's
    ``event_index`` in the clip; ``join`` [s], the blend width at each join; ``angle``
    [rad] and ``shift`` (position unit, on the floor axes of
    :func:`beatsync.graph.distance.ground_axes`; None without positions), the floor
    transform from one pass to the next; ``distance``, the pose distance at the join.
    """

    events: np.ndarray
    event_index: np.ndarray
    first: float
    last: float
    length: float
    repetitions: int
    join: float
    angle: float = 0.0
    shift: np.ndarray | None = None
    distance: float = float("nan")

    @property
    def join_times(self) -> np.ndarray:
        """Looped times of the joins [s]."""
        return self.last + np.arange(self.repetitions - 1) * self.length

    def locate(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(a, b, w, ra, rb)`` at looped times ``t``: the pose blends clip times ``a`` and
        ``b`` with weight ``w`` (0 away from joins) of repetitions ``ra`` and ``rb``."""
        t = np.asarray(t, dtype=np.float64)
        r = np.floor((t - self.last) / self.length) + 1.0  # repetition index (0: the clip)
        r = np.clip(r, 0.0, self.repetitions - 1.0)
        a = np.where(r == 0, t, self.first + (t - self.last - (r - 1.0) * self.length))
        b = a.copy()
        w = np.zeros_like(t)
        ra, rb = r, r.copy()
        half = 0.5 * self.join
        if half > 0 and self.repetitions > 1:
            joins = self.join_times
            k = np.clip(np.searchsorted(joins, t), 0, joins.size - 1)
            for kk in (k, np.maximum(k - 1, 0)):
                d = t - joins[kk]
                near = np.abs(d) < half
                a = np.where(near, self.last + d, a)
                b = np.where(near, self.first + d, b)
                u = np.clip((d + half) / (2.0 * half), 0.0, 1.0)
                w = np.where(near, join_weight(u), w)
                ra = np.where(near, kk, ra)  # join kk ends repetition kk, starts kk + 1
                rb = np.where(near, kk + 1.0, rb)
        return a, b, w, ra, rb

    @cached_property
    def _pass_moves(self) -> tuple[np.ndarray, np.ndarray]:
        """Rotation angle and floor translation of ``M^r``, per repetition ``r``."""
        n = self.repetitions
        ang = np.arange(n) * self.angle
        off = np.zeros((n, 2))
        if self.shift is not None:
            c, s = np.cos(self.angle), np.sin(self.angle)
            for r in range(1, n):  # M^r = M o M^(r-1): x -> R x + shift
                x, y = off[r - 1]
                off[r] = (c * x - s * y + self.shift[0], s * x + c * y + self.shift[1])
        return ang, off

    def _moves(self, reps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rotation angles and floor translations of ``M^r`` for each repetition."""
        ang, off = self._pass_moves
        idx = reps.astype(np.int64)
        return ang[idx], off[idx]

    def sample_positions(self, pos: np.ndarray, fps: float, t: np.ndarray) -> np.ndarray:
        """Positions ``(frames, points, 3)`` (z up) at looped times ``t``: interpolated
        linearly, each pass moved by ``M^r``, blended at the joins."""
        a, b, w, ra, rb = self.locate(t)
        out = _move(interp_frames(pos, fps, a), *self._moves(ra))
        blend = w > 0
        if blend.any():
            vb = _move(interp_frames(pos, fps, b[blend]), *(x[blend] for x in self._moves(rb)))
            wb = w[blend, None, None]
            out[blend] = (1.0 - wb) * out[blend] + wb * vb
        return out

    def sample(self, motion: object, t: np.ndarray) -> np.ndarray:
        """Values of ``motion`` at looped times ``t`` (each pass moved by ``M^r``,
        blended at the joins)."""
        if motion.is_positional:
            pos = motion.values.reshape(motion.n_frames, -1, 3)
            return self.sample_positions(pos, motion.fps, t).reshape(len(t), -1)
        a, b, w, ra, rb = self.locate(t)
        values = self._move_root(motion, sample_motion(motion, a), ra)
        blend = w > 0
        if blend.any():
            vb = self._move_root(motion, sample_motion(motion, b[blend]), rb[blend])
            values[blend] = blend_values(motion, values[blend], vb, w[blend])
        return values

    def _move_root(self, motion: object, values: np.ndarray, reps: np.ndarray) -> np.ndarray:
        """Skeleton motion: the root turned about the vertical (y) axis and moved on the
        floor by ``M^r`` (its position and its rotation channels)."""
        cols = _root_floor_columns(motion)
        if cols is None or self.shift is None:
            return values
        ang, off = self._moves(reps)
        if np.any(ang):
            zx = values[:, cols]
            c, s = np.cos(ang), np.sin(ang)
            values[:, cols[0]] = c * zx[:, 0] - s * zx[:, 1]
            values[:, cols[1]] = s * zx[:, 0] + c * zx[:, 1]
            root = motion.skeleton.joints[0].name
            for joint, idx, order in motion.rotation_triples():
                if joint == root:  # its rotation channels, turned about the vertical too
                    euler = values[:, list(idx)]
                    spin = Rotation.from_euler("y", ang[:, None])
                    turned = spin * euler_to_rotation(euler, order)
                    values[:, list(idx)] = rotation_to_euler(turned, order, reference=euler)
                    break
        values[:, cols] += off
        return values


def join_weight(u: np.ndarray) -> np.ndarray:
    """Blend weight over a join's window (phase ``u`` in [0, 1]): two raised-cosine
    half-ramps, 0 -> 1/2 -> 1, so ``w'`` vanishes at both ends and at the join itself,
    where the blend then adds no velocity and the landed speed minimum stays put."""
    c = 0.25 * np.cos(2.0 * np.pi * u)
    return np.where(u < 0.5, 0.25 - c, 0.75 + c)


def _move(p: np.ndarray, ang: np.ndarray, off: np.ndarray) -> np.ndarray:
    """Rotate ``p`` (frames, points, 3; z up) about the vertical axis by ``ang`` and
    translate it on the floor by ``off`` (per frame)."""
    if not np.any(ang) and not np.any(off):
        return p
    c, s = np.cos(ang)[:, None], np.sin(ang)[:, None]
    out = p.copy()
    out[:, :, 0] = c * p[:, :, 0] - s * p[:, :, 1] + off[:, 0:1]
    out[:, :, 1] = s * p[:, :, 0] + c * p[:, :, 1] + off[:, 1:2]
    return out


def _root_floor_columns(motion: object) -> np.ndarray | None:
    """The skeleton root's two horizontal position channels (y up), in the order of
    :func:`beatsync.graph.distance.ground_axes` (z, x), or None."""
    skeleton = getattr(motion, "skeleton", None)
    if skeleton is None:
        return None
    root = skeleton.joints[0].name
    names = (f"{root}_Zposition", f"{root}_Xposition")
    if not all(n in motion.channels for n in names):
        return None
    return np.array([motion.channels.index(n) for n in names])


def joint_positions(
    motion: object, positions: np.ndarray | None = None
) -> tuple[np.ndarray, int] | None:
    """Joint positions and the index of their vertical axis, or None (angle tables);
    ``positions``: the motion's, if already computed."""
    if motion.is_positional:
        return motion.values.reshape(motion.n_frames, -1, 3), 2
    if _root_floor_columns(motion) is None:
        return None
    if positions is not None:
        return positions, 1
    try:
        return motion_positions(motion), 1
    except ParameterError:
        return None


def choose_loop(
    motion: object,
    events: np.ndarray,
    *,
    join: float = LOOP_BLEND_S,
    dance: int | None = None,
    positions: np.ndarray | None = None,
) -> tuple[int, int, float, np.ndarray | None, float, float]:
    """Where to loop a clip (see the module docstring): ``(a, b, angle, shift, distance,
    join)``, ``a < b`` indexing ``events``, the rest as in :class:`LoopedClip` (``join``
    shortened only when the clip leaves no room for it); ``positions``: the motion's
    joint positions, if already computed."""
    p = events.size - 1
    duration = (motion.n_frames - 1) / motion.fps
    got = joint_positions(motion, positions)
    half_t = 0.5 * join
    room = (events - half_t >= 0) & (events + half_t <= duration)
    idx = np.nonzero(room)[0]
    ii, jj = np.meshgrid(idx, idx, indexing="ij")
    ok = jj - ii >= max(1, int(np.ceil(MIN_SPAN * p)))
    if dance is not None:
        ok &= (ii % dance == 0) & ((jj - ii) % dance == 0)
    ok &= events[jj] - events[ii] > 2.0 * join
    fit = float(min(join, 0.5 * np.min(np.diff(events))))
    if got is None:  # nothing to compare or to move: the whole span, blended over what fits
        return 0, p, 0.0, None, float("nan"), fit
    if not ok.any():
        # no pair with room for the whole blend: the pair with room for the widest, the
        # blend shrunk to it, so that it never reaches outside the clip (a T-pose first
        # frame, say); each pass still starts where the previous one ended
        ii, jj = np.meshgrid(np.arange(p + 1), np.arange(p + 1), indexing="ij")
        ok = jj - ii >= max(1, int(np.ceil(MIN_SPAN * p)))
        width = np.minimum(np.minimum(2.0 * events[ii], 2.0 * (duration - events[jj])), fit)
        width = np.where(ok, width, -np.inf)
        best = np.flatnonzero(width == width.max())
        pick = best[np.argmax((jj - ii).ravel()[best])]  # among equals the longest span
        idx = np.array([ii.flat[pick], jj.flat[pick]])
        join = max(float(width.flat[pick]), 0.0)
        ok = np.array([[False, True], [False, False]])
        ii, jj = np.meshgrid(idx, idx, indexing="ij")
    pos, up = got
    fps = float(motion.fps)
    frames = np.rint(events[idx] * fps).astype(np.int64)
    half = max(1, int(round(0.5 * join * fps / 2)))
    clouds = point_clouds(pos, frames, half)
    dist = aligned_distance_matrix(clouds, clouds, up=up)
    score = np.where(ok, dist, np.inf)
    # the most alike pair; among equals the longest span
    best = np.flatnonzero(score == score.min())
    pick = best[np.argmax((jj - ii).ravel()[best])]
    ia, ib = np.unravel_index(pick, score.shape)
    a, b = int(idx[ia]), int(idx[ib])
    # the floor rotation (about the vertical, in the plane of ground_axes: R_y for y up)
    # and translation that carry the clouds at e_a onto those at e_b
    g0, g1 = ground_axes(up)
    src = clouds[ia][:, [g0, g1]]
    dst = clouds[ib][:, [g0, g1]]
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    ps, pd = src - ms, dst - md
    angle = float(
        np.arctan2(
            np.sum(ps[:, 0] * pd[:, 1] - ps[:, 1] * pd[:, 0]),
            np.sum(ps[:, 0] * pd[:, 0] + ps[:, 1] * pd[:, 1]),
        )
    )
    c, s = np.cos(angle), np.sin(angle)
    shift = md - np.array([c * ms[0] - s * ms[1], s * ms[0] + c * ms[1]])
    return a, b, angle, shift, float(score.flat[pick]), float(join)


def loop_events(
    events: np.ndarray,
    n_needed: int,
    *,
    join: float,
    span: tuple[int, int],
    angle: float = 0.0,
    shift: np.ndarray | None = None,
    distance: float = float("nan"),
) -> LoopedClip:
    """Repeat the span ``events[a] .. events[b]`` (``span``) until
    the looped timeline holds ``n_needed`` intervals; ``join`` [s] is the blend width,
    ``angle``, ``shift`` and ``distance`` the floor transform of :func:`choose_loop`."""
    a, b = span
    head = events[: b + 1]
    per = b - a
    reps = 1 + max(0, -(-(int(n_needed) - b) // per))  # the clip, then enough passes
    length = float(events[b] - events[a])
    rel = events[a + 1 : b + 1] - events[a]
    parts = [head] + [events[b] + (r - 1) * length + rel for r in range(1, reps)]
    index = [np.arange(b + 1)] + [np.arange(a + 1, b + 1)] * (reps - 1)
    return LoopedClip(
        events=np.concatenate(parts),
        event_index=np.concatenate(index),
        first=float(events[a]),
        last=float(events[b]),
        length=length,
        repetitions=reps,
        join=float(join),
        angle=float(angle),
        shift=shift,
        distance=float(distance),
    )


def with_center(out: Any, motion: Any, src_times: np.ndarray, looped: LoopedClip | None) -> Any:
    """The output with the input's root track (``position_info.center``, the JSON
    layout's ``center``) resampled like the joints, so joints keep their place
    relative to it."""
    info = getattr(motion, "position_info", None)
    if info is None or info.center is None or len(info.center) != motion.n_frames:
        return out
    center = np.asarray(info.center, dtype=np.float64)[:, None, :]
    if looped is None:
        c = interp_frames(center, motion.fps, src_times)
    else:
        c = looped.sample_positions(center, motion.fps, src_times)
    return replace(out, position_info=replace(info, center=c[:, 0, :]), _cache={})
