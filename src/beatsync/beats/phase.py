"""Beat placement: the phase HMM for a given tempo curve, and snapping to onsets.

The onset signal is correlated with a pulse train that follows the decoded tempo curve
(eq. 8), in 4-beat windows every 0.25 s; a circular phase HMM picks the phase, and each
beat is snapped to the nearby onset with the best strength x closeness. Bands are weighted
by their **phase concentration** at the decoded tempo (:func:`band_phase_weights`), not
paper A's ``6 - c``: a bass line between the beats would pull the phase onto the off-beat
(docs/tuning.md#band-phase-weights).
"""

from __future__ import annotations

import functools

import numpy as np

from .onset import OnsetSignal
from .tempo import analysis_windows, viterbi

__all__ = ["band_phase_weights", "phase_hmm", "snap_to_onsets", "place_beats"]


def band_phase_weights(
    bands: np.ndarray, cycles: np.ndarray, starts=None, stops=None
) -> np.ndarray:
    """Each band's phase concentration over the beat cycle, normalised to sum to 1.

    In each window ``[a, b)`` (default: the whole signal) band ``c`` has the concentration
    ``|sum_n x_c(n) exp(2 pi i cycles(n))| / sum_n x_c(n)`` (``cycles`` [beats] per frame);
    its weight is their mean weighted by its onset strength per window (so a phase slip
    does not cancel it out); equal weights if no band has any onset.
    """
    n_bands = bands.shape[0]
    if starts is None:
        starts, stops = [0], [bands.shape[1]]
    turn = np.exp(2j * np.pi * cycles)
    num, den = np.zeros(n_bands), np.zeros(n_bands)
    for a, b in zip(starts, stops, strict=True):
        x = bands[:, a:b]
        num += np.abs(x @ turn[a:b])  # mass times concentration
        den += x.sum(axis=1)
    conc = np.divide(num, den, out=np.zeros(n_bands), where=den > 0)
    total = conc.sum()
    if not total > 0:
        return np.full(n_bands, 1.0 / n_bands)
    return conc / total


#: Phase HMM: phase states per beat, pulse width and phase step sd [beats], sharpness.
N_PHASE, PULSE_WIDTH, PHASE_SIGMA, PHASE_BETA = 64, 0.04, 0.03, 6.0


def phase_hmm(env: np.ndarray, cycles: np.ndarray, starts, stops) -> np.ndarray:
    """Viterbi path of the beat phase (fraction of a beat) per window: beats are where
    ``cycles + phase`` is an integer, observed by correlating the onset signal ``env`` with
    a pulse train at those times (eq. 8)."""
    n_phase = N_PHASE
    frac = np.mod(cycles, 1.0)
    bins = np.rint(frac * n_phase).astype(np.int64) % n_phase
    q, kf, log_trans = _phase_terms()
    hist = np.empty((len(starts), n_phase))
    for i, (a, b) in enumerate(zip(starts, stops, strict=True)):
        hist[i] = np.bincount(bins[a:b], weights=env[a:b], minlength=n_phase)
    # r(theta) = sum_n env(n) K(frac(n) + theta): circular cross-correlation, all
    # windows in one batch of FFTs
    obs = np.fft.irfft(np.conj(np.fft.rfft(hist, axis=1)) * kf, n=n_phase, axis=1).T
    scale = np.maximum(obs.max(axis=0, keepdims=True), 1e-12)
    log_like = PHASE_BETA * (obs / scale - 1.0)
    path = viterbi(log_like, log_trans)
    return q[path]


@functools.lru_cache(maxsize=1)
def _phase_terms():
    """The phase grid, pulse kernel spectrum and log transitions of :func:`phase_hmm`."""
    n_phase, pulse_width, phase_sigma = N_PHASE, PULSE_WIDTH, PHASE_SIGMA
    q = np.arange(n_phase) / n_phase
    dq = np.minimum(q, 1 - q)
    kernel = np.exp(-0.5 * (dq / pulse_width) ** 2)
    kf = np.fft.rfft(kernel)
    d = (q[:, None] - q[None, :] + 0.5) % 1.0 - 0.5
    trans = np.exp(-0.5 * (d / phase_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    log_trans = np.log(trans)
    for arr in (q, kf, log_trans):
        arr.flags.writeable = False
    return q, kf, log_trans


#: Beats snap to onsets within this many beat periods, of at least this share of the
#: strongest onset's strength (weaker onsets also do not count as activity).
SNAP_REACH, MIN_REL_STRENGTH = 0.12, 0.05


def snap_to_onsets(beats, periods_at_beats, onset_times, onset_strengths):
    """Move each beat to the onset within :data:`SNAP_REACH` beat periods with the best
    strength times a Gaussian of its distance (sd ``SNAP_REACH / 2`` periods)."""
    reach = SNAP_REACH
    strong = onset_strengths >= MIN_REL_STRENGTH * np.max(onset_strengths)
    t, s = onset_times[strong], onset_strengths[strong]
    out = beats.copy()
    lo = np.searchsorted(t, beats - reach * periods_at_beats)
    hi = np.searchsorted(t, beats + reach * periods_at_beats)
    for i in np.flatnonzero(hi > lo):
        dist = (t[lo[i] : hi[i]] - beats[i]) / (0.5 * reach * periods_at_beats[i])
        j = lo[i] + int(np.argmax(s[lo[i] : hi[i]] * np.exp(-0.5 * dist**2)))
        out[i] = t[j]
    return out


def place_beats(
    ons: OnsetSignal,
    period_w: np.ndarray,
    centres: np.ndarray,
    tempo_win_s: float,
    duration: float,
):
    """Beats [s] for a step-wise tempo curve (a period per tempo window) and the period at
    each; the phase is decoded in 4-beat windows, so that it follows tempo changes quickly.
    """
    fps = ons.fps
    n = ons.bands.shape[1]
    t_frames = np.arange(n) / fps
    period_f = period_w[np.searchsorted((centres[1:] + centres[:-1]) / 2, t_frames)]
    cycles = np.cumsum(1.0 / (period_f * fps))
    # band weights: phase concentration over tempo windows (see the module docstring)
    w_starts, w_stops, _ = analysis_windows(n, fps, tempo_win_s, tempo_win_s / 2)
    raw = band_phase_weights(ons.bands, cycles, w_starts, w_stops) @ ons.bands
    ph_win = float(np.clip(4.0 * np.median(period_w), 1.5, tempo_win_s))
    p_starts, p_stops, p_centres = analysis_windows(n, fps, ph_win, 0.25)
    theta_w = phase_hmm(raw, cycles, p_starts, p_stops)
    theta_u = np.unwrap(theta_w * 2 * np.pi) / (2 * np.pi)
    theta_f = np.interp(t_frames, p_centres, theta_u)
    total = cycles + theta_f
    k = np.floor(total)
    idx = np.flatnonzero(np.diff(k) > 0)
    # sub-frame time of the integer crossing
    frac = (k[idx + 1] - total[idx]) / (total[idx + 1] - total[idx])
    beats = t_frames[idx] + frac / fps
    periods = period_f[idx]
    beats = snap_to_onsets(beats, periods, ons.onset_times, ons.onset_strengths)
    # trim beats outside the region with onset activity
    act = ons.onset_times[ons.onset_strengths >= MIN_REL_STRENGTH * ons.onset_strengths.max()]
    keep = (beats >= act[0] - 0.5 * periods) & (beats <= act[-1] + 0.5 * periods)
    keep &= (beats >= 0) & (beats <= duration)
    beats, periods = beats[keep], periods[keep]
    if beats.size > 1:  # strictly increasing, no two beats closer than half a period
        keep = np.concatenate([[True], np.diff(beats) > 0.5 * periods[1:]])
        beats, periods = beats[keep], periods[keep]
    return beats, periods
