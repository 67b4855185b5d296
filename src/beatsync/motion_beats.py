"""Motion beats and motion intensity of dance clips (paper B, section 3.1).

Paper B builds its motion graph on the *beat frames* of every clip and weights the
edge between two successive beat frames by the *motion intensity* of that interval.

- **Kinematic beats** (``method="speed"``): local minima of the mean joint speed,
  Gaussian-smoothed (sigma ``smooth`` [s]): dancers mark the beat by stopping or
  reversing a movement (Shiratori et al. 2004, Kim et al. 2003). Minima closer than
  ``min_interval`` [s] are thinned and those less prominent than ``rel_prominence``
  times the median speed dropped (flat plateaus).
- **PCA beats** (``method="pca"``, Kim et al. 2003): the extrema of each frame's
  projection on the first principal axis of root-relative joint positions over a
  ``window`` [s].
- **Motion intensity**: the joints' mean kinetic energy ``0.5 * mean_j |v_j|^2`` (unit
  mass) over ``[beat_i, beat_{i+1})`` [(position unit / s)^2].

Motions have a skeleton or are marker tables of ``<marker>_x/_y/_z`` triples; the
array functions take positions ``(n_frames, n_joints, 3)``. Beats lie on frame times.

Notebook: ``notebooks/paper_b_tab01_search_speed.ipynb``; paper B section 3.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.signal import find_peaks

from .errors import ParameterError, warn
from .validation import (
    check_choice,
    check_finite,
    check_fps,
    check_positive,
    check_range,
    check_times,
    frames_to_time,
    time_to_frames,
)

__all__ = [
    "kinematic_beats",
    "kinematic_beat_frames",
    "speed_minima",
    "beat_interval_intensity",
    "interval_intensity",
    "speed_curve",
    "pca_curve",
    "kinetic_energy",
    "motion_positions",
    "zscore",
    "motion_tempo",
]


def motion_positions(motion: Any, *, joints: Any = None) -> np.ndarray:
    """World joint positions of a motion, ``(n_frames, n_joints, 3)`` [position unit].

    From :meth:`Motion.positions` (forward kinematics, or a position-only motion's
    ``<name>_x/_y/_z`` triples); ``joints``: names or indices to keep (default all).
    """
    pos = np.asarray(motion.positions(), dtype=np.float64)
    names = motion.joint_names
    if joints is not None:
        idx = [names.index(j) if j in names else j for j in joints]
        for j in idx:
            if not isinstance(j, (int, np.integer)) or not 0 <= j < pos.shape[1]:
                raise ParameterError(
                    f"joint {j!r} not in the motion (indices 0..{pos.shape[1] - 1}); known "
                    f"joints: {', '.join(names[:12])}" + (" ..." if len(names) > 12 else "")
                )
        if not idx:
            raise ParameterError("joints is empty: give at least one joint name or None for all")
        pos = pos[:, idx, :]
    return check_finite(pos, name="joint positions")


def _check_positions(positions: Any, fps: Any) -> tuple[np.ndarray, float]:
    fps = check_fps(fps)
    pos = check_finite(positions, name="positions")
    if pos.ndim == 2 and pos.shape[1] % 3 == 0:
        pos = pos.reshape(pos.shape[0], -1, 3)
    if pos.ndim != 3 or pos.shape[2] != 3:
        raise ParameterError(f"positions must have shape (n_frames, n_joints, 3), got {pos.shape}")
    if pos.shape[0] < 3:
        raise ParameterError(
            f"motion has only {pos.shape[0]} frame(s); at least 3 are needed for velocities"
        )
    return pos, fps


def _check_seconds(value: Any, *, name: str, allow_zero: bool = True) -> float:
    v = check_positive(value, name=name, unit="s", allow_zero=allow_zero)
    if v > 60:
        raise ParameterError(
            f"{name}={value!r} s is implausibly long; it is in seconds (did you give frames "
            "or milliseconds?)"
        )
    return v


def zscore(x: Any, *, name: str = "values") -> np.ndarray:
    """``(x - mean) / std`` of a 1-D array; zeros with a :class:`BeatsyncWarning` if constant."""
    arr = check_finite(x, name=name)
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be 1-D, got shape {arr.shape}")
    if arr.size == 0:
        return arr.copy()
    sd = float(arr.std())
    if sd <= 1e-12 * max(1.0, float(np.abs(arr).max())):
        if arr.size > 1:
            warn(f"{name} is constant; its z-score is set to 0", stacklevel=2)
        return np.zeros_like(arr)
    return (arr - arr.mean()) / sd


def kinetic_energy(positions: Any, *, fps: float) -> np.ndarray:
    """Per-frame mean kinetic energy ``0.5 * mean_j |v_j|^2`` [(unit / s)^2] (unit masses)."""
    pos, fps = _check_positions(positions, fps)
    vel = np.gradient(pos, axis=0) * fps
    return 0.5 * np.mean(np.sum(vel * vel, axis=2), axis=1)


def speed_curve(positions: Any, *, fps: float, smooth: float = 0.1) -> np.ndarray:
    """Mean joint speed per frame [unit / s], Gaussian-smoothed (sigma ``smooth`` [s])."""
    pos, fps = _check_positions(positions, fps)
    smooth = _check_seconds(smooth, name="smooth")
    vel = np.gradient(pos, axis=0) * fps
    speed = np.mean(np.linalg.norm(vel, axis=2), axis=1)
    if smooth > 0:
        speed = gaussian_filter1d(speed, sigma=smooth * fps, mode="nearest")
    return speed


def pca_curve(
    positions: Any, *, fps: float, window: float = 0.5, smooth: float = 0.1
) -> np.ndarray:
    """Projection of each frame on the first principal axis of a sliding window [unit].

    Joint positions relative to joint 0; for the ``window`` [s] around each frame the
    first principal axis (eigenvector of the window's Gram matrix), its sign aligned with
    the previous window's; then Gaussian-smoothed (sigma ``smooth`` [s]).
    """
    pos, fps = _check_positions(positions, fps)
    window = _check_seconds(window, name="window", allow_zero=False)
    smooth = _check_seconds(smooth, name="smooth")
    n = pos.shape[0]
    x = (pos - pos[:, :1, :]).reshape(n, -1) if pos.shape[1] > 1 else pos.reshape(n, -1)
    half = max(1, int(time_to_frames(window / 2, fps=fps, mode="round")))
    w = 2 * half + 1
    xp = np.pad(x, ((half, half), (0, 0)), mode="edge")
    axes = np.empty_like(x)
    proj = np.empty(n)
    chunk = max(1, int(4_000_000 // max(1, w * x.shape[1])))
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        win = np.lib.stride_tricks.sliding_window_view(xp[s : e + 2 * half], w, axis=0)
        win = np.swapaxes(win, 1, 2)  # (m, w, d)
        mean = win.mean(axis=1, keepdims=True)
        c = win - mean
        gram = c @ np.swapaxes(c, 1, 2)  # (m, w, w)
        _, evec = np.linalg.eigh(gram)
        u1 = evec[:, :, -1]  # (m, w)
        v1 = np.einsum("mw,mwd->md", u1, c)
        norm = np.linalg.norm(v1, axis=1, keepdims=True)
        v1 = np.divide(v1, norm, out=np.zeros_like(v1), where=norm > 0)
        axes[s:e] = v1
        proj[s:e] = np.einsum("md,md->m", c[:, half, :], v1)
    # keep the axis orientation consistent from window to window
    dots = np.einsum("nd,nd->n", axes[1:], axes[:-1])
    flips = np.concatenate([[1.0], np.where(dots < 0, -1.0, 1.0)])
    proj = proj * np.cumprod(flips)
    if smooth > 0:
        proj = gaussian_filter1d(proj, sigma=smooth * fps, mode="nearest")
    return proj


def speed_minima(
    curve: np.ndarray, fps: float, min_interval: float = 0.2, rel_prominence: float = 0.02
) -> np.ndarray:
    """Frames of the minima of a :func:`speed_curve` (checked inputs): at least
    ``min_interval`` [s] apart and ``rel_prominence`` of its median value prominent;
    never its first or last frame."""
    distance = max(1, int(time_to_frames(min_interval, fps=fps, mode="round")))
    scale = float(np.median(np.abs(curve)))
    prom = rel_prominence * scale if scale > 0 else None
    return find_peaks(-curve, distance=distance, prominence=prom)[0]


def kinematic_beat_frames(
    positions: Any,
    *,
    fps: float,
    method: str = "speed",
    smooth: float = 0.1,
    min_interval: float = 0.2,
    rel_prominence: float = 0.02,
    window: float = 0.5,
) -> np.ndarray:
    """Beat frames (int64, increasing) of joint positions: :func:`kinematic_beats` on arrays.

    ``rel_prominence``: minimum prominence of an extremum, relative to the median
    absolute value (speed) or the median absolute deviation (pca) of the curve.
    """
    check_choice(method, ("speed", "pca"), name="method")
    pos, fps = _check_positions(positions, fps)
    min_interval = _check_seconds(min_interval, name="min_interval")
    rel_prominence = check_positive(
        rel_prominence, name="rel_prominence", unit="fraction of the curve's scale", allow_zero=True
    )
    if method == "speed":
        frames = speed_minima(
            speed_curve(pos, fps=fps, smooth=smooth), fps, min_interval, rel_prominence
        )
    else:
        distance = max(1, int(time_to_frames(min_interval, fps=fps, mode="round")))
        curve = pca_curve(pos, fps=fps, window=window, smooth=smooth)
        # the projection's median absolute deviation
        scale = float(np.median(np.abs(curve - np.median(curve))))
        prom = rel_prominence * scale if scale > 0 else None
        lo, _ = find_peaks(-curve, prominence=prom)
        hi, _ = find_peaks(curve, prominence=prom)
        kept: list[int] = []  # drop extrema closer than distance to the previously kept one
        for f in np.sort(np.concatenate([lo, hi])):
            if not kept or f - kept[-1] >= distance:
                kept.append(int(f))
        frames = kept
    frames = np.asarray(frames, dtype=np.int64)
    if frames.size == 0:
        warn(
            f"no motion beats found in {pos.shape[0]} frames (method={method!r}, "
            f"smooth={smooth} s): the motion may be static or too short",
            stacklevel=2,
        )
    return frames


def kinematic_beats(
    motion: Any,
    *,
    method: str = "speed",
    smooth: float = 0.1,
    min_interval: float = 0.2,
    joints: Any = None,
    rel_prominence: float = 0.02,
    window: float = 0.5,
) -> np.ndarray:
    """Motion beat times of a clip [s] (see the module docstring for the methods)."""
    pos = motion_positions(motion, joints=joints)
    frames = kinematic_beat_frames(
        pos,
        fps=motion.fps,
        method=method,
        smooth=smooth,
        min_interval=min_interval,
        rel_prominence=rel_prominence,
        window=window,
    )
    return frames_to_time(frames, fps=motion.fps)


def interval_intensity(positions: Any, beat_frames: Any, *, fps: float) -> np.ndarray:
    """Mean :func:`kinetic_energy` over frames ``[b_i, b_{i+1})`` of successive beat frames."""
    energy = kinetic_energy(positions, fps=fps)
    bf = np.asarray(beat_frames)
    if bf.ndim != 1:
        raise ParameterError(f"beat_frames must be 1-D, got shape {bf.shape}")
    if not np.issubdtype(bf.dtype, np.integer) and not np.all(np.equal(np.mod(bf, 1), 0)):
        raise ParameterError(
            "beat_frames must be integer frame indices; convert seconds with "
            "beatsync.validation.time_to_frames"
        )
    bf = bf.astype(np.int64)
    if bf.size < 2:
        return np.empty(0)
    if np.any(np.diff(bf) <= 0):
        raise ParameterError(
            "beat frames must be strictly increasing and at least one frame apart "
            "(two beats fell on the same frame: are the beat times too close?)"
        )
    if bf[0] < 0 or bf[-1] >= energy.size:
        raise ParameterError(
            f"beat frames span {bf[0]}..{bf[-1]} but the clip has {energy.size} frames"
        )
    cum = np.concatenate([[0.0], np.cumsum(energy)])
    return (cum[bf[1:]] - cum[bf[:-1]]) / np.diff(bf)


def beat_interval_intensity(motion: Any, beat_times: Any, *, joints: Any = None) -> np.ndarray:
    """Motion intensity of each interval between successive motion beats [s] of a clip."""
    fps = check_fps(motion.fps)
    duration = float(frames_to_time(motion.n_frames - 1, fps=fps))
    beats = check_times(beat_times, name="beat_times", duration=duration)
    pos = motion_positions(motion, joints=joints)
    frames = time_to_frames(beats, fps=fps)
    return interval_intensity(pos, frames, fps=fps)


def motion_tempo(
    beat_times: Any,
    *,
    min_bpm: float = 30.0,
    max_bpm: float = 240.0,
    tolerance: float = 0.08,
) -> float:
    """Tempo of a dance from its motion beats [s], by beat induction [BPM].

    Kinematic beats miss beats (a held pose) more often than they add them, so
    successive motion beats are whole numbers ``n_i`` of beat periods ``P`` apart. As in
    Dixon 2001's inter-onset clustering (and paper B's [XTY10]), over a log-spaced grid of
    periods in ``[60 / max_bpm, 60 / min_bpm]``::

        score(P) = sum_i max_{n >= 1} exp(-log(d_i / (n P))^2 / (2 tolerance^2)) / n,

    (the 1/n weight makes the fundamental win over its sub-multiples; ``tolerance`` in
    log-duration); the best is refined to ``sum d_i / sum n_i`` over the intervals it
    explains within twice the tolerance.

    >>> motion_tempo([0.0, 0.5, 1.0, 2.0, 2.5])  # one missed beat
    120.0
    """
    lo, hi = check_range(min_bpm, max_bpm, name="(min_bpm, max_bpm)", unit="BPM")
    tol = float(tolerance)
    if not np.isfinite(tol) or not 0 < tol < 1:
        raise ParameterError(f"tolerance={tolerance!r} must lie in (0, 1) [log-duration]")
    t = check_times(beat_times, name="motion beat times")
    if t.size < 2:
        raise ParameterError(
            f"{t.size} motion beat(s): a tempo needs at least two (is the clip static or "
            "shorter than one beat?)"
        )
    d = np.diff(t)
    periods = np.geomspace(60.0 / hi, 60.0 / lo, 600)
    n_max = max(1, int(np.ceil(d.max() / periods[0])))
    n = np.arange(1, min(n_max, 16) + 1)
    # (P, i, n): match of interval i as n periods P
    x = np.log(d[None, :, None] / (n[None, None, :] * periods[:, None, None]))
    match = np.exp(-(x**2) / (2 * tol * tol)) / n[None, None, :]
    best_n = np.argmax(match, axis=2)
    score = np.max(match, axis=2).sum(axis=1)
    k = int(np.argmax(score))
    p = periods[k]
    ni = n[best_n[k]]
    fit = np.abs(np.log(d / (ni * p))) <= 2 * tol
    if fit.any():
        p = float(np.sum(d[fit]) / np.sum(ni[fit]))  # least-squares period of the fit
    return float(60.0 / p)
