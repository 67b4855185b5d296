"""Synthetic periodic multi-channel joint-angle signals with known period boundaries.

Stands in for paper A's synthetic experiments (sec. 3): 29 joint-angle channels at
25 Hz, 750 frames, every period a time-warped copy of one template cycle whose
duration jitters within +-``jitter`` of the nominal period, with a small waveform
change from period to period and white noise at a given SNR. ``values`` are
``(n_frames, n_channels)`` degrees; the boundaries are frame indices from 0 to
``n_frames - 1`` (the convention of :func:`beatsync.segment.segment`) and times [s].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..motion import Motion
from ..validation import check_fps, frames_to_time

__all__ = ["SyntheticMotion", "periodic_motion"]


@dataclass(frozen=True)
class SyntheticMotion:
    """A synthetic periodic motion (channels ``"ch00_angle"``, ... [deg]), its ``n_periods +
    1`` true boundaries [s] and frames, the noiseless signal and the nominal ``period`` [s].
    """

    motion: Motion
    boundaries: np.ndarray
    boundary_frames: np.ndarray
    clean: np.ndarray
    period: float

    @property
    def n_periods(self) -> int:
        return int(self.boundary_frames.size - 1)


def periodic_motion(
    *,
    n_frames: int = 750,
    n_channels: int = 29,
    fps: float = 25.0,
    n_periods: int = 25,
    jitter: float = 0.08,
    variation: float = 0.05,
    snr_db: float | None = 20.0,
    n_harmonics: int = 3,
    n_constant: int = 0,
    seed: int | None = 0,
) -> SyntheticMotion:
    """A periodic joint-angle signal with known period boundaries (see the module docstring).

    Each channel is ``offset_c + amp_c * f_c(phase)``, ``f_c`` a sum of ``n_harmonics``
    random harmonics and the phase rising by one within every period; ``variation`` changes
    the harmonics from period to period; ``n_constant`` channels are exactly constant.

    Examples
    --------
    >>> s = periodic_motion(n_frames=300, n_periods=10, seed=1)
    >>> s.motion.values.shape, s.n_periods, int(s.boundary_frames[0]), int(s.boundary_frames[-1])
    ((300, 29), 10, 0, 299)
    """
    fps = check_fps(fps)
    n_frames, n_channels, n_periods = int(n_frames), int(n_channels), int(n_periods)
    if n_periods < 2:
        raise ParameterError(f"n_periods={n_periods} must be >= 2")
    if n_channels < 1 or not 0 <= n_constant <= n_channels:
        raise ParameterError(
            f"n_channels={n_channels}, n_constant={n_constant}: need 0 <= n_constant <= n_channels"
        )
    nominal = (n_frames - 1) / n_periods
    if nominal < 4:
        raise ParameterError(
            f"n_frames={n_frames} over n_periods={n_periods} gives {nominal:.2f} frames per "
            "period; need at least 4"
        )
    if not 0 <= jitter < 0.5:
        raise ParameterError(f"jitter={jitter!r} must be in [0, 0.5) (a fraction of the period)")
    if variation < 0:
        raise ParameterError(f"variation={variation!r} must be >= 0")
    rng = np.random.default_rng(seed)

    # period durations: uniform jitter, rescaled to span the clip, rounded cumulatively
    dur = nominal * (1.0 + rng.uniform(-jitter, jitter, n_periods))
    dur *= (n_frames - 1) / dur.sum()
    frames = np.rint(np.concatenate([[0.0], np.cumsum(dur)])).astype(np.int64)
    frames[-1] = n_frames - 1
    if np.any(np.diff(frames) < 2):
        raise ParameterError("periods too short after rounding; use fewer periods")

    # phase within the period: linear from 0 to 1 over each period
    t = np.arange(n_frames, dtype=np.float64)
    idx = np.clip(np.searchsorted(frames, t, side="right") - 1, 0, n_periods - 1)
    frac = (t - frames[idx]) / (frames[idx + 1] - frames[idx])

    # template harmonics per channel, varied per period
    h = np.arange(1, n_harmonics + 1, dtype=np.float64)
    amp = rng.uniform(0.3, 1.0, (n_channels, n_harmonics)) / h  # (C, H)
    phi = rng.uniform(0.0, 2 * np.pi, (n_channels, n_harmonics))
    # waveform variation: random per boundary, blended linearly across each period so
    # the signal stays continuous (no artificial jump marks the true boundaries)
    d_amp = 1.0 + variation * rng.standard_normal((n_periods + 1, n_channels, n_harmonics))
    d_phi = variation * rng.standard_normal((n_periods + 1, n_channels, n_harmonics))
    w = frac[:, None, None]
    a_t = amp[None] * ((1 - w) * d_amp[idx] + w * d_amp[idx + 1])  # (n, C, H)
    p_t = phi[None] + (1 - w) * d_phi[idx] + w * d_phi[idx + 1]
    wave = np.sum(a_t * np.cos(2 * np.pi * h * frac[:, None, None] + p_t), axis=2)
    scale = rng.uniform(5.0, 40.0, n_channels)  # [deg]
    offset = rng.uniform(-60.0, 60.0, n_channels)  # [deg]
    clean = offset + scale * wave
    if n_constant:
        const = rng.choice(n_channels, n_constant, replace=False)
        clean[:, const] = offset[const]
    values = clean.copy()
    if snr_db is not None:
        sig = clean.std(axis=0)
        noise_std = sig * 10.0 ** (-float(snr_db) / 20.0)
        values = values + rng.standard_normal(values.shape) * noise_std
    names = tuple(f"ch{c:02d}_angle" for c in range(n_channels))
    motion = Motion(values, fps, names, None, f"synthetic_{n_channels}ch")
    return SyntheticMotion(
        motion=motion,
        boundaries=frames_to_time(frames, fps=fps),
        boundary_frames=frames,
        clean=clean,
        period=nominal / fps,
    )
