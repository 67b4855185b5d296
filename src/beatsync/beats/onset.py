"""Phase-slope (group-delay) onsets: the tracker's front end (paper A, eqs. 6-8).

1. **Phase-slope function** (:func:`phase_slope`): per band, the average group delay
   without phase unwrapping, ``sum_k Re(X_k conj(Y_k)) / sum_k |X_k|^2`` over the band's
   bins, with ``X`` the STFT with window ``w`` and ``Y`` with ``n w(n)``. It crosses
   zero upwards when an impulse-like onset passes the frame centre, which locates the
   onset to a fraction of a frame.
2. **Onsets** (:func:`onset_strength_psf`): positive zero crossings of each band's phase
   slope, weighted by the band's locally normalised spectral flux (eqs. 6-7); bands
   combined with weights ``6 - c`` (c = 1..4, low bands count most).

:data:`FRONTEND_DEFAULTS` are not the paper's; known limit (a steady tone has onsets):
docs/tuning.md#front-end-phase-slope-onsets.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..audio_resampling import resample
from ..errors import ParameterError
from ..validation import (
    check_audio,
    check_positive,
    check_sample_rate,
    frames_to_time,
    time_to_frames,
)
from .filters import moving_max, moving_mean

__all__ = [
    "SILENCE_PEAK",
    "FRONTEND_DEFAULTS",
    "FrontEnd",
    "OnsetSignal",
    "frontend_settings",
    "phase_slope",
    "onset_strength_psf",
    "compute_onsets",
]

#: Audio whose peak magnitude is below this (re full scale 1.0, -140 dBFS) is silent.
SILENCE_PEAK = 1e-7

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
class FrontEnd:
    """Validated front-end settings in samples at the analysis rate ``analysis_sr`` [Hz]
    (the input rate, or lower after resampling); fields as :data:`FRONTEND_DEFAULTS`.
    """

    analysis_sr: float
    win_length: int
    hop_length: int
    n_fft: int
    band_edges_hz: tuple[float, ...]
    flux_norm_s: float

    @property
    def fps(self) -> float:
        """Frame rate of the onset signal [Hz]."""
        return self.analysis_sr / self.hop_length


def frontend_settings(params: dict[str, Any], sr: float) -> FrontEnd:
    """Validate front-end parameters (keys of :data:`FRONTEND_DEFAULTS`) for input rate ``sr``:
    a window of 16 samples or more, a hop of at most half of it, increasing band edges each
    holding an FFT bin at the analysis rate."""
    sr = check_sample_rate(sr)
    if not params:  # the defaults, cached on their values (they may have been changed)
        return _default_frontend(sr, tuple(FRONTEND_DEFAULTS.items()))
    return _frontend_settings(params, sr)


@functools.lru_cache(maxsize=16)
def _default_frontend(sr: float, defaults: tuple) -> FrontEnd:
    """The default front end at rate ``sr`` (cached)."""
    return _frontend_settings({}, sr)


def _frontend_settings(params: dict[str, Any], sr: float) -> FrontEnd:
    """:func:`frontend_settings`, uncached."""
    unknown = set(params) - set(FRONTEND_DEFAULTS)
    if unknown:
        raise ParameterError(
            f"unknown front-end parameter(s) {sorted(unknown)}; known: {sorted(FRONTEND_DEFAULTS)}"
        )
    p = {**FRONTEND_DEFAULTS, **params}
    if p["analysis_sr"] is not None:
        target = check_positive(p["analysis_sr"], name="analysis_sr", unit="Hz")
        sr = min(sr, float(int(round(target))))
    win = int(time_to_frames(check_positive(p["win_s"], name="win_s", unit="s"), fps=sr))
    hop = int(time_to_frames(check_positive(p["hop_s"], name="hop_s", unit="s"), fps=sr))
    if win < 16:
        raise ParameterError(f"win_s={p['win_s']!r} s is only {win} samples at sr={sr:g}")
    if hop < 1 or hop > win // 2:
        raise ParameterError(
            f"hop_s={p['hop_s']!r} s must be at most half the window win_s={p['win_s']!r} s "
            "(the phase-slope zero crossings would be missed)"
        )
    n_fft = int(2 ** np.ceil(np.log2(win))) if p["n_fft"] is None else int(p["n_fft"])
    if n_fft < win:
        raise ParameterError(f"n_fft={n_fft} must be >= the window length {win} samples")
    edges = np.asarray(p["band_edges_hz"], dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0) or edges[0] < 0:
        raise ParameterError(
            f"band_edges_hz={p['band_edges_hz']!r} must be increasing frequencies [Hz]"
        )
    band = _bin_bands(np.fft.rfftfreq(n_fft, d=1.0 / sr), edges)
    empty = np.flatnonzero(np.bincount(band[band >= 0], minlength=edges.size - 1) == 0)
    # the default top band (4-22 kHz) is empty below 8 kHz: only edges a user gave count
    given = tuple(edges.tolist()) != tuple(FRONTEND_DEFAULTS["band_edges_hz"])
    if empty.size and given:
        k = int(empty[0])
        why = (
            f"it lies above {sr / 2:g} Hz, the highest frequency at the analysis rate "
            f"{sr:g} Hz (edges meant for another sample rate?)"
            if edges[k] >= sr / 2
            else f"it is narrower than one FFT bin ({sr / n_fft:.3g} Hz)"
        )
        raise ParameterError(
            f"band_edges_hz={p['band_edges_hz']!r}: band {k + 1} ({edges[k]:g}-"
            f"{edges[k + 1]:g} Hz) holds no frequency of the analysis: {why}"
        )
    flux_norm_s = check_positive(p["flux_norm_s"], name="flux_norm_s", unit="s", allow_zero=True)
    return FrontEnd(sr, win, hop, n_fft, tuple(float(e) for e in edges), flux_norm_s)


@dataclass(frozen=True)
class OnsetSignal:
    """Output of :func:`onset_strength_psf`: ``envelope`` (n_frames,), band-weighted onset
    impulses at ``fps`` [Hz]; ``bands`` (n_bands, n_frames), unweighted; ``onset_times`` [s]
    (sub-frame) and ``onset_strengths`` (band-weighted) of every onset; ``band_weights``,
    ``6 - c`` summing to 1; ``psf`` (n_bands, n_frames) [s], the phase slope (NaN if silent).
    """

    envelope: np.ndarray
    bands: np.ndarray
    fps: float
    onset_times: np.ndarray
    onset_strengths: np.ndarray
    band_weights: np.ndarray
    psf: np.ndarray = field(repr=False)


def _hann(n: int) -> np.ndarray:
    """Periodic Hann window of ``n`` samples (the DFT-even form used for STFTs)."""
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


#: Frames per block of the front end (a block's spectra stay in cache).
BLOCK_FRAMES = 256


def _frames(y32: np.ndarray, n_fft: int, hop: int) -> np.ndarray:
    """Frames (n_frames, n_fft) of the zero-padded signal, frame ``m`` centred on ``m * hop``."""
    return np.lib.stride_tricks.sliding_window_view(np.pad(y32, n_fft // 2), n_fft)[::hop]


def _frame_window(window: np.ndarray, n_fft: int) -> np.ndarray:
    """The window centred inside the ``n_fft`` frame (float32)."""
    w = np.zeros(n_fft, dtype=np.float32)
    left = (n_fft - window.size) // 2
    w[left : left + window.size] = window
    return w


@functools.lru_cache(maxsize=8)
def _stft_terms(sr: float, fe: FrontEnd) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The two frame windows (Hann, and Hann times the time ramp) and the band membership
    matrix, cached per rate and settings.
    """
    win, n_fft = fe.win_length, fe.n_fft
    w = _hann(win)
    ramp = np.arange(win) - (win - 1) / 2.0  # time ramp centred on the frame centre
    terms = (_frame_window(w, n_fft), _frame_window(w * ramp, n_fft), _band_matrix(sr, fe))
    for arr in terms:
        arr.flags.writeable = False
    return terms


def _bin_bands(freqs: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Band index of each FFT bin (-1 outside the edges; the top edge is inclusive)."""
    band = np.searchsorted(edges, freqs, side="right") - 1
    band[freqs == edges[-1]] = edges.size - 2
    band[(freqs < edges[0]) | (freqs > edges[-1])] = -1
    return band


def _band_matrix(sr: float, fe: FrontEnd) -> np.ndarray:
    """Membership of each FFT bin in each band, shape (n_bins, n_bands), float32."""
    freqs = np.fft.rfftfreq(fe.n_fft, d=1.0 / sr)
    edges = np.asarray(fe.band_edges_hz)
    band = _bin_bands(freqs, edges)
    return (band[:, None] == np.arange(edges.size - 1)[None, :]).astype(np.float32)


def _phase_slope(y: np.ndarray, sr: float, fe: FrontEnd, *, keep_mag: bool = True):
    """``(psf, energy, fps, mag, flux)``: :func:`phase_slope`'s and the band's spectral
    ``flux`` (mean half-wave rectified log-magnitude difference), in blocks of frames.
    """
    import scipy.fft  # noqa: PLC0415 (batched real FFTs, much faster than numpy's here)

    hop, n_fft = fe.hop_length, fe.n_fft
    frames = _frames(np.asarray(y, dtype=np.float32), n_fft, hop)
    w_x, w_y, member = _stft_terms(float(sr), fe)
    n_frames, n_bands = frames.shape[0], member.shape[1]
    energy = np.empty((n_frames, n_bands), dtype=np.float32)
    num = np.empty((n_frames, n_bands), dtype=np.float32)
    flux = np.empty((n_frames, n_bands), dtype=np.float32)
    mag = np.empty((n_frames, member.shape[0]), dtype=np.float32) if keep_mag else None
    prev = None
    for a in range(0, n_frames, BLOCK_FRAMES):
        b = min(a + BLOCK_FRAMES, n_frames)
        X = scipy.fft.rfft(frames[a:b] * w_x, axis=1)
        Y = scipy.fft.rfft(frames[a:b] * w_y, axis=1)
        power = X.real**2 + X.imag**2
        cross = X.real * Y.real + X.imag * Y.imag  # Re(X conj(Y))
        # energy-weighted average over the band's bins: sums as one matrix product each
        energy[a:b] = power @ member
        num[a:b] = cross @ member
        m = np.sqrt(power)
        if mag is not None:
            mag[a:b] = m
        # log(1 + 100 m) by np.log in float32 (vectorised, unlike log1p)
        logmag = np.float32(100.0) * m
        logmag += np.float32(1.0)
        np.log(logmag, out=logmag)
        diff = np.diff(logmag, axis=0, prepend=logmag[:1] if prev is None else prev)
        np.maximum(diff, 0.0, out=diff)
        flux[a:b] = diff @ member
        prev = logmag[-1:]
    energy_t = energy.T.astype(np.float64)
    floor = 1e-10 * max(float(energy_t.max()), 1e-30)
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = num.T.astype(np.float64) / energy_t  # samples relative to the frame centre
    centroid[energy_t <= floor] = np.nan
    psf = -centroid / sr  # frame centre minus energy centroid [s]
    counts = np.maximum(member.sum(axis=0)[:, None], 1.0)
    return psf, energy_t, sr / hop, mag, flux.T.astype(np.float64) / counts


def phase_slope(
    y: np.ndarray,
    sr: float,
    *,
    win_s: float = FRONTEND_DEFAULTS["win_s"],
    hop_s: float = FRONTEND_DEFAULTS["hop_s"],
    n_fft: int | None = None,
    band_edges_hz=FRONTEND_DEFAULTS["band_edges_hz"],
) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Phase-slope function per band ``psf`` (n_bands, n_frames) [s], frame centre minus the
    band's energy centroid (NaN where silent); with ``energy`` ``sum |X|^2``, ``fps`` and the
    STFT magnitude ``mag`` (n_bins, n_frames)."""
    given = {"win_s": win_s, "hop_s": hop_s, "n_fft": n_fft, "band_edges_hz": band_edges_hz}
    y, sr, fe = _validated(y, sr, {**given, "analysis_sr": None})
    psf, energy, fps, mag, _ = _phase_slope(y, sr, fe)
    return psf, energy, fps, mag.T


def onset_strength_psf(y: np.ndarray, sr: float, **params: Any) -> OnsetSignal:
    """Onset signal from positive zero crossings of the band phase-slope function.

    Each crossing in band ``c`` is weighted by the band's spectral flux around it
    (half-wave rectified log-magnitude difference minus its local mean over
    ``flux_norm_s`` [s]; eqs. 6-7); bands combined with weights ``6 - c``. ``params``: the
    front end's settings (:data:`FRONTEND_DEFAULTS`); audio above ``analysis_sr`` [Hz] is
    first resampled to it (soxr), so that 22.05, 44.1 and 48 kHz input behave alike.

    Examples
    --------
    >>> from beatsync.synth.audio import click_track
    >>> y = click_track([0.5, 1.0, 1.5], sr=22050, duration=2.0)
    >>> ons = onset_strength_psf(y, 22050)
    >>> bool(abs(ons.onset_times[np.argmax(ons.onset_strengths)] - 0.5) < 0.01)
    True
    """
    return compute_onsets(*_validated(y, sr, params))


def _validated(y, sr, params: dict[str, Any]) -> tuple[np.ndarray, float, FrontEnd]:
    y, sr = check_audio(y, sr, silence_peak=SILENCE_PEAK)
    return np.asarray(y, dtype=np.float64), sr, frontend_settings(params, sr)


def compute_onsets(y: np.ndarray, sr: float, fe: FrontEnd) -> OnsetSignal:
    """:func:`onset_strength_psf` on validated input (``y`` finite mono, not silent)."""
    if fe.analysis_sr != sr:
        # soxr, keeping round(n * ratio) samples (float32; a very loud signal comes back
        # lowered by a power of two, which the normalisation below removes)
        n_out = int(round(y.size * fe.analysis_sr / sr))
        y = resample(y, sr, fe.analysis_sr, n_out, keep_level=False)
        sr = fe.analysis_sr
    # float32 divided in float32: the same as in float64 rounded to float32 (double
    # rounding is innocuous for a division), without the float64 copies
    y = y / np.max(np.abs(y))
    psf, _, fps, _, flux = _phase_slope(y, sr, fe, keep_mag=False)
    n_bands, n_frames = psf.shape
    if fe.flux_norm_s > 0:  # remove the fluctuation floor of sustained sounds
        size = max(int(time_to_frames(fe.flux_norm_s, fps=fps)), 3)
        flux = np.maximum(flux - moving_mean(flux, size), 0.0)
    # the flux peaks when the onset enters the window, up to half a window before the
    # phase-slope zero crossing: take its maximum over a window-long neighbourhood
    reach = int(np.ceil(fe.win_length / fe.hop_length / 2)) + 1
    flux = moving_max(flux, 2 * reach + 1, origin=reach // 2)
    weights = np.maximum(6.0 - np.arange(1, n_bands + 1, dtype=np.float64), 1.0)
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
    return OnsetSignal(envelope, bands, fps, t, s, weights, psf)
