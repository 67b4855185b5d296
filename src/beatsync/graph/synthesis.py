"""Synthesis of a composed dance from a graph path (paper B, section 3.5).

Every chosen interval (beat frame ``f_k`` to the next beat frame of its clip) is
time-warped onto its music beat interval ``[b_k, b_{k+1}]``, so each motion beat lands
exactly on its music beat:
``s(t) = f_k / fps + (t - b_k) / (b_{k+1} - b_k) * (f_{k+1} - f_k) / fps``
(or a monotone cubic through the same points), sampled with
:func:`beatsync.rotations.sample_motion`. Runs of consecutive intervals of one clip
play as captured; at a transition (beat frame ``a`` to ``m``) the new run is placed by
the rigid floor-plane transform that puts its root at ``m`` where the old run's is at
``a``, same heading (Kovar et al. 2002), and the old run, continued past ``a``, is
blended into it over ``blend`` seconds with smooth-step weights
(:func:`beatsync.rotations.blend_values`). The first and last intervals' warps extend
to ``start_time`` and ``end_time``; frame ``j`` plays at ``j / fps`` s of the music.

Notebook: ``notebooks/paper_b_tab02_quality_proxies.ipynb``; paper B section 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import ParameterError
from ..motion import Motion
from ..quaternions import quat_from_euler, quat_multiply
from ..rotations import (
    blend_values,
    continuous_euler,
    euler_to_rotation,
    rotation_to_euler,
    sample_motion,
)
from ..validation import (
    as_float,
    check_choice,
    check_fps,
    check_times,
    frames_to_time,
    time_to_frames,
)
from .build import WeightedMotionGraph
from .distance import ground_axes

__all__ = [
    "SynthesisResult",
    "synthesize",
    "synthesize_core",
    "check_output",
    "beat_warp",
]


@dataclass(frozen=True, eq=False)
class SynthesisResult:
    """A composed motion and where each output frame came from.

    ``source_clip`` and ``source_time`` [s]: the clip and time each output frame was
    sampled from; ``transition_times`` [s]: music beats where a transition (and its
    blend) starts; ``beat_source_times`` [s]: the source time of every music beat.
    """

    motion: Motion
    source_clip: np.ndarray
    source_time: np.ndarray
    transition_times: np.ndarray
    beat_source_times: np.ndarray
    info: dict = field(default_factory=dict)


def beat_warp(
    music_beats: np.ndarray, src_start: np.ndarray, src_end: np.ndarray, times: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Piecewise-linear warp from music time to source time: ``(k, s)`` per time.

    ``src_start``, ``src_end`` [s] are the source times of the beat frames that start and
    end each interval; ``k`` is the interval of each time (clipped to 0..K-1) and ``s``
    its source time, with ``s(b_k) = src_start[k]`` exactly.
    """
    k_n = src_start.size
    k = np.clip(np.searchsorted(music_beats, times, side="right") - 1, 0, k_n - 1)
    rate = (src_end - src_start) / np.diff(music_beats)
    s = src_start[k] + (times - music_beats[k]) * rate[k]
    return k, s


def _heading(rot: Rotation, up: int) -> np.ndarray:
    """Heading angle [rad] about the up axis of the root's local forward axis."""
    g0, g1 = ground_axes(up)
    fwd = np.zeros(3)
    fwd[g0] = 1.0  # local axis lying on the floor in the rest pose (z for y-up)
    v = rot.apply(fwd)
    return np.arctan2(v[..., g1], v[..., g0])


def synthesize(
    graph: WeightedMotionGraph,
    path: Any,
    music_beats: Any,
    *,
    fps: float | None = None,
    blend: float = 1.0 / 3.0,
    start_time: float = 0.0,
    end_time: float | None = None,
    warp: str = "pchip",
) -> SynthesisResult:
    """Concatenate, warp and blend the chosen intervals into one motion.

    ``path`` ``(K,)``: interval nodes for the ``K = len(music_beats) - 1`` intervals;
    ``fps``: default the library's; ``blend`` [s]: capped at the interval's duration;
    ``start_time``, ``end_time`` [s]: default 0 and the last beat; ``warp``: piecewise
    linear (the rate jumps at every beat) or monotone cubic (continuous rate).
    """
    beats = check_times(music_beats, name="music beats")
    path = np.asarray(path, dtype=np.int64)
    if beats.size < 2:
        raise ParameterError(f"the music has {beats.size} beat(s): nothing to compose")
    if path.shape != (beats.size - 1,):
        raise ParameterError(
            f"path has {path.size} nodes for {beats.size - 1} music intervals "
            "(one node per interval between successive beats)"
        )
    if np.any(path < 0) or np.any(path >= graph.n_nodes) or not graph.is_interval[path].all():
        raise ParameterError("path contains nodes that do not start an interval")
    fps, blend, end_time = check_output(graph, beats, fps, blend, warp, start_time, end_time)
    return synthesize_core(graph, path, beats, fps, blend, start_time, end_time, warp)


def check_output(graph, beats, fps, blend, warp, start_time, end_time):
    """``(fps, blend, end_time)`` of the output motion (defaults: the library's, last beat)."""
    blend = as_float(blend, name="blend", unit="s")
    if blend < 0 or blend > 5:
        raise ParameterError(f"blend={blend!r} must be a duration in [0, 5] [s]")
    check_choice(warp, ("pchip", "linear"), name="warp")
    end_time = float(beats[-1]) if end_time is None else float(end_time)
    if not end_time > start_time >= 0:
        raise ParameterError(f"end_time={end_time!r} must be > start_time={start_time!r} >= 0")
    return check_fps(graph.clips[0].fps if fps is None else fps), blend, end_time


def synthesize_core(graph, path, beats, fps, blend, start_time, end_time, warp):
    """:func:`synthesize` on validated inputs (the compose path calls this directly)."""
    template = graph.clips[0]
    up = "xyz".index(graph.params.get("up_axis", "y"))
    g0, g1 = ground_axes(up)
    root = template.skeleton.joints[0].name
    pos_cols = []
    for ax in "XYZ":
        if f"{root}_{ax}position" not in template.channels:
            raise ParameterError(
                f"the root joint {root!r} has no {ax}position channel: cannot place the "
                "dancer on the floor"
            )
        pos_cols.append(template.channel_index(f"{root}_{ax}position"))
    triples = [(list(idx), order) for j, idx, order in template.rotation_triples() if j == root]
    if not triples:
        raise ParameterError(f"the root joint {root!r} has no rotation triple")
    rot_cols, order = triples[0]

    k_n = path.size
    node_t = graph.node_time()  # [s] in each node's clip (one frame rate per library)
    clip_of = graph.node_clip[path]
    src_start = node_t[path]
    nxt = graph.next_node[path]
    src_end = node_t[nxt]
    trans = np.zeros(k_n, dtype=bool)
    trans[1:] = graph.next_node[path[:-1]] != path[1:]
    run_id = np.cumsum(trans)

    j0 = int(time_to_frames(start_time, fps=fps, mode="ceil"))
    j1 = int(time_to_frames(end_time, fps=fps, mode="floor"))
    t = frames_to_time(np.arange(j0, j1 + 1), fps=fps)
    k_of, s_of = beat_warp(beats, src_start, src_end, t)
    run_of = run_id[k_of]
    if warp == "pchip":  # a monotone cubic through the beat correspondences of each run
        from scipy.interpolate import PchipInterpolator

        for r in np.unique(run_id):
            ks = np.flatnonzero(run_id == r)
            if ks.size < 2:
                continue
            x = beats[ks[0] : ks[-1] + 2]
            y = np.concatenate([src_start[ks], src_end[ks[-1:]]])
            # times before the first beat / after the last beat of the run keep the
            # linear warp's extrapolation (lead-in and tail of the dance)
            inside = (run_of == r) & (t >= x[0]) & (t <= x[-1])
            s_of[inside] = PchipInterpolator(x, y)(t[inside])

    # rigid floor transforms per run: yaw angle and ground translation
    n_runs = int(run_id[-1]) + 1
    yaw = np.zeros(n_runs)
    shift = np.zeros((n_runs, 3))
    run_first_k = np.flatnonzero(np.concatenate([[True], trans[1:]]))

    def raw_root(clip: int, frame: int) -> tuple[np.ndarray, Rotation]:
        v = graph.clips[clip].values[frame]  # beat frames lie on frames: no sampling
        return v[pos_cols], euler_to_rotation(v[rot_cols][None, :], order)

    axis = np.eye(3)[up]  # the vertical axis
    for r in range(1, n_runs):
        k = run_first_k[r]
        # previous run ends on beat frame a (= next_node[path[k-1]]) of its clip
        a = graph.next_node[path[k - 1]]
        pa, ra = raw_root(graph.node_clip[a], graph.node_frame[a])
        pb, rb = raw_root(clip_of[k], graph.node_frame[path[k]])
        turn = Rotation.from_rotvec(yaw[r - 1] * axis)
        yaw[r] = _heading(turn * ra, up)[0] - _heading(rb, up)[0]
        target = turn.apply(pa)
        target[[g0, g1]] += shift[r - 1, [g0, g1]]
        moved = Rotation.from_rotvec(yaw[r] * axis).apply(pb)
        shift[r, [g0, g1]] = target[[g0, g1]] - moved[[g0, g1]]

    def transformed(runs: np.ndarray, clips: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Samples of the given clips at source times, placed by their runs' transforms."""
        v = np.empty((s.size, template.n_channels))
        for c in np.unique(clips):
            sel = clips == c
            v[sel] = sample_motion(graph.clips[int(c)], s[sel])
        moved = (yaw[runs] != 0.0) | np.any(shift[runs] != 0.0, axis=1)
        if not moved.any():
            return v
        vm = v[moved]
        rm = runs[moved]
        turn = Rotation.from_rotvec(yaw[rm][:, None] * axis[None, :])
        p = turn.apply(vm[:, pos_cols])
        p[:, [g0, g1]] += shift[rm][:, [g0, g1]]
        vm[:, pos_cols] = p
        rot = Rotation.from_quat(
            quat_multiply(turn.as_quat(), quat_from_euler(vm[:, rot_cols], order))
        )
        vm[:, rot_cols] = rotation_to_euler(rot, order, reference=vm[:, rot_cols])
        v[moved] = vm
        return v

    values = transformed(run_of, clip_of[k_of], s_of)

    # blends after every transition, within its music interval: the frames of interval k
    # within blend of its start, with the old run continued past its beat frame a
    trans_times = beats[:-1][trans]
    length = np.minimum(blend, np.diff(beats))
    sel = np.flatnonzero(trans[k_of] & (t >= beats[k_of]) & (t < beats[k_of] + length[k_of]))
    if sel.size:
        k = k_of[sel]
        a = graph.next_node[path[k - 1]]
        rate = (src_end[k] - src_start[k]) / (beats[k + 1] - beats[k])
        old = transformed(run_id[k] - 1, graph.node_clip[a], node_t[a] + (t[sel] - beats[k]) * rate)
        x = np.clip((t[sel] - beats[k]) / length[k], 0.0, 1.0)
        # smooth step: zero slope at both ends
        values[sel] = blend_values(template, old, values[sel], x * x * (3.0 - 2.0 * x))

    # continuous Euler curves in the output file: the root's triples were re-derived
    # after the yaw alignment, so choose each frame's triple closest to the previous one
    values[:, rot_cols] = continuous_euler(values[:, rot_cols])
    for _joint, idx, _order in template.rotation_triples():
        cols = list(idx)
        values[:, cols] = np.unwrap(values[:, cols], period=360.0, axis=0)

    motion = Motion(
        values=values,
        fps=fps,
        channels=template.channels,
        skeleton=template.skeleton,
        name="composed",
    )
    beat_src = np.concatenate([src_start, src_end[-1:]])
    return SynthesisResult(
        motion=motion,
        source_clip=clip_of[k_of],
        source_time=s_of,
        transition_times=trans_times,
        beat_source_times=beat_src,
        info={"n_runs": n_runs, "start_frame": j0, "blend_s": blend},
    )
