"""Tempo: the tempo HMM over beat periods, and a plain-numpy Viterbi decoder.

The beat period is a hidden state per analysis window, observed through the tactus
salience (:mod:`.metrical`); transitions are log-normal in the period ratio plus a small
jump probability, so an abrupt tempo change is followed rather than averaged away.
"""

from __future__ import annotations

import functools

import numpy as np

from ..validation import frames_to_time, time_to_frames

__all__ = [
    "analysis_windows",
    "period_grid",
    "tempo_hmm",
    "viterbi",
    "viterbi_banded",
]


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


def viterbi(log_obs: np.ndarray, log_trans: np.ndarray) -> np.ndarray:
    """Most likely state path of an HMM, log domain, uniform start: ``log_obs``
    (n_states, n_steps), ``log_trans[i, j]`` from ``i`` to ``j``.
    """
    n_states, n_steps = log_obs.shape
    value = log_obs[:, 0]
    back = np.empty((n_steps, n_states), dtype=np.int64)
    cols = np.arange(n_states)
    for t in range(1, n_steps):
        scores = value[:, None] + log_trans
        back[t] = np.argmax(scores, axis=0)
        value = scores[back[t], cols] + log_obs[:, t]
    return _backtrack(back, value)


def _backtrack(back: np.ndarray, value: np.ndarray) -> np.ndarray:
    """The Viterbi path from back-pointers ``(n_steps, n_states)`` and final values."""
    path = np.empty(back.shape[0], dtype=np.int64)
    path[-1] = int(np.argmax(value))
    for t in range(back.shape[0] - 1, 0, -1):
        path[t - 1] = back[t, path[t]]
    return path


@functools.lru_cache(maxsize=8)
def _log_transitions(
    periods_key: bytes, trans_sigma: float, p_jump: float
) -> tuple[np.ndarray, int | None, tuple[np.ndarray, np.ndarray] | None]:
    """Log transition matrix of the tempo HMM, its band ``reach`` (the largest ``|i - j|``
    whose log transition is not exactly ``log(p_jump / n)``; None without jumps) and
    :func:`_band` of it (cached per period grid).
    """
    logp = np.log(np.frombuffer(periods_key, dtype=np.float64))
    d = logp[:, None] - logp[None, :]
    trans = np.exp(-0.5 * (d / trans_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    trans = (1 - p_jump) * trans + p_jump / logp.size
    with np.errstate(divide="ignore"):  # p_jump 0: far transitions are impossible
        log_trans = np.log(trans)
    log_trans.flags.writeable = False
    if p_jump <= 0:
        return log_trans, None, None
    i, j = np.nonzero(log_trans != np.log(p_jump / logp.size))
    reach = int(np.max(np.abs(i - j))) if i.size else 0
    return log_trans, reach, _band(log_trans, reach)


def tempo_hmm(
    log_obs: np.ndarray, periods: np.ndarray, *, trans_sigma: float, p_jump: float
) -> np.ndarray:
    """Viterbi path (state index per window) of the tempo HMM over the log-spaced ``periods``
    [s]: ``trans_sigma`` is the sd of the log period ratio between windows, ``p_jump`` the
    probability of an abrupt change to any period.
    """
    periods = np.ascontiguousarray(periods, dtype=np.float64)
    log_trans, reach, band = _log_transitions(periods.tobytes(), float(trans_sigma), float(p_jump))
    if reach is not None and 2 * reach + 1 < periods.size:
        return viterbi_banded(log_obs, band, np.log(p_jump / periods.size))
    return viterbi(log_obs, log_trans)


def _band(log_trans: np.ndarray, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """``(band, src)`` of shape (n_states, 2 reach + 1): ``log_trans[src[j, d], j]`` for the
    predecessors ``src[j, d] = j + d - reach`` of each state (-inf outside the grid).
    """
    n_states = log_trans.shape[0]
    offsets = np.arange(-reach, reach + 1)
    src = np.arange(n_states)[:, None] + offsets[None, :]  # predecessor i of j, (n, width)
    valid = (src >= 0) & (src < n_states)
    band = np.full(src.shape, -np.inf)
    band[valid] = log_trans[src[valid], np.nonzero(valid)[0]]
    src = np.clip(src, 0, n_states - 1)
    for arr in (band, src):
        arr.flags.writeable = False
    return band, src


def viterbi_banded(
    log_obs: np.ndarray, band_terms: tuple[np.ndarray, np.ndarray], log_jump: float
) -> np.ndarray:
    """:func:`viterbi` for transitions that are a band (:func:`_band`) plus a uniform jump
    ``log_jump`` (the least of all): ``(2 reach + 1) n`` a step instead of ``n**2``.
    """
    n_states, n_steps = log_obs.shape
    band, src = band_terms
    reach = band.shape[1] // 2
    cols = np.arange(n_states)
    value = log_obs[:, 0]
    back = np.empty((n_steps, n_states), dtype=np.int64)
    pad = np.full(n_states + 2 * reach, -np.inf)
    for t in range(1, n_steps):
        pad[reach : reach + n_states] = value
        # row j: the values of j's predecessors j - reach .. j + reach (a reduction over
        # contiguous rows, faster than over the columns of the transposed layout)
        scores = np.lib.stride_tricks.sliding_window_view(pad, 2 * reach + 1) + band
        k = np.argmax(scores, axis=1)
        best = scores[cols, k]
        i_best = src[cols, k]
        top = int(np.argmax(value))
        jump = value[top] + log_jump
        use_jump = jump > best
        best[use_jump] = jump
        i_best[use_jump] = top
        back[t] = i_best
        value = best + log_obs[:, t]
    return _backtrack(back, value)
