"""Beat placement: the phase HMM for a given tempo curve, and snapping to onsets.

The onset signal is correlated with a reference pulse train that follows the decoded
tempo curve (eq. 8), in 4-beat windows every 0.25 s, for 64 phase offsets; a circular
phase HMM decoded with Viterbi picks the offset. Each beat is then snapped to the
nearby onset with the best strength x closeness (phase-slope zero crossings give the
onset time to a fraction of a frame).

The phase observation sums the four band onset signals with equal weights, not with
paper A's weights ``6 - c`` (eq. 7, which :attr:`OnsetSignal.envelope` keeps). On the
two annotated real recordings the lowest band (0-250 Hz) holds the most onset
strength, yet its onsets fall evenly over the beat: 0.25 and 0.27 of its strength lie
within an eighth of a beat of an annotated beat, as for onsets at random phases
(0.25), against 0.34-0.51 for the bands above 1 kHz. Weighted 5:4:3:2, it pulled
the phase of short excerpts onto the off-beat: over the excerpts of 15-30 s
starting every 2.5 s (56 of Hainsworth 001, 16 of the Ballroom waltz), the mean
F-measure was 0.992 and 0.842 (lowest 0.680 and 0.000: two waltz excerpts on the
off-beat), and with equal weights 0.998 and 0.998 (lowest 0.970 and 0.964); the
scores of the whole recordings and of the synthetic set are unchanged. Chosen on those
two recordings only: a sanity check, not a benchmark (``benchmarks/bench_beats.py``,
excerpt table).
"""

from __future__ import annotations

import numpy as np

from .onset import OnsetSignal
from .tempo import analysis_windows, viterbi

__all__ = ["phase_hmm", "snap_to_onsets", "place_beats"]


def phase_hmm(
    env: np.ndarray,
    cycles: np.ndarray,
    starts,
    stops,
    *,
    n_phase: int,
    pulse_width: float,
    phase_sigma: float,
    beta: float,
) -> np.ndarray:
    """Viterbi path of the beat phase (fraction of a beat) per window.

    ``cycles`` is the integrated tempo [beats] per frame; beats are where
    ``cycles + phase`` is an integer. The observation is the correlation of the onset
    signal with a pulse train at those times (eq. 8), for each of ``n_phase`` phases.
    """
    frac = np.mod(cycles, 1.0)
    bins = np.rint(frac * n_phase).astype(np.int64) % n_phase
    q = np.arange(n_phase) / n_phase
    dq = np.minimum(q, 1 - q)
    kernel = np.exp(-0.5 * (dq / pulse_width) ** 2)
    kf = np.fft.rfft(kernel)
    obs = np.zeros((n_phase, len(starts)))
    for i, (a, b) in enumerate(zip(starts, stops, strict=True)):
        hist = np.bincount(bins[a:b], weights=env[a:b], minlength=n_phase)
        # r(theta) = sum_n env(n) K(frac(n) + theta): circular cross-correlation
        obs[:, i] = np.fft.irfft(np.conj(np.fft.rfft(hist)) * kf, n=n_phase)
    scale = np.maximum(obs.max(axis=0, keepdims=True), 1e-12)
    log_like = beta * (obs / scale - 1.0)
    d = (q[:, None] - q[None, :] + 0.5) % 1.0 - 0.5
    trans = np.exp(-0.5 * (d / phase_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    path = viterbi(log_like, np.log(trans))
    return q[path]


def snap_to_onsets(
    beats, periods_at_beats, onset_times, onset_strengths, reach: float, min_rel: float
):
    """Move each beat to the best onset within ``reach`` beat periods.

    The best onset maximises strength times a Gaussian of its distance to the
    predicted beat (standard deviation ``reach / 2`` periods); onsets weaker than
    ``min_rel`` times the strongest are ignored.
    """
    if onset_times.size == 0 or beats.size == 0:
        return beats
    thresh = min_rel * np.max(onset_strengths)
    strong = onset_strengths >= thresh
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
    """Beats [s] for a tempo curve (period per tempo window), and the period at each beat.

    The tempo per frame is step-wise between window centres (abrupt changes stay
    abrupt); the phase is decoded in windows of 4 beats (1.5 s to ``tempo_win_s``),
    so that it follows tempo changes quickly.
    """
    raw = ons.bands.sum(axis=0)  # equal band weights (see the module docstring)
    fps = ons.fps
    n = raw.size
    t_frames = np.arange(n) / fps
    if centres.size > 1:
        mids = (centres[1:] + centres[:-1]) / 2
        period_f = period_w[np.searchsorted(mids, t_frames)]
    else:
        period_f = np.full(n, period_w[0])
    cycles = np.cumsum(1.0 / (period_f * fps))
    ph_win = float(np.clip(4.0 * np.median(period_w), 1.5, tempo_win_s))
    p_starts, p_stops, p_centres = analysis_windows(n, fps, ph_win, 0.25)
    theta_w = phase_hmm(
        raw,
        cycles,
        p_starts,
        p_stops,
        n_phase=64,
        pulse_width=0.04,
        phase_sigma=0.03,
        beta=6.0,
    )
    theta_u = np.unwrap(theta_w * 2 * np.pi) / (2 * np.pi)
    theta_f = np.interp(t_frames, p_centres, theta_u)
    total = cycles + theta_f
    k = np.floor(total)
    idx = np.flatnonzero(np.diff(k) > 0)
    # sub-frame time of the integer crossing
    frac = (k[idx + 1] - total[idx]) / (total[idx + 1] - total[idx])
    beats = t_frames[idx] + frac / fps
    periods = period_f[idx]
    beats = snap_to_onsets(
        beats, periods, ons.onset_times, ons.onset_strengths, reach=0.12, min_rel=0.05
    )
    # trim beats outside the region with onset activity
    act = ons.onset_times[ons.onset_strengths >= 0.05 * ons.onset_strengths.max()]
    keep = (beats >= act[0] - 0.5 * periods) & (beats <= act[-1] + 0.5 * periods)
    keep &= (beats >= 0) & (beats <= duration)
    beats, periods = beats[keep], periods[keep]
    if beats.size > 1:  # strictly increasing, no two beats closer than half a period
        keep = np.concatenate([[True], np.diff(beats) > 0.5 * periods[1:]])
        beats, periods = beats[keep], periods[keep]
    return beats, periods
