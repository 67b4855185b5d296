"""Objective quality proxies of a composed dance (stand-ins for paper B's user study).

Paper B's Table 2 is a user study; we cannot repeat it. These numbers are *proxies*
for what viewers judged, not a replacement:

- **Beat alignment** (:mod:`beatsync.evaluate.alignment`): both published scores,
  averaged over motion beats (Siyao et al. 2022) and over music beats (Li et al.
  2021), Gaussian sigma 0.05 s, on the kinematic beats of the composed motion.
- **Intensity correlation**: Pearson r between the composed motion's intensity per
  music beat interval (mean joint kinetic energy) and the music level (RMS dB).
- **Transition smoothness**: the largest frame-to-frame change of joint velocity
  (mean over joints) within ``[T - 1 frame, T + blend]`` of each transition,
  divided by the median of that change over the whole dance: 1 means a transition
  is as smooth as ordinary movement, large values mean a visible jerk.
- **Foot sliding**: mean horizontal speed [position unit / s] of the feet while they
  are in contact with the floor (height below the foot's 5th percentile plus 10 % of
  its height range), averaged over feet.

Data contract: motions are :class:`beatsync.motion.Motion` with a skeleton; times in
seconds.

Notebook: ``notebooks/paper_b_tab02_quality_proxies.ipynb``; paper B section 4 (Table 2).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import BeatsyncWarning, ParameterError
from ..motion_beats import beat_interval_intensity, kinematic_beats, motion_positions
from ..units import frames_to_time, time_to_frames

__all__ = [
    "intensity_correlation",
    "transition_jumps",
    "foot_sliding",
    "foot_joints",
    "quality_proxies",
]


def intensity_correlation(motion: Any, music_beats: Any, music_level: Any) -> float:
    """Pearson r between motion intensity and music level per music beat interval."""
    beats = np.asarray(music_beats, dtype=np.float64)
    level = np.asarray(music_level, dtype=np.float64)
    last = float(frames_to_time(motion.n_frames - 1, fps=motion.fps))
    keep = beats <= last + 1e-9
    beats_in = beats[keep]
    if beats_in.size < 3:
        warnings.warn(
            "fewer than two beat intervals: correlation set to NaN", BeatsyncWarning, stacklevel=2
        )
        return float("nan")
    inten = beat_interval_intensity(motion, beats_in)
    lv = level[: inten.size]
    if np.std(inten) == 0 or np.std(lv) == 0:
        return float("nan")
    return float(np.corrcoef(inten, lv)[0, 1])


def _velocity_change(motion: Any) -> np.ndarray:
    pos = motion_positions(motion)
    vel = np.gradient(pos, axis=0) * motion.fps
    dv = np.linalg.norm(np.diff(vel, axis=0), axis=2).mean(axis=1)  # between frames j, j+1
    return dv


def transition_jumps(motion: Any, transition_times: Any, *, blend: float = 1.0 / 3.0) -> np.ndarray:
    """Velocity-jump ratio at each transition (see module docstring); empty if none."""
    tt = np.asarray(transition_times, dtype=np.float64)
    dv = _velocity_change(motion)
    med = float(np.median(dv))
    if tt.size == 0:
        return np.empty(0)
    if med <= 0:
        raise ParameterError("the motion does not move: velocity changes are all zero")
    out = []
    first = time_to_frames(tt, fps=motion.fps, mode="floor") - 1
    after = time_to_frames(tt + blend, fps=motion.fps, mode="ceil") + 1
    for f0, f1 in zip(first, after, strict=True):
        j0 = max(0, int(f0))
        j1 = min(dv.size, int(f1))
        out.append(dv[j0:j1].max() / med if j1 > j0 else np.nan)
    return np.asarray(out)


def foot_joints(motion: Any) -> list[str]:
    """Names of the foot/toe joints (end sites excluded) found by name."""
    names = motion.joint_names
    skel = motion.skeleton
    cand = [
        j.name
        for j in skel.joints
        if not j.is_end_site and any(k in j.name.lower() for k in ("toe", "foot", "ankle"))
    ]
    if not cand:
        raise ParameterError(
            f"no foot joint (name with 'foot', 'toe' or 'ankle') among {names[:10]}...; "
            "pass feet=[...] explicitly"
        )
    # keep the most distal per side: joints that are nobody's parent among candidates
    idx = {skel.index(n) for n in cand}
    parents = {skel.joints[i].parent for i in idx}
    return [skel.joints[i].name for i in sorted(idx) if i not in parents] or cand


def foot_sliding(motion: Any, *, feet: Any = None, up_axis: str = "y") -> float:
    """Mean horizontal foot speed during floor contact [position unit / s]."""
    feet = foot_joints(motion) if feet is None else list(feet)
    pos = motion_positions(motion, joints=feet)
    up = "xyz".index(up_axis)
    ground = [a for a in range(3) if a != up]
    vel = np.gradient(pos, axis=0) * motion.fps
    hspeed = np.linalg.norm(vel[:, :, ground], axis=2)
    h = pos[:, :, up]
    lo = np.percentile(h, 5, axis=0)
    rng = np.percentile(h, 95, axis=0) - lo
    contact = h <= lo + 0.1 * np.maximum(rng, 1e-9)
    if not contact.any():
        return float("nan")
    return float(hspeed[contact].mean())


def quality_proxies(
    composition: Any,
    *,
    sigma: float = 0.05,
    blend: float = 1.0 / 3.0,
    beat_smooth: float = 0.1,
) -> dict[str, float]:
    """All proxies of a :class:`beatsync.graph.compose.Composition`.

    Parameters
    ----------
    composition : Composition
    sigma : float > 0 [s]
        Gaussian width of the beat-alignment scores.
    blend : float >= 0 [s]
        Transition blend length (window of the velocity-jump ratio).
    beat_smooth : float >= 0 [s]
        Smoothing of the speed curve before its minima become the composed motion's
        kinematic beats (``smooth`` of :func:`beatsync.motion_beats.kinematic_beats`).
        The default 0.1 s suits captured data; on noise-free motion it can move a
        minimum by a frame or two where the speed profile is asymmetric around the
        beat, so motion whose beats land exactly scores alignment 1 only with 0.

    Returns
    -------
    dict
        ``alignment_motion``, ``alignment_music`` (beat alignment averaged over motion
        beats / music beats), ``intensity_r``, ``transition_jump_mean``,
        ``transition_jump_max``, ``foot_sliding``, ``n_transitions``.
    """
    from ..evaluate.alignment import alignment_scores

    m = composition.motion
    beats = composition.music_beats
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        mb = kinematic_beats(m, smooth=beat_smooth)
        last = float(frames_to_time(m.n_frames - 1, fps=m.fps))
        span = (float(beats[0]), float(min(beats[-1], last)))
        al = alignment_scores(mb, beats, sigma=sigma, span=span)
        jumps = transition_jumps(m, composition.synthesis.transition_times, blend=blend)
        r = intensity_correlation(m, beats, composition.music_level)
    return {
        "alignment_motion": al["alignment_motion"],
        "alignment_music": al["alignment_music"],
        "intensity_r": r,
        "transition_jump_mean": float(np.mean(jumps)) if jumps.size else float("nan"),
        "transition_jump_max": float(np.max(jumps)) if jumps.size else float("nan"),
        "foot_sliding": foot_sliding(m, up_axis=composition.synthesis.info.get("up_axis", "y")),
        "n_transitions": int(composition.search.n_transitions),
    }
