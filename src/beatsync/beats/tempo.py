"""Tempo: the tempo HMM over beat periods, and a plain-numpy Viterbi decoder.

The tempo (beat period) is a hidden state per analysis window (8 s, 1 s hop). Its
observation is a salience per candidate period (:mod:`beatsync.beats.metrical`
gives the tactus salience of the metrical model); transitions are log-normal in the
period ratio plus a small jump probability, so that an abrupt tempo change is
followed rather than averaged away. Decoding is :func:`viterbi` (numpy, no JIT: our
state spaces have a few hundred states and a few hundred steps).
"""

from __future__ import annotations

import numpy as np

from ..units import frames_to_time, time_to_frames

__all__ = ["analysis_windows", "period_grid", "tempo_hmm", "viterbi"]


def analysis_windows(n_frames: int, fps: float, win_s: float, hop_s: float):
    """Start/stop frames and centre times [s] of analysis windows covering the signal."""
    dur = float(frames_to_time(n_frames, fps=fps))
    if dur <= win_s:
        centres = np.array([dur / 2])
    else:
        n_win = int(np.floor((dur - win_s) / hop_s)) + 1
        centres = win_s / 2 + hop_s * np.arange(n_win)
        if dur - (centres[-1] + win_s / 2) > hop_s / 2:
            centres = np.append(centres, dur - win_s / 2)
    half = int(time_to_frames(win_s / 2, fps=fps))
    c = time_to_frames(centres, fps=fps)
    return np.maximum(c - half, 0), np.minimum(c + half, n_frames), centres


def period_grid(min_bpm: float, max_bpm: float, step: float = 0.005) -> np.ndarray:
    """Log-spaced beat periods [s] from ``60 / max_bpm`` to ``60 / min_bpm``."""
    lo, hi = np.log(60.0 / max_bpm), np.log(60.0 / min_bpm)
    n = max(int(np.ceil((hi - lo) / step)) + 1, 2)
    return np.exp(np.linspace(lo, hi, n))


def viterbi(
    log_obs: np.ndarray, log_trans: np.ndarray, log_init: np.ndarray | None = None
) -> np.ndarray:
    """Most likely state sequence of an HMM, in the log domain.

    Parameters
    ----------
    log_obs : np.ndarray [shape=(n_states, n_steps)]
        Log observation likelihood of each state at each step.
    log_trans : np.ndarray [shape=(n_states, n_states)]
        ``log_trans[i, j]``: log probability of moving from state ``i`` to ``j``.
    log_init : np.ndarray [shape=(n_states,)], optional
        Log initial distribution (uniform if None).

    Returns
    -------
    path : np.ndarray [shape=(n_steps,)], int
    """
    n_states, n_steps = log_obs.shape
    value = log_obs[:, 0] + (0.0 if log_init is None else log_init)
    back = np.empty((n_steps, n_states), dtype=np.int64)
    cols = np.arange(n_states)
    for t in range(1, n_steps):
        scores = value[:, None] + log_trans
        back[t] = np.argmax(scores, axis=0)
        value = scores[back[t], cols] + log_obs[:, t]
    path = np.empty(n_steps, dtype=np.int64)
    path[-1] = int(np.argmax(value))
    for t in range(n_steps - 1, 0, -1):
        path[t - 1] = back[t, path[t]]
    return path


def tempo_hmm(
    log_obs: np.ndarray,
    periods: np.ndarray,
    *,
    trans_sigma: float,
    p_jump: float,
    log_prior: np.ndarray | None = None,
) -> np.ndarray:
    """Viterbi path (state index per window) of the tempo HMM.

    Parameters
    ----------
    log_obs : np.ndarray [shape=(n_periods, n_windows)]
        Log observation likelihood of each beat period per window.
    periods : np.ndarray [s]
        The period grid (log-spaced).
    trans_sigma : float > 0
        Standard deviation of the log period ratio between consecutive windows.
    p_jump : float in [0, 1)
        Probability of an abrupt change to any period.
    log_prior : np.ndarray, optional
        Log initial distribution over the periods.
    """
    logp = np.log(periods)
    d = logp[:, None] - logp[None, :]
    trans = np.exp(-0.5 * (d / trans_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    trans = (1 - p_jump) * trans + p_jump / periods.size
    return viterbi(log_obs, np.log(trans), log_prior)
