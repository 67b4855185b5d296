"""Period estimation and the periodicity test of the segmentation.

Data contract
-------------
- Input: standardised channels ``x`` ``(n_channels, n_frames)`` (see
  :func:`.channels.standardise`); periods and boundaries in frames (float periods
  allowed, boundaries int).
- Output: a nominal period [frames] (:func:`estimate_period`); mean Pearson distances
  of uniform segmentations (:func:`uniform_energy`); the periodicity contrast of a
  found segmentation (:func:`periodicity_contrast`).

Seconds and validation belong to the public entry (:func:`beatsync.segment.segment_values`,
:func:`beatsync.segment.estimate_period_count`): it turns the period range [s] into
the frame band :func:`estimation_band` and checks that band before calling
:func:`estimate_period`, which trusts it.

The periodicity rule: a clip is refused as not periodic when the optimum's mean
Pearson distance per channel and pair reaches :data:`MAX_NORMALISED_ENERGY`, or when
its :func:`periodicity_contrast` is below :data:`MIN_PERIODICITY_CONTRAST`.
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
    """Consecutive tiers ``(lo, 5 lo), (5 lo, 25 lo), ... , (.., hi)`` of a period range.

    A range wider than :data:`TIER_FACTOR` is searched tier by tier, shortest first,
    so that a motion periodic at a step (say 1 s) is not described by a multiple of it
    (a 3 s figure, whose uniform segmentation is often as good or better); a motion
    that repeats only over a longer figure (a 4 s waltz box) is found in a later tier.
    Any unit; the paper's range (0.25, 1.25) is one tier.
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
    """Candidate periods [frames] for a clip of ``n`` frames: two periods must fit.

    ``lo_frames``/``hi_frames`` is the requested period range in frames; the band is
    ``max(lo, 2) .. min(hi, (n - 1) / 2)`` (empty if the first exceeds the second).
    """
    return max(float(lo_frames), 2.0), min(float(hi_frames), (n - 1) / 2.0)


def uniform_frames(n: int, period: float) -> np.ndarray:
    """Uniform boundaries 0, L, 2L, ... (rounded) that fit in frames 0..n-1."""
    count = int(np.floor((n - 1) / period + 1e-9))
    return np.rint(np.arange(count + 1) * period).astype(np.int64)


def uniform_energy(x: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Mean Pearson distance per channel and pair of uniform segmentations (NaN if < 2)."""
    n_ch, n = x.shape
    a_l, b_l, c_l, owner = [], [], [], []
    for i, per in enumerate(periods):
        f = uniform_frames(n, float(per))
        if f.size < 3 or np.any(np.diff(f) < 1):
            continue
        a_l.append(f[:-2])
        b_l.append(f[1:-1])
        c_l.append(f[2:])
        owner.append(np.full(f.size - 2, i))
    out = np.full(len(periods), np.nan)
    if not a_l:
        return out
    own = np.concatenate(owner)
    costs = pair_costs(x, np.concatenate(a_l), np.concatenate(b_l), np.concatenate(c_l))
    tot = np.bincount(own, weights=costs, minlength=len(periods))
    cnt = np.bincount(own, minlength=len(periods))
    ok = cnt > 0
    out[ok] = tot[ok] / (cnt[ok] * n_ch)
    return out


def estimate_period(x: np.ndarray, lo_f: float, hi_f: float, method: str) -> float:
    """Nominal period [frames] in ``lo_f..hi_f`` by FFT peak or uniform-segmentation energy.

    ``lo_f..hi_f`` comes from :func:`estimation_band` (``2 <= lo_f <= hi_f``).
    ``"fft"``: the peak of the channel-summed power spectrum (Hann window, 8x zero
    padding) within the band (the bin nearest to it if none lies inside). ``"energy"``:
    the period ``T`` minimising :func:`uniform_energy` over a 0.25-frame grid (at most
    400 log-spaced candidates); if the minimum lies at the short end of the band (where
    short windows of a slow signal correlate trivially), the lowest interior local
    minimum is taken instead (if any).
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
    e = uniform_energy(x, cands)
    if np.all(np.isnan(e)):
        raise RuntimeError(f"no uniform segmentation of {lo_f:.1f}-{hi_f:.1f} frames fits {n}")
    e = np.where(np.isnan(e), np.inf, e)
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

    ``min_f e(U_{f T}) - e(U_T)`` for ``f`` in (0.5, 0.75, 1.25, 1.5), where ``e`` is the
    mean Pearson distance per channel and consecutive pair, ``T`` the optimum's mean
    period and ``U_P`` the uniform segmentation with period ``P`` starting at the
    optimum's first boundary (only those with at least two pairs count). Both sides are
    unoptimised, so noise or a non-repeating motion scores about 0 (or below), while a
    periodic motion scores clearly above. NaN if no off-period segmentation fits.
    """
    n_found = frames.size - 1
    period = (frames[-1] - frames[0]) / n_found
    xs = x[:, frames[0] :]
    e = uniform_energy(xs, period * np.array((1.0,) + OFF_PERIOD_FACTORS))
    if np.isnan(e[0]) or np.all(np.isnan(e[1:])):
        return float("nan")
    return float(np.nanmin(e[1:]) - e[0])
