"""The smooth time warp of paper A, eq. 9: blended per-period rates integrated into a warp.

Data contract: event times are 1-D float64 seconds, strictly increasing; source times
are in the motion's timeline, target times in the music's. Rates are dimensionless
(``target duration / source duration``). See :mod:`beatsync.sync` for the method.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validation import check_positive, check_times

__all__ = ["TimeWarp", "blended_rate", "correction_bump", "integrate_warp", "time_warp"]

#: knots of the warp grid inside each period
GRID_PER_PERIOD = 128
#: fraction of a period over which the correction ramps in (and out) at each end
TAPER = 0.25
#: below this bump amplitude the correction would make the rate near zero: scale instead
MIN_BUMP = -0.9
#: Gaussian weights are summed over centres within this many widths of a time
BLEND_REACH = 8.0
#: a held stretch covers at most this share of a period at each end
MAX_HOLD = 0.2
_CHUNK = 4096


def correction_bump(u: np.ndarray) -> np.ndarray:
    """Correction shape on the period phase ``u`` in [0, 1]: 0 at both ends, 1 in the
    middle, with raised-cosine ramps over ``TAPER`` of the period at each end."""
    ramp = np.minimum(u, 1.0 - u) / TAPER
    return np.where(ramp >= 1.0, 1.0, np.sin(0.5 * np.pi * np.clip(ramp, 0.0, 1.0)) ** 2)


def blended_rate(t: Any, centres: Any, rates: Any, *, delta: float) -> np.ndarray:
    """Gaussian-blended rate (paper A, eq. 9, our reading) at source times ``t`` [s]:
    ``r(t) = sum_i w_i(t) r_i / sum_i w_i(t)``, ``w_i(t) = exp(-(t - c_i)^2 / (2 delta^2))``
    with ``c_i`` the period centres [s], ``r_i`` the per-period rates (target / source)
    and ``delta`` [s] the Gaussian width."""
    t = np.asarray(t, dtype=np.float64)
    c = np.asarray(centres, dtype=np.float64)
    r = np.asarray(rates, dtype=np.float64)
    out = np.empty(t.shape)
    # weights beyond BLEND_REACH widths are below 1e-14 of the nearest one: the sum is
    # taken over the centres within reach only (sorted centres; chunks of times), so
    # long songs cost time and memory linear in their length
    order = np.argsort(c, kind="stable")
    c, r = c[order], r[order]
    reach = BLEND_REACH * delta
    for a in range(0, t.size, _CHUNK):
        tc = t[a : a + _CHUNK]
        lo = int(np.searchsorted(c, tc.min() - reach, side="left"))
        hi = int(np.searchsorted(c, tc.max() + reach, side="right"))
        # always keep the centres nearest to the chunk's ends (times far outside)
        lo = max(0, min(lo, int(np.searchsorted(c, tc.min())) - 1))
        hi = min(c.size, max(hi, int(np.searchsorted(c, tc.max())) + 1))
        z = (tc[:, None] - c[None, lo:hi]) / delta
        # subtract the row maximum of the log weights so far-away times do not underflow
        logw = -0.5 * z * z
        logw -= logw.max(axis=1, keepdims=True)
        w = np.exp(logw)
        out[a : a + _CHUNK] = (w @ r[lo:hi]) / w.sum(axis=1)
    return out


@dataclass(frozen=True)
class TimeWarp:
    """A monotonic, piecewise-linear map from source time to music time.

    Knots ``src`` [s] (source, increasing) and ``tgt`` [s] (music, increasing); the
    ``boundaries`` [s] used and the ``targets`` [s] they land on; ``period_rates``
    ``r_i`` (target / source) and the corrected continuous ``rate`` at the knots;
    ``n_scaled``, the periods whose correction fell back to scaling (the rate jumps
    at their ends); ``delta`` [s], eq. 9's width.
    """

    src: np.ndarray
    tgt: np.ndarray
    boundaries: np.ndarray
    targets: np.ndarray
    period_rates: np.ndarray
    rate: np.ndarray
    n_scaled: int
    delta: float

    def to_target(self, t: Any) -> np.ndarray:
        """Music time [s] of source times ``t`` [s] (linear beyond the ends)."""
        t = np.asarray(t, dtype=np.float64)
        out = np.interp(t, self.src, self.tgt)
        lo, hi = t < self.src[0], t > self.src[-1]
        out[lo] = self.tgt[0] + (t[lo] - self.src[0]) * self.rate[0]
        out[hi] = self.tgt[-1] + (t[hi] - self.src[-1]) * self.rate[-1]
        return out

    def to_source(self, tau: Any) -> np.ndarray:
        """Source time [s] of music times ``tau`` [s], clipped to the warp's source span."""
        return np.interp(np.asarray(tau, dtype=np.float64), self.tgt, self.src)


def time_warp(
    boundaries: Any,
    targets: Any,
    *,
    start: float | None = None,
    end: float | None = None,
    delta: float | None = None,
) -> TimeWarp:
    """Integrate the blended, boundary-corrected rate into a time warp that lands every
    boundary [s] on its target [s] (to rounding), covering ``start`` / ``end`` [s]
    before the first / after the last boundary at the rate there; ``delta`` [s] is eq.
    9's width (default the mean period). ParameterError on mismatched lengths, fewer
    than two boundaries, unsorted times or a bad ``delta``.

    Examples
    --------
    >>> w = time_warp([0.0, 1.0, 2.0], [0.0, 0.5, 1.0])
    >>> w.to_target([0.5, 1.5]).round(6)
    array([0.25, 0.75])
    """
    s = check_times(boundaries, name="boundaries")
    b = np.asarray(targets, dtype=np.float64)
    if s.size < 2:
        raise ParameterError(
            f"need at least 2 period boundaries (one period), got {s.size}; is the motion periodic?"
        )
    if b.shape != s.shape:
        raise ParameterError(
            f"targets has shape {b.shape} but boundaries has {s.shape}: one music time per boundary"
        )
    b = check_times(b, name="targets")
    if delta is not None:
        delta = check_positive(delta, name="delta", unit="s")
    return integrate_warp(s, b, start=start, end=end, delta=delta)


def integrate_warp(
    s: np.ndarray,
    b: np.ndarray,
    *,
    start: float | None = None,
    end: float | None = None,
    delta: float | None = None,
    hold: float = 0.0,
    floor: np.ndarray | None = None,
) -> TimeWarp:
    """:func:`time_warp` on inputs already checked (float64, increasing, same length >= 2).

    ``hold`` [s]: the rate stays at its boundary value, the geometric mean of the two
    periods' rates there, this long on both sides of every boundary (at most
    ``MAX_HOLD`` of a period), so that a speed minimum of the motion there is neither
    moved nor erased by a change of rate; the bump corrects in between.
    ``floor`` (one per boundary): the lowest rate held at each boundary (ignored
    without ``hold``).
    """
    src_len = np.diff(s)
    tgt_len = np.diff(b)
    if delta is None:
        delta = float(src_len.mean())
    p = src_len.size
    k = GRID_PER_PERIOD
    u = np.linspace(0.0, 1.0, k + 1)
    # grid (p, k+1): period i from s_i to s_{i+1}; shared endpoints duplicated per row
    grid = s[:-1, None] + u[None, :] * src_len[:, None]
    rates = tgt_len / src_len
    centres = 0.5 * (s[:-1] + s[1:])
    r = blended_rate(grid.ravel(), centres, rates, delta=delta).reshape(p, k + 1)
    # exact landing: r~ = r (1 + a_i h), h vanishes at both ends
    v = u[None, :]
    if hold > 0:  # the bump's phase runs over the period between the held ends
        q = np.minimum(hold / src_len, MAX_HOLD)[:, None]
        v = np.clip((v - q) / (1.0 - 2.0 * q), 0.0, 1.0)
    h = np.broadcast_to(correction_bump(v), r.shape)
    if hold > 0:
        # held at the rate where the two periods meet (their geometric mean): eq. 9's
        # blend reaches further periods, and held at a slower neighbour's rate a short
        # fast period would have to make the time up in its middle
        log_r = np.log(rates)
        joint = np.exp(np.concatenate([log_r[:1], 0.5 * (log_r[:-1] + log_r[1:]), log_r[-1:]]))
        r[:, 0], r[:, -1] = joint[:-1], joint[1:]
        if floor is not None:
            r[:, 0] = np.maximum(r[:, 0], floor[:-1])
            r[:, -1] = np.maximum(r[:, -1], floor[1:])
        ease = v * v * (3.0 - 2.0 * v)  # flat at 0 and 1: the held boundary rates
        base = r[:, :1] + (r[:, -1:] - r[:, :1]) * ease
        r = base + (r - base) * h
    dt = src_len[:, None] * np.diff(u)[None, :]
    integ = ((r[:, :-1] + r[:, 1:]) * 0.5 * dt).sum(axis=1)
    rh = r * h
    integ_h = ((rh[:, :-1] + rh[:, 1:]) * 0.5 * dt).sum(axis=1)
    a = (tgt_len - integ) / integ_h
    scaled = a <= MIN_BUMP
    rc = r * (1.0 + a[:, None] * h)
    if scaled.any():
        rc[scaled] = r[scaled] * (tgt_len[scaled] / integ[scaled])[:, None]
    seg = (rc[:, :-1] + rc[:, 1:]) * 0.5 * dt  # (p, k)
    # cumulative music time within each period, anchored on its own target beat so
    # rounding does not accumulate across periods
    tau = np.empty((p, k + 1))
    tau[:, 0] = b[:-1]
    tau[:, 1:] = b[:-1, None] + np.cumsum(seg, axis=1)
    tau[:, -1] = b[1:]
    src_knots = np.concatenate([grid[:, :-1].ravel(), s[-1:]])
    tgt_knots = np.concatenate([tau[:, :-1].ravel(), b[-1:]])
    rate_knots = np.concatenate([rc[:, :-1].ravel(), rc[-1:, -1]])
    if start is not None and start < s[0]:
        src_knots = np.concatenate([[start], src_knots])
        tgt_knots = np.concatenate([[b[0] - (s[0] - start) * rate_knots[0]], tgt_knots])
        rate_knots = np.concatenate([rate_knots[:1], rate_knots])
    if end is not None and end > s[-1]:
        src_knots = np.concatenate([src_knots, [end]])
        tgt_knots = np.concatenate([tgt_knots, [b[-1] + (end - s[-1]) * rate_knots[-1]]])
        rate_knots = np.concatenate([rate_knots, rate_knots[-1:]])
    return TimeWarp(
        src=src_knots,
        tgt=tgt_knots,
        boundaries=s,
        targets=b,
        period_rates=rates,
        rate=rate_knots,
        n_scaled=int(scaled.sum()),
        delta=delta,
    )
