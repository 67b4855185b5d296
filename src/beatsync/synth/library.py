"""Synthetic dance clips with exact motion beats (tests and a second study library).

A 17-joint BVH skeleton dances in place: every rotation channel, and the root's height,
moves from one extreme pose to the next once per beat along a half cosine,

    theta_j(t) = A_j * (s_k + (s_{k+1} - s_k) * (1 - cos(pi u)) / 2),  u = (t - t_k) / T,

with ``s_k = (-1)^k a_k`` and ``a_k`` the loudness of beat ``k``'s section. All joint
velocities vanish together at every beat, so the kinematic beats are exactly the beat
times; clips drawn with different seeds share the pose vocabulary, so a library of them
has transitions. Stands in for paper B's second (Indian dance) library. Returns a
:class:`beatsync.motion.Motion` (degrees, metres) and its beat times [s].
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..motion import Joint, Motion, Skeleton
from ..validation import as_int, check_fps, check_positive, frames_to_time, time_to_frames

__all__ = ["dance_skeleton", "synthetic_dance", "synthetic_library"]

_ROT = ("Zrotation", "Xrotation", "Yrotation")
_ROOT = ("Xposition", "Yposition", "Zposition", *_ROT)


def dance_skeleton(scale: float = 1.0) -> Skeleton:
    """A 17-joint humanoid (y up, metres times ``scale``), ZXY rotations."""
    s = float(scale)

    def j(name, parent, off, end=False):
        return Joint(name, parent, np.asarray(off, dtype=np.float64) * s, () if end else _ROT, end)

    joints = [
        Joint("hip", -1, np.zeros(3), _ROOT),
        j("spine", 0, [0, 0.25, 0]),
        j("neck", 1, [0, 0.30, 0]),
        j("head_end", 2, [0, 0.15, 0], True),
        j("lShoulder", 1, [0.18, 0.25, 0]),
        j("lElbow", 4, [0.28, 0, 0]),
        j("lHand_end", 5, [0.25, 0, 0], True),
        j("rShoulder", 1, [-0.18, 0.25, 0]),
        j("rElbow", 7, [-0.28, 0, 0]),
        j("rHand_end", 8, [-0.25, 0, 0], True),
        j("lThigh", 0, [0.1, 0, 0]),
        j("lShin", 10, [0, -0.42, 0]),
        j("lFoot", 11, [0, -0.42, 0]),
        j("lToe_end", 12, [0, -0.05, 0.12], True),
        j("rThigh", 0, [-0.1, 0, 0]),
        j("rShin", 14, [0, -0.42, 0]),
        j("rFoot", 15, [0, -0.42, 0]),
        j("rToe_end", 16, [0, -0.05, 0.12], True),
    ]
    return Skeleton(tuple(joints))


def synthetic_dance(
    *,
    duration: float = 10.0,
    bpm: float = 100.0,
    fps: float = 60.0,
    seed: int = 0,
    section_beats: int = 4,
    level_range: tuple[float, float] = (0.3, 1.0),
    start: float = 0.25,
    scale: float = 1.0,
    n_moves: int = 3,
    vocabulary_seed: int = 0,
    name: str | None = None,
) -> tuple[Motion, np.ndarray]:
    """One synthetic dance clip and its exact beat times [s] (on frame times, inside the clip).

    One extreme pose per beat from ``start`` [s]; ``seed`` draws each ``section_beats``
    section's move and loudness ``a_k`` (in ``level_range``), ``vocabulary_seed`` the
    ``n_moves`` moves (clips of one vocabulary share poses).
    """
    fps = check_fps(fps)
    bpm = check_positive(bpm, name="bpm", unit="BPM")
    duration = check_positive(duration, name="duration", unit="s")
    section_beats = as_int(section_beats, name="section_beats", minimum=1)
    n_moves = as_int(n_moves, name="n_moves", minimum=1)
    rng = np.random.default_rng(seed)
    skel = dance_skeleton(scale)
    channels = skel.channel_names()
    n = int(time_to_frames(duration, fps=fps, mode="round"))
    t = frames_to_time(np.arange(n), fps=fps)
    period = 60.0 / bpm
    # beats on frame times
    beat_frames = np.unique(
        time_to_frames(start + np.arange(0, duration, period), fps=fps, mode="round")
    )
    beat_frames = beat_frames[beat_frames < n]
    if beat_frames.size < 3:
        raise ParameterError(
            f"duration={duration} s at {bpm} BPM gives fewer than 3 beats; make it longer"
        )
    beats = frames_to_time(beat_frames, fps=fps)
    n_sec = int(np.ceil(beats.size / section_beats)) + 1
    levels = rng.uniform(*level_range, size=n_sec)
    moves = rng.integers(0, n_moves, size=n_sec)
    sec = np.arange(beats.size) // section_beats
    sign = (-1.0) ** np.arange(beats.size)
    vocab = _move_vocabulary(channels, n_moves, vocabulary_seed)  # (n_moves, C)
    keys = vocab[moves[sec]] * (levels[sec] * sign)[:, None]  # (n_beats, C) key poses
    root_y = channels.index("hip_Yposition")
    keys[:, root_y] = (0.9 + 0.04 * levels[sec] * sign) * scale
    # half-cosine interpolation between key poses: zero velocity at every beat
    k = np.clip(np.searchsorted(beats, t, side="right") - 1, 0, beats.size - 2)
    u = np.clip((t - beats[k]) / (beats[k + 1] - beats[k]), 0.0, 1.0)
    wgt = ((1.0 - np.cos(np.pi * u)) / 2.0)[:, None]
    values = keys[k] + (keys[k + 1] - keys[k]) * wgt
    values[t < beats[0]] = keys[0]
    motion = Motion(values, fps, channels, skel, name or f"synthetic_{seed}")
    return motion, beats


_AMP = {
    "spine": (8, 10, 15),
    "neck": (5, 8, 10),
    "lShoulder": (40, 20, 15),
    "rShoulder": (-40, 20, -15),
    "lElbow": (10, 0, 50),
    "rElbow": (-10, 0, -50),
    "lThigh": (5, 30, 5),
    "rThigh": (5, -30, 5),
    "lShin": (0, -35, 0),
    "rShin": (0, 35, 0),
    "lFoot": (0, 10, 0),
    "rFoot": (0, -10, 0),
    "hip": (0, 0, 10),
}


def _move_vocabulary(channels: tuple[str, ...], n_moves: int, seed: int) -> np.ndarray:
    """Joint amplitudes [deg] of each move, shape ``(n_moves, n_channels)``."""
    rng = np.random.default_rng(10_000 + seed)
    out = np.zeros((n_moves, len(channels)))
    for ci, ch in enumerate(channels):
        joint, _, dof = ch.rpartition("_")
        if joint in _AMP and dof in _ROT:
            base = _AMP[joint][_ROT.index(dof)]
            out[:, ci] = base * rng.uniform(-1.4, 1.4, size=n_moves)
    return out


def synthetic_library(
    n_clips: int = 4,
    *,
    duration: float = 20.0,
    bpm_range: tuple[float, float] = (90.0, 130.0),
    fps: float = 60.0,
    seed: int = 0,
) -> tuple[list[Motion], list[np.ndarray]]:
    """``n_clips`` synthetic dances at tempi drawn from ``bpm_range`` (seeded)."""
    if int(n_clips) < 1:
        raise ParameterError(f"n_clips={n_clips!r} must be >= 1")
    rng = np.random.default_rng(seed)
    tempi = rng.uniform(bpm_range[0], bpm_range[1], size=int(n_clips))
    dances = [
        synthetic_dance(
            duration=duration,
            bpm=float(bpm),
            fps=fps,
            seed=seed * 1000 + i,
            name=f"synthetic_{i:02d}",
        )
        for i, bpm in enumerate(tempi)
    ]
    return [m for m, _ in dances], [b for _, b in dances]
