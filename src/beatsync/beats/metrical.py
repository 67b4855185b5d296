"""The metrical level: which pulse of the music is the beat (octave errors).

Deliberately and per constant-tempo segment: the beat is the pulse whose alternate
pulses carry comparable onset *energy* (uniformity >= 0.15 of the mean squared
energy flux in +-30 ms). If the points halfway (or a third of the way) between the
beats are that strong, the faster pulse is the beat; if every other beat is much
weaker, the slower one is.
"""

from __future__ import annotations

import numpy as np

from ..units import time_to_frames

__all__ = ["level_factor"]


def _window_energy(env: np.ndarray, fps: float, times: np.ndarray, reach_s: float = 0.03):
    """Sum of the onset signal within +-reach_s of each time."""
    cs = np.concatenate([[0.0], np.cumsum(env)])
    a = np.clip(time_to_frames(times - reach_s, fps=fps), 0, env.size)
    b = np.clip(time_to_frames(times + reach_s, fps=fps) + 1, 0, env.size)
    return cs[b] - cs[a]


def _uniformity(signals, fps: float, a: np.ndarray, b: np.ndarray) -> float:
    best = 0.0
    for env in signals:
        ea = np.mean(_window_energy(env, fps, a) ** 2)
        eb = np.mean(_window_energy(env, fps, b) ** 2)
        if max(ea, eb) > 0:
            best = max(best, min(ea, eb) / max(ea, eb))
    return best


def level_factor(signals, fps, beats, level_ratio: float, accent_ratio: float) -> float:
    """Factor on the beat period (1/2, 1/3, 2 or 1) deciding the metrical level."""
    d = np.diff(beats)
    if _uniformity(signals, fps, beats[:-1], beats[:-1] + d / 2) >= level_ratio:
        return 0.5
    thirds = min(
        _uniformity(signals, fps, beats[:-1], beats[:-1] + d / 3),
        _uniformity(signals, fps, beats[:-1], beats[:-1] + 2 * d / 3),
    )
    if thirds >= level_ratio:
        return 1.0 / 3.0
    if beats.size >= 4 and _uniformity(signals, fps, beats[0::2], beats[1::2]) < accent_ratio:
        return 2.0
    return 1.0
