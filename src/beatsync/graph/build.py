"""Construction of the weighted motion graph of paper B (section 3.2, eqs. 1-2).

Nodes are the beat frames of every clip of a library (one skeleton structure and
frame rate). *Forward edges* join successive beat frames of a clip, with the motion
intensity of their interval (:func:`beatsync.motion_beats.interval_intensity`),
z-scored over the library; a node that starts one is an *interval node*. *Transition
edges* join two beat frames ``i != j`` (either direction, across or within clips) with
``rd(i, j) < TH`` (eq. 1, ``TH = 3.0``), weighted by eq. 2 as written,
``w2 = rd if rd > 2 else 2`` (``weight_rule="paper"``), or ``w2 = rd`` (``"rd"``).

The frame distance ``rd`` (eq. 1): after Kovar, Gleicher and Pighin (2002), ``D``
[position unit] is the RMS distance of the point clouds of all joints over a
``window`` [s] around each frame after the best rotation about the vertical axis and
translation on the floor (:mod:`beatsync.graph.distance`), made scale-free::

    rd = D / (v_typ * rd_unit),

with ``v_typ`` [position unit / s] the median aligned distance between consecutive
frames times ``fps`` and ``rd_unit = 0.1`` s: ``rd < 3`` accepts pose jumps of at most
what the dancer typically covers in 0.3 s, about the 1/3 s of a transition's blend.

Notebook: ``notebooks/paper_b_tab01_search_speed.ipynb``; paper B section 3.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError, silenced, warn
from ..motion_beats import interval_intensity, kinematic_beat_frames, motion_positions, zscore
from ..validation import (
    check_choice,
    check_fps,
    check_positive,
    check_times,
    frames_to_time,
    time_to_frames,
)
from .distance import aligned_distance_matrix, point_clouds, typical_speed

__all__ = [
    "WeightedMotionGraph",
    "build_graph",
    "check_library",
    "check_th",
    "transition_weight",
    "WEIGHT_RULES",
]

WEIGHT_RULES = ("paper", "rd")
# the graph's arrays, as stored in the on-disk cache
_ARRAYS = (
    "node_clip",
    "node_frame",
    "next_node",
    "intensity",
    "z_intensity",
    "trans_src",
    "trans_dst",
    "trans_rd",
    "trans_weight",
)


def transition_weight(rd: Any, rule: str = "paper") -> np.ndarray:
    """Eq. 2: ``w2 = rd if rd > 2 else 2`` (``"paper"``) or ``w2 = rd`` (``"rd"``)."""
    check_choice(rule, WEIGHT_RULES, name="weight_rule")
    rd = np.asarray(rd, dtype=np.float64)
    if rule == "paper":
        return np.where(rd > 2.0, rd, 2.0)
    return rd.copy()


@dataclass(frozen=True, eq=False)
class WeightedMotionGraph:
    """A weighted motion graph over the beat frames of a motion library (module docstring).

    Per node ``(N,)``: ``node_clip``, ``node_frame`` [frames], ``next_node`` (the next beat
    node of its clip, -1 at a clip's last beat), ``intensity`` [(unit / s)^2] and
    ``z_intensity`` of the interval it starts (NaN at last beats). Per directed transition
    ``(E,)`` (each two-way edge twice): ``trans_src``, ``trans_dst``, ``trans_rd``,
    ``trans_weight``. ``speed_scale``: ``v_typ`` [unit / s]; ``min_rd``: the smallest
    ``rd`` between two beat frames (to suggest a TH); ``params``: the construction
    parameters.
    """

    clips: tuple
    node_clip: np.ndarray
    node_frame: np.ndarray
    next_node: np.ndarray
    intensity: np.ndarray
    z_intensity: np.ndarray
    trans_src: np.ndarray
    trans_dst: np.ndarray
    trans_rd: np.ndarray
    trans_weight: np.ndarray
    th: float
    weight_rule: str
    speed_scale: float
    min_rd: float
    params: dict = field(default_factory=dict)
    build_time: float = 0.0
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def n_nodes(self) -> int:
        return int(self.node_clip.size)

    @property
    def n_intervals(self) -> int:
        return int(np.sum(self.next_node >= 0))

    @property
    def n_transitions(self) -> int:
        """Number of two-way transition edges (each counted once)."""
        return int(self.trans_src.size // 2)

    @property
    def is_interval(self) -> np.ndarray:
        return self.next_node >= 0

    def node_time(self) -> np.ndarray:
        """Beat time [s] of each node in its own clip (all clips share one frame rate)."""
        return frames_to_time(self.node_frame, fps=self.clips[0].fps)

    def interval_duration(self) -> np.ndarray:
        """Natural duration [s] of the interval starting at each node (NaN at last beats)."""
        t = self.node_time()
        out = np.full(self.n_nodes, np.nan)
        ok = self.next_node >= 0
        out[ok] = t[self.next_node[ok]] - t[ok]
        return out

    def summary(self) -> dict:
        return {
            "n_clips": len(self.clips),
            "clips": [c.name for c in self.clips],
            "n_nodes": self.n_nodes,
            "n_intervals": self.n_intervals,
            "n_transitions": self.n_transitions,
            "th": self.th,
            "weight_rule": self.weight_rule,
            "min_rd": self.min_rd,
            "speed_scale": self.speed_scale,
            "build_time_s": self.build_time,
        }

    def _kept_cache(self) -> dict:
        """Cache entries that survive a change of edges (they depend on the clips only)."""
        return {k: v for k, v in self._cache.items() if k == "speeds"}

    def speed_reference(self) -> dict:
        """Per-clip speed percentiles (:func:`.plausibility.library_profile`), computed once."""
        if "speeds" not in self._cache:
            from .plausibility import library_profile

            self._cache["speeds"] = library_profile(self.clips)
        return self._cache["speeds"]

    def successors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Edges between interval nodes: ``(src, dst, weight)``.

        After playing ``u``'s interval the dancer stands on beat frame ``a = next_node[u]``;
        the next interval is ``a``'s own (weight 0, "continue") or that of any ``v`` with a
        transition edge ``a -> v`` (weight ``w2``).
        """
        if "succ" in self._cache:
            return self._cache["succ"]
        isint = self.is_interval
        u = np.flatnonzero(isint)
        a = self.next_node[u]
        keep = isint[a]
        # transitions: for every edge a -> v, every u with next_node[u] == a
        prev = np.full(self.n_nodes, -1)
        prev[a] = u
        p = prev[self.trans_src]
        ok = (p >= 0) & isint[self.trans_dst]
        self._cache["succ"] = (
            np.concatenate([u[keep], p[ok]]).astype(np.int64),
            np.concatenate([a[keep], self.trans_dst[ok]]).astype(np.int64),
            np.concatenate([np.zeros(int(keep.sum())), self.trans_weight[ok]]).astype(np.float64),
        )
        return self._cache["succ"]

    def predecessor_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense ``(N, max_in)`` table ``(pred, weight, is_trans)`` for the DP (padding: inf)."""
        if "pred" in self._cache:
            return self._cache["pred"]
        src, dst, w = self.successors()
        n = self.n_nodes
        order = np.argsort(dst, kind="stable")
        src, dst, w = src[order], dst[order], w[order]
        counts = np.bincount(dst, minlength=n)
        width = max(1, int(counts.max()) if counts.size else 1)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        col = np.arange(dst.size) - starts[dst]
        pred = np.zeros((n, width), dtype=np.int64)
        weight = np.full((n, width), np.inf)
        is_trans = np.zeros((n, width), dtype=bool)
        pred[dst, col] = src
        weight[dst, col] = w
        is_trans[dst, col] = self.next_node[src] != dst
        self._cache["pred"] = (pred, weight, is_trans)
        return self._cache["pred"]

    def successor_lists(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """CSR successor lists over all nodes: ``(indptr, dst, weight)``."""
        if "csr" in self._cache:
            return self._cache["csr"]
        src, dst, w = self.successors()
        order = np.lexsort((dst, src))
        src, dst, w = src[order], dst[order], w[order]
        indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=self.n_nodes))])
        self._cache["csr"] = (indptr, dst, w)
        return self._cache["csr"]

    def to_arrays(self) -> dict[str, np.ndarray]:
        out = {k: getattr(self, k) for k in _ARRAYS}
        out["scalars"] = np.array([self.th, self.speed_scale, self.min_rd, self.build_time])
        out["weight_rule"] = np.array(self.weight_rule)
        return out

    @classmethod
    def from_arrays(cls, arrays: dict[str, Any], clips: Sequence[Any], params: dict) -> Any:
        th, speed, min_rd, build_time = (float(x) for x in np.asarray(arrays["scalars"]))
        return cls(
            clips=tuple(clips),
            **{k: np.asarray(arrays[k]) for k in _ARRAYS},
            th=th,
            weight_rule=str(np.asarray(arrays["weight_rule"])),
            speed_scale=speed,
            min_rd=min_rd,
            params=dict(params),
            build_time=build_time,
        )

    def with_threshold(self, th: float) -> WeightedMotionGraph:
        """The graph with only the transitions ``rd < th <= TH``, without recomputing distances."""
        th = check_th(th)
        if th > self.th:
            raise ParameterError(
                f"TH={th:g} is larger than the TH={self.th:g} this graph was built with: "
                "build it with the largest TH needed"
            )
        keep = self.trans_rd < th
        return dataclasses.replace(
            self,
            trans_src=self.trans_src[keep],
            trans_dst=self.trans_dst[keep],
            trans_rd=self.trans_rd[keep],
            trans_weight=self.trans_weight[keep],
            th=th,
            params={**self.params, "th": th},
            _cache=self._kept_cache(),
        )

    def with_rule(self, weight_rule: str) -> WeightedMotionGraph:
        """The same graph with transition weights recomputed under another eq. 2 rule."""
        return dataclasses.replace(
            self,
            trans_weight=transition_weight(self.trans_rd, weight_rule),
            weight_rule=weight_rule,
            params={**self.params, "weight_rule": weight_rule},
            _cache=self._kept_cache(),
        )


def check_library(clips: Any) -> tuple:
    """Validate a motion library: non-empty, BVH clips with one skeleton and frame rate."""
    clips = () if clips is None else tuple(clips)
    if not clips:
        raise ParameterError("the motion library is empty: give at least one BVH clip")
    for c in clips:
        if getattr(c, "skeleton", None) is None:
            raise ParameterError(
                f"clip {getattr(c, 'name', '?')!r} has no skeleton (marker data or a table); "
                "a motion graph needs BVH clips with joint rotations"
            )
    ref = clips[0]
    for c in clips[1:]:
        if abs(float(c.fps) - float(ref.fps)) > 1e-9:
            raise ParameterError(
                f"clips {ref.name!r} ({ref.fps} fps) and {c.name!r} ({c.fps} fps) have "
                "different frame rates; read them at one rate (--fps) or resample first"
            )
        if not ref.skeleton.same_structure(c.skeleton):
            ja = ref.skeleton.joints
            jb = c.skeleton.joints
            what = f"{len(ja)} vs {len(jb)} joints"
            for x, y in zip(ja, jb, strict=False):
                if x.name != y.name or x.parent != y.parent or x.channels != y.channels:
                    what = f"joint {x.name!r} vs {y.name!r}"
                    break
            raise ParameterError(
                f"clips {ref.name!r} and {c.name!r} have different skeletons ({what}); "
                "one motion graph needs clips of one skeleton: build separate libraries"
            )
    return clips


def check_th(th: Any, *, name: str = "TH") -> float:
    """The transition threshold ``th`` (eq. 1) as a float > 0; ``name`` as the caller calls it."""
    try:
        return check_positive(th, name=name, unit="scale-free distance rd")
    except ParameterError as exc:
        raise ParameterError(f"{exc}; the paper uses TH = 3.0") from None


def _beat_frames(beats: Any, clip: Any) -> np.ndarray:
    """Nearest frames of a clip's given beat times [s]; refuses beats after its last frame."""
    what = f"beats of clip {clip.name!r}"
    bt = check_times(beats, name=what, duration=clip.duration)
    last = float(frames_to_time(clip.n_frames - 1, fps=clip.fps))
    if bt.size and bt[-1] > last + 1e-9:
        raise ParameterError(
            f"{what} end at {bt[-1]:g} s, after the clip's last frame at {last:g} s "
            f"(frame {clip.n_frames - 1} at {clip.fps:g} fps); a beat must lie on the clip"
        )
    fr = time_to_frames(bt, fps=clip.fps, mode="round")
    merged = np.flatnonzero(np.diff(fr) == 0)
    if merged.size:
        warn(
            f"{merged.size} pair(s) of {what} round to the same frame at {clip.fps:g} fps "
            f"(first: {bt[merged[0]]:g} s and {bt[merged[0] + 1]:g} s -> frame "
            f"{fr[merged[0]]}); they are merged into one beat node",
            stacklevel=3,
        )
    return np.unique(fr)


def build_graph(
    clips: Sequence[Any],
    *,
    th: float = 3.0,
    weight_rule: str = "paper",
    beats: Sequence[Any] | None = None,
    beat_method: str = "speed",
    smooth: float = 0.1,
    min_interval: float = 0.2,
    joints: Sequence[str] | None = None,
    window: float = 0.2,
    rd_unit: float = 0.1,
    up_axis: str = "y",
    require_transitions: bool = True,
) -> WeightedMotionGraph:
    """Build the weighted motion graph of a motion library (paper B, section 3.2).

    ``beats``: beat times [s] per clip, each put on its nearest frame (two on one frame
    are merged with a warning), by default kinematic beats (``beat_method``, ``smooth``,
    ``min_interval``: :func:`beatsync.motion_beats.kinematic_beats`); ``joints``: for
    beats, intensities and distances; ``window``, ``rd_unit`` [s]: as in eq. 1 (module
    docstring); ``require_transitions``: refuse a graph without transitions.
    """
    t0 = time.perf_counter()
    clips = check_library(clips)
    th = check_th(th)
    check_choice(weight_rule, WEIGHT_RULES, name="weight_rule")
    if up_axis not in ("y", "z"):
        raise ParameterError(f"up_axis={up_axis!r} must be 'y' (BVH) or 'z'")
    up = "xyz".index(up_axis)
    for name, val in (("window", window), ("rd_unit", rd_unit)):
        if check_positive(val, name=name, unit="s") > 10:
            raise ParameterError(f"{name}={val!r} must be a duration in (0, 10] [s]")
    if beats is not None and len(beats) != len(clips):
        raise ParameterError(
            f"beats has {len(beats)} entries for {len(clips)} clips: give one array of beat "
            "times [s] per clip"
        )

    positions = [motion_positions(c, joints=joints) for c in clips]
    frames_list = []
    for i, (c, pos) in enumerate(zip(clips, positions, strict=True)):
        if beats is None:
            with silenced():
                fr = kinematic_beat_frames(
                    pos, fps=c.fps, method=beat_method, smooth=smooth, min_interval=min_interval
                )
        else:
            fr = _beat_frames(beats[i], c)
        if fr.size < 2:
            warn(f"clip {c.name!r} has {fr.size} beat(s): it contributes no interval", stacklevel=2)
        frames_list.append(np.asarray(fr, dtype=np.int64))

    node_clip = np.repeat(np.arange(len(clips), dtype=np.int64), [f.size for f in frames_list])
    node_frame = np.concatenate(frames_list)
    n = node_frame.size
    last = np.diff(node_clip, append=-1) != 0  # the last beat node of each clip
    next_node = np.where(last, -1, np.arange(1, n + 1))
    intensity = np.full(n, np.nan)
    per_clip = zip(positions, frames_list, clips, strict=True)
    intensity[~last] = np.concatenate(
        [interval_intensity(p, f, fps=c.fps) if f.size > 1 else () for p, f, c in per_clip]
    )
    ok = next_node >= 0
    if not ok.any():
        raise ParameterError(
            "no clip of the library has two motion beats, so the graph has no interval; "
            "use longer clips or a smaller min_interval"
        )
    z = np.full(n, np.nan)
    with silenced():
        z[ok] = zscore(intensity[ok], name="motion intensity")

    # eq. 1: scale-free distances between all pairs of beat frames
    fps0 = [check_fps(c.fps) for c in clips]
    half = max(1, int(time_to_frames(window / 2, fps=fps0[0], mode="round")))
    speed = typical_speed(positions, fps0, half=half, up=up)
    if not speed > 0:
        raise ParameterError("the library does not move (zero typical speed): rd is undefined")
    clouds = np.concatenate(
        [point_clouds(p, f, half) for p, f in zip(positions, frames_list, strict=True) if f.size]
    )
    src_l, dst_l, rd_l = [], [], []
    min_rd = np.inf
    chunk = max(1, int(2_000_000 // max(1, n)))
    for s in range(0, n, chunk):
        d = aligned_distance_matrix(clouds[s : s + chunk], clouds, up=up)
        rd = d / (speed * float(rd_unit))
        rows = np.arange(s, min(n, s + chunk))
        rd[rows - s, rows] = np.inf
        min_rd = min(min_rd, float(rd.min()))
        ii, jj = np.nonzero(rd < th)
        src_l.append(ii + s)
        dst_l.append(jj)
        rd_l.append(rd[ii, jj])
    trans_src = np.concatenate(src_l).astype(np.int64)
    trans_dst = np.concatenate(dst_l).astype(np.int64)
    trans_rd = np.concatenate(rd_l)
    if require_transitions and trans_src.size == 0:  # (two beat frames at least: min_rd < inf)
        raise ParameterError(
            f"no transition edges at TH={th}: no two beat frames are closer than rd < TH; the "
            f"smallest rd between two beat frames is {min_rd:.3f}: try --th "
            f"{max(min_rd * 1.5, min_rd + 0.5):.2f} or more"
        )
    params = {
        "th": th,
        "weight_rule": weight_rule,
        "beat_method": beat_method,
        "smooth": float(smooth),
        "min_interval": float(min_interval),
        "joints": list(joints) if joints is not None else None,
        "window": float(window),
        "rd_unit": float(rd_unit),
        "up_axis": up_axis,
        "given_beats": beats is not None,
    }
    return WeightedMotionGraph(
        clips=clips,
        node_clip=node_clip,
        node_frame=node_frame,
        next_node=next_node,
        intensity=intensity,
        z_intensity=z,
        trans_src=trans_src,
        trans_dst=trans_dst,
        trans_rd=trans_rd,
        trans_weight=transition_weight(trans_rd, weight_rule),
        th=th,
        weight_rule=weight_rule,
        speed_scale=speed,
        min_rd=float(min_rd),
        params=params,
        build_time=time.perf_counter() - t0,
    )
