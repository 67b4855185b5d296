"""Music beat tracking: phase-slope onsets and a tempo/phase HMM (paper A, section 4).

Data contract
-------------
- Input audio is mono float ``y`` (1-D, finite) with its sample rate ``sr`` > 0 [Hz].
- Output beat times are a 1-D ``float64`` array in seconds, strictly increasing.
- Tempo is in BPM; tempo curves are given per analysis window (centre times [s]).

Method (``method="psf"``)
-------------------------
1. **Phase-slope function** (:func:`phase_slope`). For short frames, the average
   group delay is computed without phase unwrapping as
   ``sum_k Re(X_k conj(Y_k)) / sum_k |X_k|^2`` per frequency band, where ``X`` is the
   STFT with window ``w`` and ``Y`` the STFT with the time-ramped window ``n w(n)``
   (energy-weighted averaging over the band's bins). Relative to the frame centre it
   is the phase slope: it crosses zero upwards when an impulse-like onset passes the
   frame centre, and ``t_frame - psf`` locates the onset to sub-frame precision.
2. **Onsets** (:func:`onset_strength_psf`): positive zero crossings of the phase
   slope in 4 bands, each weighted by the band's (locally normalised) spectral flux
   (eq. 6-7), bands combined with weights ``6 - c`` (c = 1..4, low bands count most).
3. **Tempo**: autocorrelation (unbiased, of the squared, slightly smoothed onset
   signal) in 8 s windows with 1 s hop; the salience of a beat period is the sum of
   the autocorrelation at its first 4 multiples; a log-normal prior on the period
   (around 0.55 s) and a tempo HMM with log-normal period-ratio transitions (plus a
   small jump probability, so that an abrupt tempo change is followed rather than
   averaged away), decoded with :func:`librosa.sequence.viterbi`.
4. **Phase**: the onset signal is correlated with a reference pulse train that
   follows the decoded tempo curve (eq. 8; band weighting is linear, so the
   weighted sum of band correlations is the correlation of the weighted onset
   signal), in 4-beat windows every 0.25 s, for 64 phase offsets; a circular phase
   HMM decoded with Viterbi picks the offset. Each beat is then snapped to the
   nearby onset with the best strength x closeness (phase-slope zero crossings give
   the onset time to a fraction of a frame).
5. **Metrical level** (octave errors), deliberately and per constant-tempo segment:
   the beat is the pulse whose alternate pulses carry comparable onset *energy*
   (uniformity >= 0.15 of the mean squared energy flux in +-30 ms, where the energy
   flux is the rectified increase of the smoothed band energies: loudness-
   proportional, unlike the log-compressed flux used for the onsets). If the points
   halfway (or a third of the way) between the beats are that strong, the faster
   pulse is the beat (a 180 BPM click track decoded at 90); if every other beat is
   much weaker, the slower one is (soft hi-hat eighths decoded as beats). Kick/snare
   alternation stays a single level. A known tempo (``bpm=``) bypasses the tempo
   HMM and this rule; a BPM range restricts both.

Audio above 22.05 kHz is first resampled to 22.05 kHz (``analysis_sr``), so the
front end behaves the same for 44.1 and 48 kHz input.

``method="librosa"`` wraps :func:`librosa.beat.beat_track` for comparison.

The front-end parameters (window, hop, FFT size, band edges) are not published in
the paper; the defaults are swept in ``notebooks/paper_a_sec4_beat_tracking.ipynb``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import librosa
import numpy as np
import scipy.ndimage
import scipy.signal

from .errors import BeatsyncWarning, ParameterError
from .units import check_positive, check_range, check_times, frames_to_time, time_to_frames

__all__ = [
    "BeatTrack",
    "OnsetSignal",
    "track_beats",
    "onset_strength_psf",
    "phase_slope",
    "check_audio",
    "check_bpm",
    "check_duration",
    "beat_tempo",
    "FRONTEND_DEFAULTS",
    "MIN_SANE_BPM",
    "MAX_SANE_BPM",
    "MIN_DURATION_S",
    "SILENCE_PEAK",
    "MIN_PULSE_CLARITY",
]

#: A ``bpm`` outside this range is refused as a likely unit mistake.
MIN_SANE_BPM = 20.0
MAX_SANE_BPM = 400.0
#: Audio shorter than this is refused [s] (:func:`check_duration`): two beat periods
#: at 80 BPM, three at 120 BPM. A shorter clip cannot show a pulse (two beat periods)
#: at any but the fastest tempi, and the tracker would return a tempo made up by its
#: prior. The madmom sample (2.8 s) passes.
MIN_DURATION_S = 1.5
#: Audio whose peak magnitude is below this (re full scale 1.0, -140 dBFS) is silent.
SILENCE_PEAK = 1e-7
#: Below this pulse clarity (median peak of the harmonic autocorrelation salience;
#: white noise about 0.35, music and the test items above 1.2) a warning says the
#: beats may be meaningless.
MIN_PULSE_CLARITY = 0.7

#: Defaults of the phase-slope front end (all swept in the notebook).
FRONTEND_DEFAULTS: dict[str, Any] = {
    "win_s": 0.023,  # analysis window [s]
    "hop_s": 0.0058,  # hop [s]
    "n_fft": None,  # FFT size [samples]; None: next power of two >= window
    "band_edges_hz": (0.0, 250.0, 1000.0, 4000.0, 22050.0),  # 4 bands [Hz]
    "flux_norm_s": 0.5,  # local-mean window removed from the flux [s]
    "analysis_sr": 22050,  # audio above this rate is resampled to it first [Hz]; None: never
}


@dataclass(frozen=True)
class BeatTrack:
    """Result of :func:`track_beats`.

    Attributes
    ----------
    beats : np.ndarray [s]
        Beat times, strictly increasing.
    tempo : float [bpm]
        Median of the tempo curve (NaN if no beat was found).
    tempo_times : np.ndarray [s]
        Centre of each tempo window.
    tempo_curve : np.ndarray [bpm]
        Tempo per window.
    method : str
        ``"psf"`` or ``"librosa"``.
    """

    beats: np.ndarray
    tempo: float
    tempo_times: np.ndarray
    tempo_curve: np.ndarray
    method: str


@dataclass(frozen=True)
class OnsetSignal:
    """Output of :func:`onset_strength_psf`.

    Attributes
    ----------
    envelope : np.ndarray [shape=(n_frames,)]
        Band-weighted onset signal at the frame rate (impulses at the onsets).
    bands : np.ndarray [shape=(n_bands, n_frames)]
        Per-band onset signals (unweighted).
    fps : float [Hz]
        Frame rate.
    onset_times : np.ndarray [s]
        Sub-frame onset times (phase-slope zero crossings) of all bands.
    onset_strengths : np.ndarray
        Band-weighted strength of each onset.
    band_weights : np.ndarray
        Weight ``6 - c`` of each band.
    psf : np.ndarray [shape=(n_bands, n_frames)] [s]
        Phase-slope function per band (NaN where the band is silent).
    energy_flux : np.ndarray [shape=(n_frames,)]
        Square root of the half-wave rectified increase of the band energies, summed
        over the bands, minus its local mean: a loudness-proportional onset signal
        (unlike the log-compressed flux), used to decide the metrical level.
    """

    envelope: np.ndarray
    bands: np.ndarray
    fps: float
    onset_times: np.ndarray
    onset_strengths: np.ndarray
    band_weights: np.ndarray
    psf: np.ndarray = field(repr=False)
    energy_flux: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)


# --------------------------------------------------------------------------- checks


def check_audio(y: Any, sr: Any, *, allow_silent: bool = False) -> tuple[np.ndarray, float]:
    """Validate mono audio; return ``(y float64, sr float)``.

    Parameters
    ----------
    y : array_like [shape=(n,)]
        Mono audio samples.
    sr : float > 0 [Hz]
    allow_silent : bool
        Accept all-silent audio (peak below :data:`SILENCE_PEAK`), e.g. to measure
        its level; beat tracking refuses it.

    Raises
    ------
    ParameterError
        Empty, multi-channel, non-finite or (unless ``allow_silent``) all-silent
        audio, or ``sr <= 0``.
    """
    try:
        sr_f = float(sr)
    except (TypeError, ValueError):
        raise ParameterError(f"sr={sr!r} is not a number; give the sample rate in Hz") from None
    if not np.isfinite(sr_f) or sr_f <= 0:
        raise ParameterError(f"sr={sr!r} must be a sample rate > 0 [Hz]")
    try:
        arr = np.asarray(y, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError("y must be a 1-D array of audio samples") from None
    if arr.ndim != 1:
        raise ParameterError(
            f"y must be mono (1-D), got shape {arr.shape}; mix down with y.mean(axis=0) "
            "(librosa layout) or y.mean(axis=1) (soundfile layout)"
        )
    if arr.size == 0:
        raise ParameterError("the audio is empty (zero samples): there are no beats to track")
    bad = ~np.isfinite(arr)
    if bad.any():
        raise ParameterError(
            f"the audio contains {int(bad.sum())} NaN or infinite sample(s) "
            f"(first at sample {int(np.argmax(bad))}); repair or trim the file"
        )
    if not allow_silent and not np.max(np.abs(arr)) >= SILENCE_PEAK:
        raise ParameterError(
            f"the audio is all silent (peak below {SILENCE_PEAK:g}): there are no beats to "
            "track (check the file and gain)"
        )
    return arr, sr_f


def check_duration(n_samples: int, sr: float, *, bpm: float | None = None) -> float:
    """Refuse audio too short to hold a pulse; return its duration [s].

    Rule: the audio must last at least :data:`MIN_DURATION_S` (1.5 s, two beat
    periods at 80 BPM) and, when the tempo is known (``bpm``), at least two beat
    periods of it (``2 * 60 / bpm`` s).

    Parameters
    ----------
    n_samples : int >= 0
    sr : float > 0 [Hz]
    bpm : float, optional [bpm]

    Raises
    ------
    ParameterError
        If the audio is shorter; the message gives its duration and the rule.
    """
    duration = float(frames_to_time(n_samples, fps=sr))
    need, why = MIN_DURATION_S, "the fixed minimum: two beat periods at 80 BPM"
    if bpm is not None and 2 * 60.0 / bpm > need:
        need, why = 2 * 60.0 / bpm, f"two beat periods at the given bpm={bpm:g}"
    if duration < need:
        raise ParameterError(
            f"the audio is only {duration:.3f} s long ({n_samples} samples at sr={sr:g} Hz): "
            f"beat tracking needs at least {need:.3g} s ({why}); give a longer excerpt "
            "(or check the sample rate)"
        )
    return duration


def beat_tempo(beats: Any) -> tuple[np.ndarray, np.ndarray]:
    """Instantaneous tempo of each beat interval: ``60 / (b[i+1] - b[i])``.

    Parameters
    ----------
    beats : np.ndarray [shape=(K,)] [s]
        Strictly increasing beat times.

    Returns
    -------
    starts : np.ndarray [shape=(K-1,)] [s]
        Start ``b[i]`` of each interval (plot as steps with ``where="post"``).
    bpm : np.ndarray [shape=(K-1,)] [bpm]
        Tempo of each interval (empty for fewer than two beats).

    Examples
    --------
    >>> beat_tempo([0.0, 0.5, 1.0, 1.75])[1]
    array([120., 120.,  80.])
    """
    beats = check_times(beats, name="beats")
    return beats[:-1].copy(), 60.0 / np.diff(beats)


def check_bpm(bpm: Any, *, name: str = "bpm") -> float:
    """Validate a tempo in BPM inside [MIN_SANE_BPM, MAX_SANE_BPM]."""
    try:
        value = float(bpm)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={bpm!r} is not a number [bpm]") from None
    if not np.isfinite(value) or not MIN_SANE_BPM <= value <= MAX_SANE_BPM:
        raise ParameterError(
            f"{name}={bpm!r} is outside the sane range {MIN_SANE_BPM:g}-{MAX_SANE_BPM:g} BPM "
            "(did you give a beat period in seconds, or beats per second?)"
        )
    return value


def _frontend(params: dict[str, Any], sr: float) -> dict[str, Any]:
    unknown = set(params) - set(FRONTEND_DEFAULTS)
    if unknown:
        raise ParameterError(
            f"unknown front-end parameter(s) {sorted(unknown)}; known: {sorted(FRONTEND_DEFAULTS)}"
        )
    p = {**FRONTEND_DEFAULTS, **params}
    if p["analysis_sr"] is not None:
        sr = min(
            sr, float(int(round(check_positive(p["analysis_sr"], name="analysis_sr", unit="Hz"))))
        )
    win = int(time_to_frames(check_positive(p["win_s"], name="win_s", unit="s"), fps=sr))
    hop = int(time_to_frames(check_positive(p["hop_s"], name="hop_s", unit="s"), fps=sr))
    if win < 16:
        raise ParameterError(f"win_s={p['win_s']!r} s is only {win} samples at sr={sr:g}")
    if hop < 1 or hop > win // 2:
        raise ParameterError(
            f"hop_s={p['hop_s']!r} s must be at most half the window win_s={p['win_s']!r} s "
            "(the phase-slope zero crossings would be missed)"
        )
    n_fft = p["n_fft"]
    n_fft = int(2 ** np.ceil(np.log2(win))) if n_fft is None else int(n_fft)
    if n_fft < win:
        raise ParameterError(f"n_fft={n_fft} must be >= the window length {win} samples")
    edges = np.asarray(p["band_edges_hz"], dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0) or edges[0] < 0:
        raise ParameterError(
            f"band_edges_hz={p['band_edges_hz']!r} must be increasing frequencies [Hz]"
        )
    flux_norm_s = float(p["flux_norm_s"])
    return {
        "sr": sr,
        "win": win,
        "hop": hop,
        "n_fft": n_fft,
        "edges": edges,
        "flux_norm_s": flux_norm_s,
    }


# --------------------------------------------------------------------------- front end


def phase_slope(
    y: np.ndarray,
    sr: float,
    *,
    win_s: float = FRONTEND_DEFAULTS["win_s"],
    hop_s: float = FRONTEND_DEFAULTS["hop_s"],
    n_fft: int | None = None,
    band_edges_hz=FRONTEND_DEFAULTS["band_edges_hz"],
) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Phase-slope function per band (energy-weighted average group delay).

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
    sr : float > 0 [Hz]
    win_s, hop_s : float > 0 [s]
    n_fft : int, optional [samples]
    band_edges_hz : sequence of float [Hz]

    Returns
    -------
    psf : np.ndarray [shape=(n_bands, n_frames)] [s]
        Frame centre time minus the band's energy centroid in time: negative before an
        impulse reaches the frame centre, positive after. NaN where the band is silent.
    energy : np.ndarray [shape=(n_bands, n_frames)]
        Band energy ``sum |X|^2``.
    fps : float [Hz]
    mag : np.ndarray [shape=(n_bins, n_frames)]
        STFT magnitude (for the spectral flux).
    """
    y, sr = check_audio(y, sr)
    fe = _frontend(
        {
            "win_s": win_s,
            "hop_s": hop_s,
            "n_fft": n_fft,
            "band_edges_hz": band_edges_hz,
            "analysis_sr": None,
        },
        sr,
    )
    return _phase_slope(y, sr, fe)


def _bin_bands(freqs: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Band index of each FFT bin (-1 outside the edges; the top edge is inclusive)."""
    band = np.searchsorted(edges, freqs, side="right") - 1
    band[freqs == edges[-1]] = edges.size - 2
    band[(freqs < edges[0]) | (freqs > edges[-1])] = -1
    return band


def _band_matrix(freqs: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Membership of each FFT bin in each band, shape (n_bands, n_bins), float32."""
    band = _bin_bands(freqs, edges)
    return (band[None, :] == np.arange(edges.size - 1)[:, None]).astype(np.float32)


def _phase_slope(y, sr, fe):
    win, hop, n_fft = fe["win"], fe["hop"], fe["n_fft"]
    w = scipy.signal.get_window("hann", win, fftbins=True)
    ramp = np.arange(win) - (win - 1) / 2.0  # time ramp centred on the frame centre
    # librosa centres a win-length window inside the n_fft frame; same for both STFTs
    y32 = y.astype(np.float32)
    X = librosa.stft(y32, n_fft=n_fft, hop_length=hop, win_length=win, window=w, center=True)
    Y = librosa.stft(y32, n_fft=n_fft, hop_length=hop, win_length=win, window=w * ramp, center=True)
    freqs = librosa.fft_frequencies(sr=sr, n_fft=n_fft)
    member = _band_matrix(freqs, fe["edges"])  # (n_bands, n_bins)
    power = X.real**2 + X.imag**2
    cross = X.real * Y.real + X.imag * Y.imag  # Re(X conj(Y))
    del Y
    # energy-weighted average over the band's bins: sums as one matrix product each
    energy = (member @ power).astype(np.float64)
    num = (member @ cross).astype(np.float64)
    floor = 1e-10 * max(float(energy.max()), 1e-30)
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = num / energy  # samples relative to the frame centre
    centroid[energy <= floor] = np.nan
    psf = -centroid / sr  # frame centre minus energy centroid [s]
    fps = sr / hop
    return psf, energy, fps, np.sqrt(power)


def onset_strength_psf(
    y: np.ndarray,
    sr: float,
    *,
    win_s: float = FRONTEND_DEFAULTS["win_s"],
    hop_s: float = FRONTEND_DEFAULTS["hop_s"],
    n_fft: int | None = FRONTEND_DEFAULTS["n_fft"],
    band_edges_hz=FRONTEND_DEFAULTS["band_edges_hz"],
    flux_norm_s: float = FRONTEND_DEFAULTS["flux_norm_s"],
    analysis_sr: float | None = FRONTEND_DEFAULTS["analysis_sr"],
) -> OnsetSignal:
    """Onset signal from positive zero crossings of the band phase-slope function.

    Every positive zero crossing of band ``c``'s phase slope is an onset candidate;
    its strength is the band's spectral flux (half-wave rectified log-magnitude
    difference, minus its local mean over ``flux_norm_s``) around the crossing
    (eq. 6-7). Bands are combined with weights ``6 - c``.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
        Mono audio.
    sr : float > 0 [Hz]
    win_s : float > 0 [s]
        Analysis window (default 23 ms).
    hop_s : float > 0 [s]
        Hop, at most ``win_s / 2`` (default 5.8 ms).
    n_fft : int, optional [samples]
    band_edges_hz : sequence of float [Hz]
        Band edges (default 0, 250, 1000, 4000, 22050: four bands).
    flux_norm_s : float >= 0 [s]
        Window of the local mean removed from the flux (0: none).
    analysis_sr : float > 0 [Hz] or None
        Audio at a higher rate is first resampled to this rate (polyphase), so that
        the front end behaves the same for 22.05, 44.1 and 48 kHz input and costs
        the same per second; None analyses at the input rate.

    Returns
    -------
    OnsetSignal

    Examples
    --------
    >>> from beatsync.synth.audio import click_track
    >>> y = click_track([0.5, 1.0, 1.5], sr=22050, duration=2.0)
    >>> ons = onset_strength_psf(y, 22050)
    >>> bool(abs(ons.onset_times[np.argmax(ons.onset_strengths)] - 0.5) < 0.01)
    True
    """
    y, sr = check_audio(y, sr)
    fe = _frontend(
        {
            "win_s": win_s,
            "hop_s": hop_s,
            "n_fft": n_fft,
            "band_edges_hz": band_edges_hz,
            "flux_norm_s": flux_norm_s,
            "analysis_sr": analysis_sr,
        },
        sr,
    )
    return _onsets(y, sr, fe)


def _resample(y: np.ndarray, sr: float, target: float) -> np.ndarray:
    """Polyphase resampling (scipy) from ``sr`` to ``target`` [Hz]."""
    a, b = int(round(target)), int(round(sr))
    g = np.gcd(a, b)
    return scipy.signal.resample_poly(y, a // g, b // g)


def _onsets(y: np.ndarray, sr: float, fe: dict[str, Any]) -> OnsetSignal:
    if fe["sr"] != sr:
        y, sr = _resample(y, sr, fe["sr"]), fe["sr"]
    y = y / np.max(np.abs(y))
    psf, energy, fps, mag = _phase_slope(y, sr, fe)
    n_bands, n_frames = psf.shape
    freqs = librosa.fft_frequencies(sr=sr, n_fft=fe["n_fft"])
    member = _band_matrix(freqs, fe["edges"])
    logmag = np.log1p(np.float32(100.0) * mag)
    diff = np.diff(logmag, axis=1, prepend=logmag[:, :1])
    np.maximum(diff, 0.0, out=diff)
    counts = np.maximum(member.sum(axis=1, keepdims=True), 1.0)
    flux = (member @ diff).astype(np.float64) / counts  # mean over the band's bins
    del diff, logmag
    # loudness-proportional onset signal: rectified increase of each band's energy
    # (band sums first, so the bin-to-bin beating of sustained low tones cancels)
    # smoothed over one window length first: the windowed energy of a low tone (an 808
    # kick's boom) oscillates from frame to frame with its phase
    span = max(int(round(fe["win"] / fe["hop"])), 2)
    smooth = scipy.ndimage.uniform_filter1d(energy, span, axis=1)
    d_energy = np.diff(smooth, axis=1, prepend=smooth[:, :1])
    energy_flux = np.sqrt(np.maximum(d_energy, 0.0).sum(axis=0))
    if fe["flux_norm_s"] > 0:  # remove the fluctuation floor of sustained sounds
        size = max(int(time_to_frames(fe["flux_norm_s"], fps=fps)), 3)
        energy_flux = np.maximum(
            energy_flux - scipy.ndimage.uniform_filter1d(energy_flux, size), 0.0
        )
    if fe["flux_norm_s"] > 0:
        size = max(int(time_to_frames(fe["flux_norm_s"], fps=fps)), 3)
        flux = np.maximum(flux - scipy.ndimage.uniform_filter1d(flux, size, axis=1), 0.0)
    # the flux peaks when the onset enters the window, up to half a window before the
    # phase-slope zero crossing: take its maximum over a window-long neighbourhood
    reach = int(np.ceil(fe["win"] / fe["hop"] / 2)) + 1
    flux = scipy.ndimage.maximum_filter1d(flux, 2 * reach + 1, axis=1, origin=reach // 2)
    weights = 6.0 - np.arange(1, n_bands + 1, dtype=np.float64)
    weights = np.maximum(weights, 1.0)
    weights = weights / weights.sum()
    bands = np.zeros((n_bands, n_frames))
    times_all, strength_all = [], []
    frame_t = frames_to_time(np.arange(n_frames), fps=fps)
    for c in range(n_bands):
        p = psf[c]
        a, b = p[:-1], p[1:]
        idx = np.flatnonzero((a < 0) & (b >= 0))  # NaN compares False: silent frames skipped
        if idx.size == 0:
            continue
        # sub-frame onset time by linear interpolation of the zero crossing
        frac = a[idx] / (a[idx] - b[idx])
        t_on = frame_t[idx] + frac / fps
        s = flux[c, idx]
        keep = s > 0
        idx, frac, t_on, s = idx[keep], frac[keep], t_on[keep], s[keep]
        np.add.at(bands[c], idx, s * (1 - frac))
        np.add.at(bands[c], np.minimum(idx + 1, n_frames - 1), s * frac)
        times_all.append(t_on)
        strength_all.append(weights[c] * s)
    envelope = weights @ bands
    if times_all:
        t = np.concatenate(times_all)
        s = np.concatenate(strength_all)
        order = np.argsort(t, kind="stable")
        t, s = t[order], s[order]
    else:
        t = s = np.empty(0)
    return OnsetSignal(envelope, bands, fps, t, s, weights, psf, energy_flux)


# --------------------------------------------------------------------------- tempo


def _windows(n_frames: int, fps: float, win_s: float, hop_s: float):
    """Start/stop frames and centre times of analysis windows covering the signal."""
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


def _period_grid(min_bpm: float, max_bpm: float, step: float = 0.005) -> np.ndarray:
    """Log-spaced beat periods [s] from 60/max_bpm to 60/min_bpm."""
    lo, hi = np.log(60.0 / max_bpm), np.log(60.0 / min_bpm)
    n = max(int(np.ceil((hi - lo) / step)) + 1, 2)
    return np.exp(np.linspace(lo, hi, n))


def _tempo_salience(
    env: np.ndarray, fps: float, starts, stops, periods: np.ndarray, n_harm: int
) -> np.ndarray:
    """Harmonic-sum autocorrelation salience, shape (n_periods, n_windows)."""
    n_win = len(starts)
    L = int(max(stops - starts))
    seg = np.zeros((n_win, L))
    for i, (a, b) in enumerate(zip(starts, stops, strict=True)):
        x = env[a:b]
        seg[i, : b - a] = x - x.mean()
    spec = np.fft.rfft(seg, n=2 * L, axis=1)
    acf = np.fft.irfft(np.abs(spec) ** 2, axis=1)[:, :L]
    # unbiased: divide by the overlap, so that all multiples of a period count alike
    overlap = np.maximum((stops - starts)[:, None] - np.arange(L)[None, :], 1)
    acf = acf / overlap
    acf[:, L // 2 :] = 0.0  # too few products to trust
    acf0 = acf[:, :1]
    acf = np.divide(acf, acf0, out=np.zeros_like(acf), where=acf0 > 0)
    sal = np.zeros((periods.size, n_win))
    step = float(np.log(periods[1] / periods[0])) if periods.size > 1 else 0.0
    for k in range(1, n_harm + 1):
        lags = k * periods * fps
        ok = lags < L // 2 - 1
        # tolerance of half a grid step around each multiple (peaks are narrow)
        width = 2 * int(np.ceil(0.5 * step * lags[ok].max())) + 1 if ok.any() else 1
        acf_k = scipy.ndimage.maximum_filter1d(acf, width, axis=1) if width > 1 else acf
        sal[ok] += acf_k[:, np.rint(lags[ok]).astype(np.int64)].T
    return sal


def _tempo_hmm(
    sal: np.ndarray,
    periods: np.ndarray,
    *,
    prior_period_s: float,
    prior_sigma: float,
    trans_sigma: float,
    p_jump: float,
    beta: float,
) -> np.ndarray:
    """Viterbi path (state index per window) of the tempo HMM."""
    logp = np.log(periods)
    prior = np.exp(-0.5 * ((logp - np.log(prior_period_s)) / prior_sigma) ** 2)
    scale = np.maximum(sal.max(axis=0, keepdims=True), 1e-9)
    obs = np.exp(beta * (sal / scale - 1.0)) * prior[:, None]
    d = logp[:, None] - logp[None, :]
    trans = np.exp(-0.5 * (d / trans_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    trans = (1 - p_jump) * trans + p_jump / periods.size
    return librosa.sequence.viterbi(obs, trans, p_init=prior / prior.sum())


# --------------------------------------------------------------------------- phase


def _phase_hmm(
    env: np.ndarray,
    fps: float,
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
    like = np.exp(beta * (obs / scale - 1.0))
    d = (q[:, None] - q[None, :] + 0.5) % 1.0 - 0.5
    trans = np.exp(-0.5 * (d / phase_sigma) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    path = librosa.sequence.viterbi(like, trans)
    return q[path]


def _snap(beats, periods_at_beats, onset_times, onset_strengths, reach: float, min_rel: float):
    """Move each beat to the best onset within ``reach`` beat periods.

    The best onset maximises strength times a Gaussian of its distance to the
    predicted beat (standard deviation ``reach / 2`` periods).
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


# --------------------------------------------------------------------------- API


def track_beats(
    y: np.ndarray,
    sr: float,
    *,
    method: str = "psf",
    bpm: float | None = None,
    min_bpm: float = 40.0,
    max_bpm: float = 240.0,
    prior_period_s: float = 0.55,
    prior_sigma: float = 1.0,
    tempo_win_s: float = 8.0,
    tempo_hop_s: float = 1.0,
    time_varying: bool = True,
    **frontend_params: Any,
) -> BeatTrack:
    """Track the beats of a piece of music.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
        Mono audio, finite, not all silent.
    sr : float > 0 [Hz]
    method : {"psf", "librosa"}
        ``"psf"``: phase-slope onsets + tempo/phase HMM (paper A, section 4);
        ``"librosa"``: :func:`librosa.beat.beat_track` (dynamic programming).
    bpm : float, optional [bpm]
        Known tempo: skips tempo estimation (the beat period is fixed).
    min_bpm, max_bpm : float [bpm]
        Tempo range searched (the metrical level is chosen inside it).
    prior_period_s : float > 0 [s]
        Centre of the log-normal prior on the beat period (0.55 s = 109 BPM).
    prior_sigma : float > 0
        Standard deviation of the prior in natural-log units of the period.
    tempo_win_s, tempo_hop_s : float > 0 [s]
        Autocorrelation windows of the tempo HMM (8 s, 1 s hop).
    time_varying : bool
        Follow tempo changes (True) or force one tempo for the whole piece (False).
    **frontend_params
        Phase-slope front end: ``win_s``, ``hop_s``, ``n_fft``, ``band_edges_hz``,
        ``flux_norm_s``, ``analysis_sr`` (see :func:`onset_strength_psf`).

    Returns
    -------
    BeatTrack

    Raises
    ------
    ParameterError
        Empty, silent or non-finite audio; audio too short for a pulse (shorter
        than 1.5 s, or than two beat periods of a given ``bpm``, see
        :func:`check_duration`); ``sr <= 0``;
        ``min_bpm >= max_bpm``; a ``bpm`` outside 20-400; unknown method or front-end
        parameter.

    Warns
    -----
    BeatsyncWarning
        If no onsets are found (e.g. a steady tone): returns no beats. If the pulse
        is unclear (e.g. noise, ``MIN_PULSE_CLARITY``): returns the beats found.

    Examples
    --------
    >>> from beatsync.synth.audio import beat_times, click_track
    >>> ref = beat_times(120, duration=10.0, start=0.3)
    >>> y = click_track(ref, sr=22050, duration=10.0)
    >>> bt = track_beats(y, 22050)
    >>> round(bt.tempo)
    120
    """
    y, sr = check_audio(y, sr)
    min_bpm, max_bpm = check_range(min_bpm, max_bpm, name="(min_bpm, max_bpm)", unit="bpm")
    check_bpm(min_bpm, name="min_bpm")
    check_bpm(max_bpm, name="max_bpm")
    if bpm is not None:
        bpm = check_bpm(bpm)
    check_duration(y.size, sr, bpm=bpm)
    if method == "librosa":
        if frontend_params:
            raise ParameterError(
                f"front-end parameters {sorted(frontend_params)} only apply to method='psf'"
            )
        return _track_librosa(y, sr, bpm=bpm, min_bpm=min_bpm, max_bpm=max_bpm)
    if method != "psf":
        raise ParameterError(f"method={method!r} is unknown; choose 'psf' or 'librosa'")
    prior_period_s = check_positive(prior_period_s, name="prior_period_s", unit="s")
    prior_sigma = check_positive(prior_sigma, name="prior_sigma", unit="log-period")
    tempo_win_s = check_positive(tempo_win_s, name="tempo_win_s", unit="s")
    tempo_hop_s = check_positive(tempo_hop_s, name="tempo_hop_s", unit="s")
    fe = _frontend(frontend_params, sr)
    if y.size / sr * fe["sr"] < 4 * fe["win"]:
        raise ParameterError(
            f"the audio is only {y.size / sr:.3f} s long ({y.size} samples at sr={sr:g}): "
            f"shorter than 4 analysis windows of {fe['win']} samples at {fe['sr']:g} Hz"
        )
    ons = _onsets(y, sr, fe)
    return _track_psf(
        ons,
        duration=y.size / sr,
        bpm=bpm,
        min_bpm=min_bpm,
        max_bpm=max_bpm,
        prior_period_s=prior_period_s,
        prior_sigma=prior_sigma,
        tempo_win_s=tempo_win_s,
        tempo_hop_s=tempo_hop_s,
        time_varying=time_varying,
    )


def _empty(method: str, msg: str) -> BeatTrack:
    warnings.warn(msg, BeatsyncWarning, stacklevel=3)
    e = np.empty(0)
    return BeatTrack(e, float("nan"), e, e, method)


def _window_energy(env: np.ndarray, fps: float, times: np.ndarray, reach_s: float = 0.03):
    """Sum of the onset signal within +-reach_s of each time."""
    cs = np.concatenate([[0.0], np.cumsum(env)])
    a = np.clip(time_to_frames(times - reach_s, fps=fps), 0, env.size)
    b = np.clip(time_to_frames(times + reach_s, fps=fps) + 1, 0, env.size)
    return cs[b] - cs[a]


def _uniformity(signals, fps: float, a: np.ndarray, b: np.ndarray) -> float:
    """How alike two pulse trains are in onset energy: min/max of their mean squared
    window energies, the larger over the given onset signals (0: one is silent, 1: equal).
    """
    best = 0.0
    for env in signals:
        ea = np.mean(_window_energy(env, fps, a) ** 2)
        eb = np.mean(_window_energy(env, fps, b) ** 2)
        if max(ea, eb) > 0:
            best = max(best, min(ea, eb) / max(ea, eb))
    return best


def _level_factor(signals, fps, beats, level_ratio: float, accent_ratio: float) -> float:
    """Factor on the beat period (1/2, 1/3, 2 or 1) deciding the metrical level.

    A pulse is the beat if its alternate pulses carry comparable onset energy
    (``signals``: the energy flux). The faster pulse (halves, thirds) is taken if its
    uniformity is at least ``level_ratio``; the slower one if the current beats
    alternate strong and very weak (uniformity below ``accent_ratio``).
    """
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


def _place_beats(ons, raw, fps, period_w, centres, t_frames, tempo_win_s, duration):
    """Phase HMM for a given tempo curve; returns beats [s] and the period at each beat."""
    n = raw.size
    # tempo per frame: step-wise between window centres (keeps abrupt changes abrupt)
    if centres.size > 1:
        mids = (centres[1:] + centres[:-1]) / 2
        period_f = period_w[np.searchsorted(mids, t_frames)]
    else:
        period_f = np.full(n, period_w[0])
    cycles = np.cumsum(1.0 / (period_f * fps))
    # phase: shorter windows than the tempo (4 beats) follow tempo changes quickly
    ph_win = float(np.clip(4.0 * np.median(period_w), 1.5, tempo_win_s))
    p_starts, p_stops, p_centres = _windows(n, fps, ph_win, 0.25)
    theta_w = _phase_hmm(
        raw,
        fps,
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
    pb = period_f[idx]
    beats = _snap(beats, pb, ons.onset_times, ons.onset_strengths, reach=0.12, min_rel=0.05)
    # trim beats outside the region with onset activity
    act = ons.onset_times[ons.onset_strengths >= 0.05 * ons.onset_strengths.max()]
    keep = (beats >= act[0] - 0.5 * pb) & (beats <= act[-1] + 0.5 * pb)
    keep &= (beats >= 0) & (beats <= duration)
    beats, pb = beats[keep], pb[keep]
    if beats.size > 1:  # strictly increasing, no two beats closer than half a period
        keep = np.concatenate([[True], np.diff(beats) > 0.5 * pb[1:]])
        beats, pb = beats[keep], pb[keep]
    return beats, pb


def _track_psf(
    ons: OnsetSignal,
    *,
    duration: float,
    bpm,
    min_bpm,
    max_bpm,
    prior_period_s,
    prior_sigma,
    tempo_win_s,
    tempo_hop_s,
    time_varying,
    power: float = 2.0,
    level_ratio: float = 0.15,
    accent_ratio: float = 0.15,
) -> BeatTrack:
    fps = ons.fps
    raw = ons.envelope
    n = raw.size
    if ons.onset_times.size == 0 or not np.any(raw > 0):
        return _empty("psf", "no onsets found in the audio (a steady sound?): no beats")
    env = scipy.ndimage.gaussian_filter1d(raw, sigma=max(0.01 * fps, 0.5))
    starts, stops, centres = _windows(n, fps, tempo_win_s, tempo_hop_s)
    if bpm is not None:
        period_w = np.full(centres.size, 60.0 / bpm)
    else:
        periods = _period_grid(min_bpm, max_bpm)
        sal = _tempo_salience(env**power, fps, starts, stops, periods, n_harm=4)
        clarity = float(np.median(sal.max(axis=0)))
        if clarity < MIN_PULSE_CLARITY:
            warnings.warn(
                f"no clear pulse in the audio (pulse clarity {clarity:.2f} < "
                f"{MIN_PULSE_CLARITY}): noise or free rhythm? the beats may be meaningless",
                BeatsyncWarning,
                stacklevel=3,
            )
        if not time_varying:
            sal = np.repeat(sal.sum(axis=1, keepdims=True), centres.size, axis=1)
        path = _tempo_hmm(
            sal,
            periods,
            prior_period_s=prior_period_s,
            prior_sigma=prior_sigma,
            trans_sigma=0.02,
            p_jump=1e-4,
            beta=8.0,
        )
        period_w = periods[path]
    t_frames = frames_to_time(np.arange(n), fps=fps)
    beats, pb = _place_beats(ons, raw, fps, period_w, centres, t_frames, tempo_win_s, duration)
    if bpm is None and beats.size > 2:
        # metrical level (octave errors), see _level_factor; decided per
        # constant-tempo segment, so each side of a tempo change gets its own level
        for _ in range(2):
            jumps = np.flatnonzero(np.abs(np.diff(np.log(period_w))) > 0.1) + 1
            bounds = np.concatenate([[0], jumps, [period_w.size]])
            new = period_w.copy()
            for a, b in zip(bounds[:-1], bounds[1:], strict=True):
                lo = centres[a] - tempo_hop_s / 2 if a > 0 else -np.inf
                hi = centres[b - 1] + tempo_hop_s / 2 if b < period_w.size else np.inf
                sel = beats[(beats >= lo) & (beats < hi)]
                if sel.size < 4:
                    continue
                factor = _level_factor((ons.energy_flux,), fps, sel, level_ratio, accent_ratio)
                tempo_new = 60.0 / np.median(period_w[a:b]) / factor
                if min_bpm <= tempo_new <= max_bpm:
                    new[a:b] = period_w[a:b] * factor
            if np.array_equal(new, period_w):
                break
            period_w = new
            beats, pb = _place_beats(
                ons, raw, fps, period_w, centres, t_frames, tempo_win_s, duration
            )
    tempo_curve = 60.0 / period_w
    if bpm is None and beats.size > 3:
        # refine the grid tempo (0.5 % steps) with the median beat interval per window
        ibi = np.diff(beats)
        mid = (beats[1:] + beats[:-1]) / 2
        reach = tempo_win_s / 2 if time_varying else np.inf  # one tempo: whole piece
        for i, c in enumerate(centres):
            sel = ibi[np.abs(mid - c) <= reach]
            if sel.size >= 3:
                est = 60.0 / np.median(sel)
                if abs(np.log(est / tempo_curve[i])) < 0.05:  # same metrical level
                    tempo_curve[i] = est
    return BeatTrack(
        beats.astype(np.float64),
        float(np.median(tempo_curve)),
        centres.astype(np.float64),
        tempo_curve,
        "psf",
    )


def _track_librosa(y, sr, *, bpm, min_bpm, max_bpm) -> BeatTrack:
    import scipy.stats

    hop = 512
    kwargs: dict[str, Any] = {}
    if bpm is not None:
        kwargs["bpm"] = bpm
    elif (min_bpm, max_bpm) != (40.0, 240.0):
        # a user-narrowed range: flat prior inside it (else librosa's log-normal prior)
        kwargs["prior"] = scipy.stats.uniform(min_bpm, max_bpm - min_bpm)
    tempo, beats = librosa.beat.beat_track(
        y=y.astype(np.float32), sr=sr, hop_length=hop, units="time", **kwargs
    )
    tempo = float(np.atleast_1d(tempo)[0])
    beats = np.unique(np.asarray(beats, dtype=np.float64))
    dur = y.size / sr
    return BeatTrack(beats, tempo, np.array([dur / 2]), np.array([tempo]), "librosa")
