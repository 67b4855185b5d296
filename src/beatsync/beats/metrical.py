"""The metrical model: tatum, tactus (beat) and measure periods estimated jointly.

Klapuri, Eronen & Astola (2006), "Analysis of the meter of acoustic musical signals",
IEEE Trans. Audio, Speech and Language Processing 14(1), 342-355, on our phase-slope
onsets (its four bands play the paper's four accent bands):

1. **Comb-filter resonators** (:func:`resonator_salience`): delay ``tau``, feedback
   ``alpha = 0.5 ** (tau / T0)`` (half-time ``T0`` = 3 s). The output over the input
   energy, normalised by the response to white noise ``gamma = (1 - alpha)**2 / (1 -
   alpha**2)``, ``r = (E_out / E_in - gamma) / (1 - gamma)`` (0: no periodicity, 1: all
   of it periodic), summed over the bands is the salience ``s(tau)``. We take the
   steady-state energy per 8-s window from the spectrum (Parseval, ``|H_tau(w)|^2 = (1 -
   alpha)^2 / (1 - 2 alpha cos(w tau) + alpha^2)``), so delays may be fractional.
2. **Probabilistic model** (:func:`tactus_observation`): log-normal priors on the
   tatum, tactus and measure periods and a ratio model ``g(x) = sum_l w_l N(x; l, 0.3)``
   for tactus/tatum and measure/tactus. The score of ``(tatum, tactus, measure)`` is
   the sum of the observations ``beta * s(tau)``, the log priors and the log ratio
   terms; tatum and measure are maximised out per window, and the tempo HMM
   (:mod:`beatsync.beats.tempo`) decodes the tactus observation left.
3. **Meter** (:func:`estimate_meter`): beats per bar.

Tuning (:data:`METER_MODEL`) and known limits: docs/tuning.md#metrical-model.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "MeterModel",
    "METER_MODEL",
    "resonator_salience",
    "resonator_saliences",
    "tactus_observation",
    "estimate_meter",
    "ratio_weight",
    "beat_observation",
]


@dataclass(frozen=True)
class MeterModel:
    """Constants of the metrical model (Klapuri et al. 2006, section IV): ``half_time_s``
    [s] is ``T0``; ``*_median_s`` [s] and ``*_sigma`` [natural-log units] are the period
    priors'; ``ratio_weights`` the ``w_l`` (l = 1..9) of measure / tactus, and
    ``tatum_ratio_weights`` of tactus / tatum (``w_3 = 0.5``: a "beat" of three sixteenths
    must not beat a waltz's own beat, docs/tuning.md#tatum-ratio-weight).
    """

    half_time_s: float = 3.0
    tatum_median_s: float = 0.18
    tactus_median_s: float = 0.55
    measure_median_s: float = 2.1
    tatum_sigma: float = 0.4
    tactus_sigma: float = 0.3
    measure_sigma: float = 0.3
    ratio_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 0.1, 0.5, 0.1, 0.5, 0.1)
    tatum_ratio_weights: tuple[float, ...] = (1.0, 1.0, 0.5, 1.0, 0.1, 0.5, 0.1, 0.5, 0.1)
    ratio_sigma: float = 0.3
    beta: float = 10.0
    min_tatum_s: float = 0.08
    max_measure_s: float = 4.0

    def __post_init__(self) -> None:  # tuples: the model keys the cache of its terms
        for name in ("ratio_weights", "tatum_ratio_weights"):
            object.__setattr__(self, name, tuple(float(w) for w in getattr(self, name)))


#: Fewest cycles of a beat period inside an analysis window for its salience to count.
MIN_BEAT_CYCLES = 4

#: The model used by :func:`beatsync.beats.track_beats`.
METER_MODEL = MeterModel()


def resonator_salience(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    half_time_s: float,
    max_hz: float | None = None,
) -> np.ndarray:
    """Normalised comb-filter resonator energy summed over bands, (n_periods, n_windows).

    ``bands`` (n_bands, n_frames) are accent signals, or (n_sets, n_bands, n_frames) (the
    result gets a last axis of n_sets); ``periods`` [s] need not be whole frames. Above
    ``max_hz`` [Hz] every resonator passes its mean gain ``gamma`` unfiltered (saves time).
    The energy is taken in the lag domain (:func:`_resonator_lag_weights`).
    """
    return resonator_saliences(bands, fps, starts, stops, [periods], half_time_s, max_hz)[0]


def resonator_saliences(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    period_blocks: Sequence[np.ndarray],
    half_time_s: float,
    max_hz: float | None = None,
) -> list[np.ndarray]:
    """:func:`resonator_salience` for several period grids (tactus, tatum and measure): the
    windows' autocorrelations are computed once, each grid's lag weights cached on their own.
    """
    import scipy.fft  # noqa: PLC0415 (batched real FFTs)

    bands = np.asarray(bands, dtype=np.float64)
    sets = bands.ndim == 3
    if not sets:
        bands = bands[None]
    n_sets, n_bands = bands.shape[:2]
    length = int(max(b - a for a, b in zip(starts, stops, strict=True)))
    n_fft = resonator_fft_size(length, fps, half_time_s)
    n_bins = n_fft // 2 + 1
    if max_hz is not None:
        n_bins = min(n_bins, int(np.ceil(max_hz / fps * n_fft)) + 1)
    # cached for lags up to the next multiple of LAG_BUCKET: clips under it share them
    n_lags = min(n_fft, -(-length // LAG_BUCKET) * LAG_BUCKET)
    weights = []
    for periods in period_blocks:
        key = np.ascontiguousarray(periods, dtype=np.float64).tobytes()
        lag_w, gamma = _resonator_lag_weights(key, fps, n_fft, n_bins, half_time_s, n_lags)
        weights.append((lag_w[:, :length], gamma))
    # the lag weights of the window's total energy (every gain 1)
    total_w = _bin_cosine_sums(n_fft, length) * _lag_multiplicity(length)
    n_acf = scipy.fft.next_fast_len(2 * length - 1, real=True)  # linear, not circular
    n_win = len(starts)
    total = np.empty((n_win, n_sets * n_bands))
    energies = [np.empty((w[0].shape[0], n_win, n_sets * n_bands)) for w in weights]
    # windows in chunks: a whole song's at once would hold about 600 padded copies
    for c0 in range(0, n_win, WINDOW_CHUNK):
        chunk = list(
            zip(starts[c0 : c0 + WINDOW_CHUNK], stops[c0 : c0 + WINDOW_CHUNK], strict=True)
        )
        seg = np.zeros((len(chunk), n_sets, n_bands, n_acf))
        for i, (a, b) in enumerate(chunk):
            x = bands[:, :, a:b]
            seg[i, :, :, : b - a] = (x - x.mean(axis=2, keepdims=True)) * _hanning(b - a)
        spec = scipy.fft.rfft(seg, axis=3)
        acf = scipy.fft.irfft(spec.real**2 + spec.imag**2, n=n_acf, axis=3)[..., :length]
        acf = acf.reshape(-1, length).T  # (lag, window x set x band)
        # each column over its lag-0 value: the same ratios, and a float32 product safe
        # at any input scale
        lag0 = acf[0]
        acf = acf / np.where(lag0 > 0, lag0, 1.0)
        total[c0 : c0 + len(chunk)] = (total_w @ acf).reshape(len(chunk), -1)
        acf = acf.astype(np.float32)
        for (lag_w, _), energy in zip(weights, energies, strict=True):
            energy[:, c0 : c0 + len(chunk)] = (lag_w @ acf).reshape(lag_w.shape[0], len(chunk), -1)
    span = (np.asarray(stops) - np.asarray(starts)) / fps
    out = []
    for periods, (_, gamma), energy in zip(period_blocks, weights, energies, strict=True):
        ratio = np.divide(energy, total[None], out=np.zeros_like(energy), where=total[None] > 0)
        r = (ratio - gamma[:, None, None]) / (1 - gamma[:, None, None])
        # fewer than two periods inside the window: no evidence either way
        r[np.asarray(periods)[:, None] > span[None, :] / 2] = 0.0
        r = r.reshape(r.shape[0], n_win, n_sets, n_bands).sum(axis=3)
        out.append(r if sets else r[:, :, 0])
    return out


#: Analysis windows whose autocorrelations :func:`resonator_salience` holds at once.
WINDOW_CHUNK = 32

#: FFT bins per resonator pass band (see :func:`resonator_fft_size`).
BINS_PER_PASS_BAND = 3


def resonator_fft_size(length: int, fps: float, half_time_s: float) -> int:
    """FFT length of the resonators' windows: :data:`BINS_PER_PASS_BAND` bins at least in
    each pass band, ``ln 2 / (pi T0)`` wide [Hz]
    (docs/tuning.md#spectral-sampling-of-the-resonators)."""
    pass_band = np.log(2.0) / (np.pi * half_time_s)  # [Hz]
    need = max(length, 2, int(np.ceil(BINS_PER_PASS_BAND * fps / pass_band)))
    return int(2 ** np.ceil(np.log2(need)))


@functools.lru_cache(maxsize=12)
def _resonator_lag_weights(
    periods_key: bytes, fps: float, n_fft: int, n_bins: int, half_time_s: float, n_lags: int
) -> tuple[np.ndarray, np.ndarray]:
    """``(lag_w, gamma)``, cached per period grid and number of lags.

    ``lag_w[i, k] = m_k sum_{b=0}^{n_fft/2} G_i(b) cos(2 pi b k / n_fft)`` with
    ``G_i = |H_tau_i|^2`` below ``n_bins`` (``gamma`` above) and ``m_k`` 1 at lag 0, else 2, so
    that ``lag_w @ a`` is the resonators' energy for a window's autocorrelation ``a``. The
    sums over bins are an inverse real FFT, :data:`LAG_WEIGHT_ROWS` periods at a time;
    stored in float32.
    """
    import scipy.fft  # noqa: PLC0415

    periods = np.frombuffer(periods_key, dtype=np.float64)
    omega = 2.0 * np.pi * np.arange(n_bins) / n_fft  # [rad / frame]
    alpha = 0.5 ** (periods / half_time_s)
    gamma = (1 - alpha) ** 2 / (1 - alpha**2)
    half = n_fft // 2
    sign = np.where(np.arange(n_lags) % 2 == 0, 1.0, -1.0)
    ones = _bin_cosine_sums(n_fft, n_lags)  # the sums for G = 1
    mult = _lag_multiplicity(n_lags)
    lag_w = np.empty((periods.size, n_lags))
    excess = np.zeros((LAG_WEIGHT_ROWS, half + 1))
    for r0 in range(0, periods.size, LAG_WEIGHT_ROWS):
        rows = slice(r0, min(r0 + LAG_WEIGHT_ROWS, periods.size))
        a, g = alpha[rows, None], gamma[rows, None]
        m = a.shape[0]
        # G - gamma on the bins below n_bins (zero above); its cosine sums by irfft:
        # irfft(X)[k] = (X[0] + 2 sum_{0<b<n/2} X[b] cos(2 pi b k / n) + X[n/2] (-1)^k) / n
        excess[:m, :n_bins] = (1 - a) ** 2 / (
            1 - 2 * a * np.cos(np.outer(periods[rows] * fps, omega)) + a**2
        ) - g
        c = n_fft * scipy.fft.irfft(excess[:m], n=n_fft, axis=1)[:, :n_lags]
        c += excess[:m, :1] + excess[:m, half : half + 1] * sign[None, :]
        lag_w[rows] = (c / 2 + g * ones[None, :]) * mult[None, :]
    lag_w = lag_w.astype(np.float32)
    for arr in (lag_w, gamma):
        arr.flags.writeable = False
    return lag_w, gamma


#: Periods whose lag weights :func:`_resonator_lag_weights` computes at once.
LAG_WEIGHT_ROWS = 32

#: Lags are cached in multiples of this (0-8 s windows at 172 frames/s: three sizes).
LAG_BUCKET = 512


def _lag_multiplicity(n_lags: int) -> np.ndarray:
    """``m_k``: lag 0 counts once, every other lag twice (``k`` and ``-k``)."""
    return np.where(np.arange(n_lags) == 0, 1.0, 2.0)


def _bin_cosine_sums(n_fft: int, n_lags: int) -> np.ndarray:
    """``sum_{b=0}^{n_fft/2} cos(2 pi b k / n_fft)`` for lags ``k < n_lags <= n_fft``:
    ``n_fft/2 + 1`` at lag 0, else 1 at even and 0 at odd lags.
    """
    k = np.arange(n_lags)
    return np.where(k == 0, n_fft // 2 + 1.0, np.where(k % 2 == 0, 1.0, 0.0))


def _log_prior(periods: np.ndarray, median: float, sigma: float) -> np.ndarray:
    """Log-normal prior per state of a log-spaced grid (no 1/tau Jacobian)."""
    return -0.5 * (np.log(periods / median) / sigma) ** 2


def ratio_weight(
    x: np.ndarray, model: MeterModel = METER_MODEL, *, tatum: bool = False
) -> np.ndarray:
    """The ratio model ``g(x) = sum_l w_l N(x; l, sigma)`` (unnormalised Gaussians) of
    measure / tactus, or with ``tatum=True`` of tactus / tatum.
    """
    x = np.asarray(x, dtype=np.float64)
    out = np.zeros_like(x)
    weights = model.tatum_ratio_weights if tatum else model.ratio_weights
    for ratio, w in enumerate(weights, start=1):
        out += w * np.exp(-0.5 * ((x - ratio) / model.ratio_sigma) ** 2)
    return out


@functools.lru_cache(maxsize=8)
def _hanning(n: int) -> np.ndarray:
    """``np.hanning(n)``, cached (the tempo windows of a song share their length)."""
    w = np.hanning(n)
    w.flags.writeable = False
    return w


def _level_grid(lo: float, hi: float, step: float = 0.01) -> np.ndarray:
    n = max(int(np.ceil(np.log(hi / lo) / step)) + 1, 2)
    return np.exp(np.linspace(np.log(lo), np.log(hi), n))


def _log_conditional(
    log_g: np.ndarray, levels: np.ndarray, median: float, sigma: float
) -> np.ndarray:
    """``log P(level | tactus)``: ratio model times the level's prior, normalised per tactus."""
    joint = log_g + _log_prior(levels, median, sigma)[None, :]
    finite = np.where(np.isfinite(joint), joint, -np.inf)
    top = finite.max(axis=1, keepdims=True)
    log_z = top + np.log(np.exp(finite - top).sum(axis=1, keepdims=True))
    return log_g - log_z


@functools.lru_cache(maxsize=8)
def _level_terms(periods_key: bytes, model: MeterModel):
    """Tatum and measure grids and ``log P(level | tactus)`` for a tactus grid (cached):
    ``(tatum, measure, g_a, g_c)``, ``g_a[i, j]`` for tatum ``j <=`` tactus ``i`` and
    ``g_c[i, k]`` for measure ``k >=`` tactus ``i`` (float32).
    """
    periods = np.frombuffer(periods_key, dtype=np.float64)
    tatum = _level_grid(model.min_tatum_s, float(periods.max()))
    measure = _level_grid(float(periods.min()), model.max_measure_s)
    with np.errstate(divide="ignore"):
        g_a = np.log(ratio_weight(periods[:, None] / tatum[None, :], model, tatum=True))
        g_c = np.log(ratio_weight(measure[None, :] / periods[:, None], model))
    g_a[tatum[None, :] > periods[:, None] * 1.0001] = -np.inf
    g_c[measure[None, :] < periods[:, None] * 0.9999] = -np.inf
    g_a = _log_conditional(g_a, tatum, model.tatum_median_s, model.tatum_sigma)
    g_c = _log_conditional(g_c, measure, model.measure_median_s, model.measure_sigma)
    g_a, g_c = g_a.astype(np.float32), g_c.astype(np.float32)
    for arr in (tatum, measure, g_a, g_c):
        arr.flags.writeable = False
    return tatum, measure, g_a, g_c


def _tactus_terms(
    s_b: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel,
) -> np.ndarray:
    """``beta s(tB) + log p(tB)``; zeroes (in place) the salience of a period with fewer than
    :data:`MIN_BEAT_CYCLES` cycles in the window.
    """
    span = (np.asarray(stops) - np.asarray(starts)) / fps
    s_b[periods[:, None] > span[None, :] / MIN_BEAT_CYCLES] = 0.0
    prior = _log_prior(periods, model.tactus_median_s, model.tactus_sigma)
    return model.beta * s_b + prior.reshape((-1,) + (1,) * (s_b.ndim - 1))


def tactus_observation(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel = METER_MODEL,
    max_hz: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Log observation of each tactus period per window, tatum and measure maximised out.

    The score of ``tB`` is ``beta s(tB) + log p(tB)`` plus
    ``max_tA [beta s(tA) + log p(tA) + log g(tB / tA) - log Z_A(tB)]`` and the same for
    the measure with ``g(tC / tB)``; ``Z`` normalises ``P(tA | tB)`` (and ``P(tC | tB)``)
    over tatum <= tactus <= measure. Returns ``(log_obs, salience, measure)``, each
    (n_periods, n_windows): the observation, the salience ``s`` at the tactus periods and
    the best measure period [s].
    """
    tatum, measure, g_a, g_c = _level_terms(
        np.ascontiguousarray(periods, dtype=np.float64).tobytes(), model
    )
    s_b, s_a, s_c = resonator_saliences(
        bands, fps, starts, stops, [periods, tatum, measure], model.half_time_s, max_hz
    )
    log_b = _tactus_terms(s_b, fps, starts, stops, periods, model)
    # the maximisation over tatum and measure in float32 (faster; rounding about 1e-5)
    obs_a = model.beta * s_a + _log_prior(tatum, model.tatum_median_s, model.tatum_sigma)[:, None]
    obs_c = (
        model.beta * s_c + _log_prior(measure, model.measure_median_s, model.measure_sigma)[:, None]
    )
    obs_a, obs_c = obs_a.astype(np.float32), obs_c.astype(np.float32)
    n_win = s_b.shape[1]
    rows = np.arange(periods.size)
    best = np.empty((periods.size, n_win))
    best_measure = np.empty((periods.size, n_win))
    for w in range(n_win):
        ta = g_a + obs_a[None, :, w]
        tc = g_c + obs_c[None, :, w]
        ic = np.argmax(tc, axis=1)
        best[:, w] = ta.max(axis=1) + tc[rows, ic]
        best_measure[:, w] = measure[ic]
    return log_b + best, s_b, best_measure


def beat_observation(
    bands: np.ndarray,
    fps: float,
    starts: Sequence[int],
    stops: Sequence[int],
    periods: np.ndarray,
    model: MeterModel = METER_MODEL,
    max_hz: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The tactus terms alone, ``beta s(tB) + log p(tB)`` and ``s(tB)`` (for the pulse-clarity
    null); sets of bands as in :func:`resonator_salience`.
    """
    s_b = resonator_salience(bands, fps, starts, stops, periods, model.half_time_s, max_hz)
    return _tactus_terms(s_b, fps, starts, stops, periods, model), s_b


def estimate_meter(measure_at_tactus: np.ndarray, tactus: np.ndarray) -> int:
    """Beats per bar: the most frequent whole ratio of measure to tactus period."""
    ratios = np.rint(measure_at_tactus / tactus).astype(np.int64)
    ratios = ratios[(ratios >= 1) & (ratios <= 9)]
    if ratios.size == 0:
        return 0
    return int(np.bincount(ratios).argmax())
