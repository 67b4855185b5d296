"""The drum-pattern cue of the metrical level: a bass drum and a snare drum that
alternate mark the beat (Goto 2001, J. New Music Research 30(2), 159-171).

The metrical model's prior pulls a drum pattern at 60 or 180 BPM towards 110 BPM; this
cue settles it:

1. **Two envelopes** (:func:`drum_envelopes`): the rising energy (not its log: the decays
   would count as much as the attacks) of the bass drum's and the snare drum's band.
2. **Alternation** (:func:`alternation_cue`): per window and period ``tau``, ``A(tau) =
   (x_LM(tau) + x_ML(tau)) / 2 - (r_L(tau) + r_M(tau)) / 2``, normalised cross- minus
   autocorrelations of the two envelopes: near +0.7 at a drum pattern's beat, -0.7 at
   twice it, 0 for clicks. Only periods with :data:`MIN_CYCLES` cycles are scored.
3. **Evidence, never counter-evidence**: ``log_obs += DRUM_WEIGHT * max(A - NOISE_LEVEL,
   0)`` before the tempo HMM decodes.

Calibrated: docs/tuning.md#drum-cue.
"""

from __future__ import annotations

import numpy as np

from .onset import _frames

__all__ = [
    "DRUM_WEIGHT",
    "LOW_BAND_HZ",
    "MID_BAND_HZ",
    "CUE_SR",
    "N_FFT_S",
    "HOP_S",
    "NOISE_LEVEL",
    "MIN_CYCLES",
    "drum_envelopes",
    "alternation_cue",
]

#: Weight of the alternation cue in the tactus observation (log-likelihood units).
DRUM_WEIGHT = 4.0

#: The bass drum's band and the snare drum's band [Hz].
LOW_BAND_HZ = (30.0, 150.0)
MID_BAND_HZ = (150.0, 5000.0)

#: Audio above this rate is resampled to it first [Hz] (the bands end at 5 kHz).
CUE_SR = 11025.0

#: STFT window [s]: about 11 Hz bins, two to three of them in the bass drum's band.
N_FFT_S = 0.093

#: Alternation that noise reaches: subtracted from the score before it counts.
NOISE_LEVEL = 0.2

#: Fewest cycles of a period inside a window for the cue to score it.
MIN_CYCLES = 4

#: Hop of the STFT [s] (4 frames of the default onset signal, 128-sample hops at 22.05 kHz).
HOP_S = 4 * 128 / 22050

#: STFT frames computed at once (bounds the memory of a long song).
BLOCK_FRAMES = 2048


def drum_envelopes(y: np.ndarray, sr: float, fps: float, n_frames: int) -> np.ndarray:
    """Rising energy of the bass-drum and snare-drum bands, shape (2, n_frames) at ``fps``
    [Hz] (frame ``k`` at ``k / fps`` s); ``y`` validated by the caller.
    """
    import scipy.fft  # noqa: PLC0415 (batched real FFTs)

    if sr > CUE_SR:  # float32 out; no float64 copy of a long full-rate recording
        from ..audio_resampling import resample  # noqa: PLC0415

        y = resample(y, sr, CUE_SR, int(round(y.size * CUE_SR / sr)), keep_level=False)
        sr = CUE_SR
    peak = float(np.max(np.abs(y)))
    y = (np.asarray(y) / (peak if peak > 0 else 1.0)).astype(np.float32, copy=False)
    n_fft = int(2 ** np.round(np.log2(N_FFT_S * sr)))
    hop = max(int(round(HOP_S * sr)), 1)
    frames = _frames(y, n_fft, hop)  # centred, as the front end's
    freqs = np.arange(n_fft // 2 + 1) * sr / n_fft
    member = np.stack(
        [(freqs >= lo) & (freqs < hi) for lo, hi in (LOW_BAND_HZ, MID_BAND_HZ)], axis=1
    ).astype(np.float32)
    window = np.hanning(n_fft + 1)[:-1].astype(np.float32)
    energy = np.empty((frames.shape[0], 2), dtype=np.float64)
    for a in range(0, frames.shape[0], BLOCK_FRAMES):
        spec = scipy.fft.rfft(frames[a : a + BLOCK_FRAMES] * window, axis=1)
        energy[a : a + BLOCK_FRAMES] = (spec.real**2 + spec.imag**2) @ member
    energy = energy.T
    # the energy, not its log (see the module docstring)
    rise = np.maximum(np.diff(energy, axis=1, prepend=energy[:, :1]), 0.0)
    times = np.arange(rise.shape[1]) * hop / sr
    target = np.arange(n_frames) / fps
    return np.stack([np.interp(target, times, r) for r in rise])


def alternation_cue(
    envelopes: np.ndarray,
    fps: float,
    starts: np.ndarray,
    stops: np.ndarray,
    periods: np.ndarray,
) -> np.ndarray:
    """``max(A - NOISE_LEVEL, 0)`` of each period per window, (n_periods, n_windows); windows
    with a silent band and periods with fewer than :data:`MIN_CYCLES` cycles score 0.
    """
    import scipy.fft  # noqa: PLC0415

    periods = np.asarray(periods, dtype=np.float64)
    out = np.zeros((periods.size, len(starts)))
    lags = periods * fps
    for w, (a, b) in enumerate(zip(starts, stops, strict=True)):
        n = int(b - a)
        seg = envelopes[:, a:b] - envelopes[:, a:b].mean(axis=1, keepdims=True)
        norms = np.sqrt((seg**2).sum(axis=1))
        if n < 2 or np.any(norms <= 0):
            continue
        size = scipy.fft.next_fast_len(2 * n, real=True)
        spec = scipy.fft.rfft(seg, n=size, axis=1)
        low, mid = spec
        auto = scipy.fft.irfft(spec.real**2 + spec.imag**2, n=size, axis=1)[:, :n]
        auto /= norms[:, None] ** 2
        # cross[k] = sum_t low(t) mid(t + k); negative lags wrap to the end
        cross = scipy.fft.irfft(np.conj(low) * mid, n=size) / (norms[0] * norms[1])
        ahead = cross[:n]
        behind = np.concatenate([cross[:1], cross[: size - n : -1]])[:n]
        k = np.arange(n)
        score = 0.5 * (np.interp(lags, k, ahead) + np.interp(lags, k, behind))
        score -= 0.5 * (np.interp(lags, k, auto[0]) + np.interp(lags, k, auto[1]))
        out[:, w] = np.where(lags * MIN_CYCLES <= n, np.maximum(score - NOISE_LEVEL, 0.0), 0.0)
    return out
