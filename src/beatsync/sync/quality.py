"""What a synchronisation did to the dance: playback speed, joint speed, the loop joins.

Measured on the result, for the report of :func:`beatsync.sync.synchronize`:

- playback speed: source seconds shown per output second. *Instantaneous*: between
  consecutive output frames; *per interval*: each placed interval's source duration
  over its music duration. For both: min, median, max and the share of output time
  within the band (``DEFAULT_SCALE_BOUND``, 0.8-1.25), counted over the output time
  the warp covers (a held lead-in, where the first pose waits for its beat, is
  reported apart);
- joint speed and acceleration (finite differences over all joints and frames, in
  the motion's position unit per second): p99 and peak of the output against the
  input's, the input sampled (linearly) at the output's frame rate when they differ;
- each loop join: its music time and the peak joint speed within its blend window;
- beats mode: the landed motion beats the output shows, found by the scorer's detector
  (:func:`beatsync.motion_beats.kinematic_beats`): how many on their landing's frame
  (within half a frame), how far from their landing times (the beats, plus a phase
  offset if one was asked for), how many not within ``SEEN_REACH``.

Data contract: times in seconds; positions ``(frames, joints, 3)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import silenced
from ..graph.timescale import DEFAULT_SCALE_BOUND
from ..motion_beats import motion_positions, speed_curve, speed_minima
from ..validation import nearest
from .positions import interp_frames

__all__ = [
    "SEEN_REACH",
    "seen_landings",
    "landing_figures",
    "live_steps",
    "instantaneous_speed",
    "joint_kinematics",
    "speed_figures",
    "join_figures",
]


#: an output motion beat this close to a landing's beat [s] is that landing's
SEEN_REACH = 0.1


def _stats(s: np.ndarray, weight: np.ndarray, band: tuple[float, float]) -> dict[str, float]:
    inside = (s >= band[0] - 1e-9) & (s <= band[1] + 1e-9)
    return {
        "min": float(s.min()),
        "median": float(np.median(s)),
        "max": float(s.max()),
        "in_band": float(weight[inside].sum() / weight.sum()),
    }


def live_steps(times: np.ndarray, covered: tuple[float, float]) -> np.ndarray:
    """Which steps between consecutive output frames (at ``times`` [s]) lie wholly within
    ``covered`` [s], where the warp plays (a held lead-in, and the step out of it, left out)."""
    return (times[:-1] >= covered[0] - 1e-9) & (times[1:] <= covered[1] + 1e-9)


def seen_landings(
    pos: np.ndarray, fps: float, targets: np.ndarray, first_frame: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """For every beat in ``targets`` [s]: how far [s] the nearest motion beat of the
    output's joint positions ``pos`` (at ``fps``, from output frame ``first_frame`` on;
    a speed minimum found to a sub-frame, the parabola through it and its neighbours)
    lies from the output frame nearest the beat, the frame a viewer can see it on (inf
    beyond ``SEEN_REACH``), and the same signed (the minimum's time minus the frame's)."""
    aim = (np.rint(targets * fps) - first_frame) / fps
    curve = speed_curve(pos, fps=fps)
    f = speed_minima(curve, fps)  # kinematic_beats' defaults
    if f.size == 0:
        return np.full(targets.size, np.inf), np.zeros(targets.size)
    c0, c1, c2 = curve[f - 1], curve[f], curve[f + 1]
    bend = c0 - 2.0 * c1 + c2
    vertex = np.where(bend > 0, 0.5 * (c0 - c2) / np.where(bend > 0, bend, 1.0), 0.0)
    near = nearest(aim, (f + vertex) / fps)
    d = np.abs(near - aim)
    return np.where(d <= SEEN_REACH, d, np.inf), near - aim


def landing_figures(pos: np.ndarray, fps: float, targets: np.ndarray) -> dict[str, Any]:
    """The landings at ``targets`` [s] the output's joint positions ``pos`` show (module
    docstring)."""
    err, off = seen_landings(pos, fps, targets)
    found = np.isfinite(err)
    ms = 1e3 * np.abs(np.rint(targets * fps) / fps + off - targets)[found]  # from the aims
    return {
        "landings": int(targets.size),
        "on_their_frame": int(np.count_nonzero(err <= 0.5 / fps)),
        "not_found": int(np.count_nonzero(~found)),
        "median_ms": float(np.median(ms)) if ms.size else float("nan"),
        "max_ms": float(ms.max()) if ms.size else float("nan"),
    }


def instantaneous_speed(
    src_times: np.ndarray, out_fps: float, covered: tuple[float, float]
) -> np.ndarray:
    """Source seconds per output second between output frames within ``covered`` [s]."""
    live = live_steps(np.arange(src_times.size) / out_fps, covered)
    return np.diff(src_times)[live] * out_fps


def speed_figures(
    src_times: np.ndarray,
    out_fps: float,
    covered: tuple[float, float],
    used: np.ndarray,
    targets: np.ndarray,
    band: tuple[float, float] = DEFAULT_SCALE_BOUND,
) -> dict[str, Any]:
    """Instantaneous and per-interval playback speed (see the module docstring)."""
    inst = instantaneous_speed(src_times, out_fps, covered)
    per = np.diff(used) / np.diff(targets)
    lead_in = np.count_nonzero(np.arange(src_times.size) / out_fps < covered[0])
    return {
        "band": list(band),
        "instantaneous": _stats(inst, np.ones_like(inst), band) if inst.size else None,
        "per_interval": _stats(per, np.diff(targets), band),
        "held_lead_in_s": float(lead_in / out_fps),
    }


def _speeds(pos: np.ndarray, fps: float) -> np.ndarray:
    return np.linalg.norm(np.diff(pos, axis=0), axis=-1) * fps


def joint_kinematics(pos_in: np.ndarray, fps_in: float, pos_out: np.ndarray, fps_out: float):
    """p99 and peak joint speed and p99 acceleration of input and output, and ratios."""
    out = {}
    for name, pos, fps in (("input", pos_in, fps_in), ("output", pos_out, fps_out)):
        v = _speeds(pos, fps)
        a = np.linalg.norm(np.diff(pos, 2, axis=0), axis=-1) * fps * fps
        out[name] = {
            "p99_joint_speed": float(np.percentile(v, 99)),
            "peak_joint_speed": float(v.max()),
            "p99_joint_accel": float(np.percentile(a, 99)) if a.size else float("nan"),
        }
    out["ratio"] = {
        k: out["output"][k] / out["input"][k] if out["input"][k] > 0 else float("nan")
        for k in out["input"]
    }
    return out


def join_figures(
    join_src: np.ndarray, warp: Any, pos_out: np.ndarray | None, out_fps: float, width: float
) -> list[dict[str, float]]:
    """Each join's music time and the peak joint speed within its blend window."""
    times = np.interp(join_src, warp.src, warp.tgt)
    rows = []
    v = None if pos_out is None else _speeds(pos_out, out_fps)
    for js, jt in zip(join_src, times, strict=True):
        if js > warp.src[-1]:
            break
        row = {"source_time_s": float(js), "time_s": float(jt)}
        if v is not None:
            # the blend spans width/2 of source time on each side: its music time span
            lo = float(np.interp(js - width / 2, warp.src, warp.tgt))
            hi = float(np.interp(js + width / 2, warp.src, warp.tgt))
            f0 = max(0, int(np.floor(lo * out_fps)) - 1)
            f1 = min(v.shape[0], int(np.ceil(hi * out_fps)) + 1)
            row["peak_joint_speed"] = float(v[f0:f1].max()) if f1 > f0 else float("nan")
        rows.append(row)
    return rows


def fitting_tempo(median_speed: float, song_bpm: float, band=DEFAULT_SCALE_BOUND) -> str:
    """The tempo at which the same beat counts would play the dance at its own speed
    (``song_bpm / median_speed``), and the tempi that keep that speed within the band."""
    natural = song_bpm / median_speed
    return f"{natural:.0f} BPM ({natural * band[0]:.0f}-{natural * band[1]:.0f} BPM)"


def report_entries(
    motion, out_motion, src_times, warp, used, targets, looped, placed, pos_in, *, aims
) -> dict:
    """Report entries computed from the output frames (see the module docstring);
    ``pos_in``: the input's joint positions (None for angle tables; from the first frame
    the output can show, at the input's rate); ``aims`` [s]: where
    the landed motion beats should show (beats mode; None in periods mode)."""
    out_fps = float(out_motion.fps)
    counts, n = np.unique(np.asarray(placed["beats"], dtype=np.float64), return_counts=True)
    rep: dict[str, Any] = {
        "beats_per_motion_beat_used": {f"{c:g}": int(k) for c, k in zip(counts, n, strict=True)},
        "n_merged_intervals": int(placed["n_merged"]),
        "n_half_beat_landings": int(placed["n_half_beat"]),
        "phrases_on_bars": placed.get("phrases_on_bars"),
        "playback_speed": speed_figures(
            src_times, out_fps, (float(warp.tgt[0]), float(warp.tgt[-1])), used, targets
        ),
    }
    pos_out = rep["kinematics"] = None
    if pos_in is not None:  # angle tables have no joint speeds to report
        with silenced():
            pos_out = motion_positions(out_motion)
        # finite differences depend on the frame rate: the input at the output's
        if out_fps != motion.fps:
            t = np.arange(0.0, (pos_in.shape[0] - 1) / motion.fps + 1e-9, 1.0 / out_fps)
            pos_in = interp_frames(pos_in, motion.fps, t)
        rep["kinematics"] = joint_kinematics(pos_in, out_fps, pos_out, out_fps)
    rep["landings_seen"] = None
    if aims is not None and pos_out is not None:
        rep["landings_seen"] = landing_figures(pos_out, out_fps, aims)
    rep["loop"] = None
    rep["joins"] = []
    if looped is not None:
        rep["loop"] = {
            "start_s": looped.first,
            "end_s": looped.last,
            "blend_s": looped.join,
            "turn_deg": float(np.degrees(looped.angle)),
            "pose_distance": looped.distance,
        }
        rep["joins"] = join_figures(looped.join_times, warp, pos_out, out_fps, looped.join)
    return rep
