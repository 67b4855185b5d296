"""Period estimation and the periodicity test of the segmentation (frames, channels first).

The public entry turns the period range [s] into the frame band of
:func:`estimation_band` and checks it; :func:`estimate_period` trusts it.
"""

from __future__ import annotations

import numpy as np

from .costs import pair_costs

__all__ = [
    "MAX_NORMALISED_ENERGY",
    "MIN_PERIODICITY_CONTRAST",
    "OFF_PERIOD_FACTORS",
    "PERIOD_METHODS",
    "TIER_FACTOR",
    "period_tiers",
    "estimation_band",
    "uniform_frames",
    "uniform_energy",
    "estimate_period",
    "periodicity_contrast",
]

MAX_NORMALISED_ENERGY = 1.0
"""Not periodic if E / (channels * (periods - 1)) (mean Pearson distance) reaches this."""

MIN_PERIODICITY_CONTRAST = 0.05
"""Not periodic if the optimum beats off-period uniform segmentations by less than this."""

OFF_PERIOD_FACTORS = (0.5, 0.75, 1.25, 1.5)
"""Wrong periods, as multiples of the found one, that :func:`periodicity_contrast` tries."""

PERIOD_METHODS = ("energy", "fft", "given")
"""How the period count is obtained (``"given"``: from the caller's ``n_periods``)."""

TIER_FACTOR = 5.0
"""Ratio of the longest to the shortest period of one search tier (the paper's 0.25-1.25 s)."""

_MAX_COUNT_CANDIDATES = 400  # candidate periods of the "energy" method (then log-spaced)


def period_tiers(lo: float, hi: float) -> list[tuple[float, float]]:
    """Consecutive tiers ``(lo, 5 lo), (5 lo, 25 lo), ..., (.., hi)`` of a period range (any unit).

    Searched shortest first, so that a motion periodic at a step is not described by a
    multiple of it, while one that repeats only over a longer figure is found later.
    """
    tiers = []
    a = float(lo)
    while True:
        b = a * TIER_FACTOR
        if b >= hi * (1 - 1e-9):
            tiers.append((a, float(hi)))
            return tiers
        tiers.append((a, b))
        a = b


def estimation_band(n: int, lo_frames: float, hi_frames: float) -> tuple[float, float]:
    """Candidate periods [frames], ``max(lo, 2) .. min(hi, (n - 1) / 2)``: two periods must fit."""
    return max(float(lo_frames), 2.0), min(float(hi_frames), (n - 1) / 2.0)


def uniform_frames(n: int, period: float) -> np.ndarray:
    """Uniform boundaries 0, L, 2L, ... (rounded) that fit in frames 0..n-1."""
    count = int(np.floor((n - 1) / period + 1e-9))
    return np.rint(np.arange(count + 1) * period).astype(np.int64)


def uniform_energy(x: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Mean Pearson distance per channel and pair of uniform segmentations (NaN if < 2)."""
    n_ch, n = x.shape
    fs = [uniform_frames(n, float(per)) for per in periods]
    use = [i for i, f in enumerate(fs) if f.size >= 3 and np.all(np.diff(f) >= 1)]
    out = np.full(len(periods), np.nan)
    if not use:
        return out
    own = np.concatenate([np.full(fs[i].size - 2, i) for i in use])
    a, b, c = (np.concatenate([fs[i][k : fs[i].size - 2 + k] for i in use]) for k in range(3))
    costs = pair_costs(x, a, b, c)
    tot = np.bincount(own, weights=costs, minlength=len(periods))
    cnt = np.bincount(own, minlength=len(periods))
    ok = cnt > 0
    out[ok] = tot[ok] / (cnt[ok] * n_ch)
    return out


def estimate_period(x: np.ndarray, lo_f: float, hi_f: float, method: str) -> float:
    """Nominal period [frames] in ``lo_f..hi_f`` by FFT peak or uniform-segmentation energy.

    ``"fft"``: the peak of the channel-summed power spectrum (Hann window, 8x zero
    padding) within the band (else the nearest bin). ``"energy"``: the period minimising
    :func:`uniform_energy` over a 0.25-frame grid (at most 400 log-spaced candidates); a
    minimum at the short end of the band (where short windows of a slow signal correlate
    trivially) gives way to the lowest interior local minimum, if any.
    """
    n = x.shape[1]
    if method == "fft":
        nfft = int(2 ** np.ceil(np.log2(8 * n)))
        spec = np.abs(np.fft.rfft(x * np.hanning(n)[None, :], n=nfft, axis=1)) ** 2
        power = spec.sum(axis=0)
        freqs = np.fft.rfftfreq(nfft, d=1.0)  # [1/frame]
        band = (freqs >= 1.0 / hi_f) & (freqs <= 1.0 / lo_f)
        if not band.any():  # band narrower than a bin: the nearest bin
            band = np.abs(freqs - 2.0 / (lo_f + hi_f)) == np.abs(freqs - 2.0 / (lo_f + hi_f)).min()
        return float(1.0 / freqs[band][np.argmax(power[band])])
    step = 0.25  # [frames]
    count = int(np.floor((hi_f - lo_f) / step)) + 1
    if count > _MAX_COUNT_CANDIDATES:
        cands = np.geomspace(lo_f, hi_f, _MAX_COUNT_CANDIDATES)
    else:
        cands = lo_f + step * np.arange(count)
    e = np.nan_to_num(uniform_energy(x, cands), nan=np.inf)  # two periods fit: one is finite
    best = int(np.argmin(e))
    edge = max(1, cands.size // 50)
    if best < edge:
        # a minimum at the short end of the range: short windows of a slow signal
        # correlate trivially (ramps); prefer the lowest interior local minimum
        inner = np.arange(edge, cands.size - edge)
        is_min = (e[inner] <= e[inner - 1]) & (e[inner] <= e[inner + 1])
        if is_min.any():
            mins = inner[is_min]
            best = int(mins[np.argmin(e[mins])])
    return float(cands[best])


def periodicity_contrast(x: np.ndarray, frames: np.ndarray) -> float:
    """How much better the found period is than wrong periods, for uniform segmentations.

    ``min_f e(U_{f T}) - e(U_T)`` for ``f`` in :data:`OFF_PERIOD_FACTORS`, with ``e`` the
    mean Pearson distance per channel and pair, ``T`` the optimum's mean period and
    ``U_P`` the uniform segmentation of period ``P`` from the optimum's first boundary.
    Noise scores about 0 or below, a periodic motion clearly above; NaN if no
    off-period segmentation fits.
    """
    period = (frames[-1] - frames[0]) / (frames.size - 1)
    xs = x[:, frames[0] :]
    e = uniform_energy(xs, period * np.array((1.0,) + OFF_PERIOD_FACTORS))
    if np.isnan(e[0]) or np.all(np.isnan(e[1:])):
        return float("nan")
    return float(np.nanmin(e[1:]) - e[0])
