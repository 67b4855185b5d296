"""Optimal temporal segmentation of periodic motion into its periods (paper A, sec. 3).

Panagiotakis, Holzapfel, Michel, Argyros, "Beat synchronous dance animation based on
visual analysis of human motion and audio analysis of music tempo", section 3.
Notebook: ``notebooks/paper_a_fig02_segmentation.ipynb`` (Figure 2 and boundary-error table).

Data contract
-------------
- Input: motion values ``(n_frames, n_channels)``, time first, at ``fps > 0`` [Hz];
  rotation channels in degrees (they are unwrapped across +-180 deg before analysis).
- Output: :class:`Segmentation` whose ``boundaries`` are ``n_periods + 1`` strictly
  increasing times [s] within ``[0, (n_frames - 1) / fps]``: start of the first full
  period ... end of the last (lead-in and tail shorter than a period are left out).
  Frames are used only inside this module; conversion goes through
  :func:`beatsync.units.frames_to_time`.

The method
----------
A segmentation ``T_p = (t_0 < t_1 < ... < t_p)`` (frames) splits the signal
into periods ``S_i = X[t_i .. t_{i+1}]`` (both ends included, ``t_{i+1} - t_i`` frames
long). Its energy (eqs. 1-2) is

    E(T_p) = sum_{i=1}^{p-1} sum_c  1 - r( S_{i-1,c}, resample(S_{i,c}, len(S_{i-1})) )

with ``r`` the Pearson correlation and ``resample`` linear interpolation of the later
period onto the earlier one's samples (end points aligned). Every period length must
stay inside the alpha band around the nominal period ``L`` (eq. 3; ``L = (n-1)/p``
when the count ``p`` is given, else the estimated period, see
:func:`estimate_period_count`):
``(1-alpha) L <= t_{i+1} - t_i <= (1+alpha) L``. The globally optimal ``T_p``
(eqs. 4-5) is a shortest path in a forward DAG whose nodes are consecutive boundary
pairs ``(t_{i-1}, t_i)``, with a virtual end node joined to every pair ending in the
tail of the clip; the DAG is solved by dynamic programming in frame order (no heap).
When the count ``p`` is given (``n_periods``), the DP carries the number of periods in
its state and returns the optimum with exactly ``p`` periods (``argmin E``, as in the
paper). When the count is estimated, the graph has no period index (and the ends are
free, see below), so the optimum may use a period count within the band other than
the estimate; minimising ``E`` itself would then favour one period fewer (one term
fewer), so that optimum minimises the mean energy per consecutive pair ``E / (p - 1)``
(Dinkelbach iteration over the same DP: ``argmin E - lambda (p - 1)``, ``lambda``
updated to the current mean). :attr:`Segmentation.n_periods` reports the count found.

Edge costs dominate the time. They are computed for all ``(middle boundary, earlier
length, later length)`` at once (in float32; on z-scored channels an edge cost then
differs from float64 by ~1e-5, checked in the tests): every sum in a Pearson
correlation (sum of A, of A^2, of resampled B, of its square, and of A * B) is a
fixed linear combination of lagged products ``X[s] X[s + l]`` in a window around the
middle boundary, so each is one matrix product of windowed products with a constant
kernel (see
:func:`_edge_costs`). :func:`_segment_literal` is the direct loop implementation of
the same equations, kept as the reference for tests and the benchmark.

Documented rules (choices the paper leaves open)
------------------------------------------------
- Near-constant channels (Pearson undefined): a channel is excluded when its standard
  deviation over the clip is at most ``CONSTANT_REL_STD`` (1e-3) times the largest
  standard deviation among the selected channels, or at most 1e-9. Inside a kept
  channel, a period whose own variance is below 1e-6 of the channel's variance is
  treated as flat: its correlation is ~0 (cost ~1).
- Periodicity: a clip is refused as not periodic when the optimum's mean Pearson
  distance per channel and pair, ``E / (n_channels * (p - 1))``, reaches
  ``MAX_NORMALISED_ENERGY`` (1.0: consecutive periods uncorrelated on average), or
  when its periodicity contrast (:func:`periodicity_contrast`: how much better the
  uniform segmentation at the found period is than uniform segmentations at 0.5,
  0.75, 1.25 and 1.5 times it) is below ``MIN_PERIODICITY_CONTRAST`` (0.05).
  Calibration (default channels, both period methods): CMU salsa 60_01/61_01/60_04/
  61_04 0.053-0.16, CMU walks 007_* 1.06-1.27, MoCap Toolbox dance1/dance2/walk1/walk2
  0.14-0.90; the CMU 005_02 pirouette -0.16 and -0.12; white noise (4 or 29 channels,
  16 trials) <= 0.04. Known limits: the margin is small (salsa 61_04 with the FFT
  period: 0.053), and a random walk (integrated noise) passed in 7 of 16 trials.
- Free ends: real clips do not start or end on a period boundary, so the first
  boundary may lie anywhere in the lead-in ``t_0 < lo`` and the last in the tail
  ``t_p >= n - lo`` (``lo``: shortest allowed period); the band of eq. 3 is rounded
  outward to whole frames. A synthetic clip that is an exact tiling is recovered with
  ``t_0 = 0`` and ``t_p = n - 1``.
- Memory: the edge-cost kernels grow with the cube of the period length in frames.
  When the exact search would need more than :data:`SEARCH_MEMORY_BUDGET` (512 MiB),
  it runs on the signal decimated in time by the smallest integer factor ``f`` that
  fits (box filter, every ``f``-th frame), and every boundary is then refined at full
  rate by an exact DP within ``+-f`` frames of the coarse optimum, repeated until the
  energy stops decreasing (:attr:`Segmentation.search_decimation` reports ``f``).
- Default channels: rotation channels of the main limb and spine joints (see
  :func:`select_channels`), or every ``*_angle`` channel for marker-derived angles.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from .errors import BeatsyncWarning, ParameterError
from .units import check_finite, check_fps, check_range, frames_to_time, time_to_frames

if TYPE_CHECKING:
    from .motion import Motion

__all__ = [
    "Segmentation",
    "segment",
    "segment_values",
    "estimate_period_count",
    "select_channels",
    "segmentation_energy",
    "CONSTANT_REL_STD",
    "MAX_NORMALISED_ENERGY",
    "MIN_PERIODICITY_CONTRAST",
    "SEARCH_MEMORY_BUDGET",
    "periodicity_contrast",
    "boundary_errors",
    "uniform_baseline",
    "minima_baseline",
    "synthetic_error_table",
    "plot_segmentation",
]

CONSTANT_REL_STD = 1e-3
"""A channel with std <= this times the largest selected std is excluded as constant."""

MAX_NORMALISED_ENERGY = 1.0
"""Not periodic if E / (channels * (periods - 1)) (mean Pearson distance) reaches this."""

MIN_PERIODICITY_CONTRAST = 0.05
"""Not periodic if the optimum beats off-period uniform segmentations by less than this."""

_OFF_PERIOD_FACTORS = (0.5, 0.75, 1.25, 1.5)

_FLAT_REL_VAR = 1e-6  # period variance floor, relative to the channel's variance
_PERIOD_METHODS = ("energy", "fft", "given")
_FAST_DTYPE = np.float32  # edge-cost sums in float32: ~2x faster, |error| ~1e-5 per edge
_MAX_COUNT_CANDIDATES = 400  # candidate periods of the "energy" method (then log-spaced)
_CHUNK_ELEMENTS = 3e5  # window-matrix elements per block of middle boundaries (cache size)
_DP_BLOCK_ELEMENTS = 2e6  # elements of one block of the fixed-count DP
_MAX_REFINE_PASSES = 10  # full-rate refinement passes after a decimated search

SEARCH_MEMORY_BUDGET = 512 * 2**20
"""Bytes [B] the exact search may use; above it the search runs on a decimated signal."""


@dataclass(frozen=True)
class Segmentation:
    """Result of :func:`segment`.

    Attributes
    ----------
    boundaries : np.ndarray [s]
        ``n_periods + 1`` strictly increasing times: start of the first period ... end
        of the last, within ``[0, (n_frames - 1) / fps]``.
    n_periods : int
    mean_period : float [s]
    energy : float
        E of the optimum (sum over consecutive period pairs and channels of 1 - r).
    channels : tuple of str
        Channels used (after selection and constant-channel exclusion).
    fps : float [Hz]
    period_method : str
        ``"energy"``, ``"fft"`` or ``"given"``.
    search_decimation : int >= 1
        Time decimation factor of the search (1: exact search at full rate; above
        :data:`SEARCH_MEMORY_BUDGET` the search runs at ``fps / f`` and the boundaries
        are refined at full rate, see :func:`segment_values`).
    """

    boundaries: np.ndarray
    n_periods: int
    mean_period: float
    energy: float
    channels: tuple[str, ...]
    fps: float
    period_method: str
    search_decimation: int = 1

    @property
    def boundary_frames(self) -> np.ndarray:
        """Boundaries as frame indices (int64)."""
        return time_to_frames(self.boundaries, fps=self.fps)

    @property
    def periods(self) -> np.ndarray:
        """Period durations [s]."""
        return np.diff(self.boundaries)

    @property
    def normalised_energy(self) -> float:
        """Mean Pearson distance between consecutive periods, E / (channels * (p-1))."""
        return float(self.energy / (len(self.channels) * max(self.n_periods - 1, 1)))


# --------------------------------------------------------------------------- channels

# Joint-name keywords (lower case, side prefixes and CC_Base_ removed) of the main
# limb and spine joints, for CMU (hip abdomen chest neck rShldr rForeArm rThigh rShin
# rFoot ...), iClone CC_Base (Spine01, Waist, L_Upperarm, L_Forearm, L_Thigh, L_Calf,
# L_Foot ...) and Mixamo-like (Spine, LeftArm, LeftUpLeg, LeftLeg ...) rigs.
_LIMB_SPINE = (
    "abdomen", "chest", "neck", "spine", "waist", "pelvis",
    "shldr", "shoulder", "upperarm", "arm", "forearm", "elbow",
    "thigh", "upleg", "leg", "shin", "calf", "knee", "foot", "ankle",
)  # fmt: skip
# Never default: twist/helper bones, extremities, face, and the root/hip (its rotation
# is the body's global orientation, not a joint angle).
_EXCLUDE = ("twist", "share", "toe", "hand", "finger", "thumb", "index", "mid", "ring",
            "pinky", "eye", "jaw", "head", "collar", "clavicle", "breast", "rib",
            "buttock", "root", "end")  # fmt: skip
_ROOT_NAMES = ("hip", "hips", "cc_base_hip", "rl_boneroot", "root")


def _joint_key(joint: str) -> str:
    """Joint key: ``"rShin"`` -> ``"shin"``, ``"CC_Base_L_Calf"`` -> ``"calf"``."""
    key = re.sub(r"^(CC_Base_|mixamorig:?|RL_)", "", joint, flags=re.IGNORECASE)
    key = re.sub(r"^([LR]_|[lr](?=[A-Z])|Left_?|Right_?)", "", key, flags=0)
    key = re.sub(r"^(left_?|right_?)", "", key, flags=re.IGNORECASE)
    return re.sub(r"\d+$", "", key.lower().replace("_", ""))


def _is_default_channel(name: str) -> bool:
    if name.endswith("_angle"):
        return True
    joint, sep, dof = name.rpartition("_")
    if not sep or not dof.lower().endswith("rotation"):
        return False
    if joint.lower() in _ROOT_NAMES:
        return False
    key = _joint_key(joint)
    if any(x in key for x in _EXCLUDE):
        return False
    return any(key == k or key.endswith(k) for k in _LIMB_SPINE)


def select_channels(
    names: Sequence[str], channels: str | Sequence[str] = "default"
) -> tuple[str, ...]:
    """Choose the channels the segmentation uses.

    Parameters
    ----------
    names : sequence of str
        All channel names, e.g. ``Motion.channels`` (``"rShin_Xrotation"``,
        ``"CC_Base_L_Calf_Zrotation"``, ``"knee_L_angle"``).
    channels : "default", "all" or sequence of str
        ``"default"``: rotation channels of the main limb and spine joints (CMU:
        abdomen chest neck rShldr rForeArm lShldr lForeArm rThigh rShin rFoot lThigh
        lShin lFoot; iClone: CC_Base_Waist/Spine01/Spine02/*_Upperarm/*_Forearm/
        *_Thigh/*_Calf/*_Foot; no twist bones, hands, toes, face, nor the root's
        global orientation), plus every ``*_angle`` channel (marker-derived angles).
        If nothing matches, all channels are used with a :class:`BeatsyncWarning`.
        ``"all"``: every channel (constant ones are dropped later). A sequence: exactly
        those names.

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        Unknown channel names or an empty selection.

    Examples
    --------
    >>> select_channels(["hip_Xposition", "hip_Zrotation", "rShin_Xrotation", "rHand_Xrotation"])
    ('rShin_Xrotation',)
    """
    names = tuple(str(n) for n in names)
    if isinstance(channels, str):
        if channels == "all":
            return names
        if channels != "default":
            if channels in names:
                return (channels,)
            raise ParameterError(
                f"channels={channels!r}: use 'default', 'all' or a list of channel names "
                f"(e.g. {list(names[:3])})"
            )
        chosen = tuple(n for n in names if _is_default_channel(n))
        if not chosen:
            warnings.warn(
                "no limb/spine rotation or *_angle channel found among "
                f"{list(names[:4])}...; using all channels",
                BeatsyncWarning,
                stacklevel=3,
            )
            return names
        return chosen
    chosen = tuple(str(c) for c in channels)
    missing = [c for c in chosen if c not in names]
    if missing:
        raise ParameterError(
            f"channel(s) {missing[:5]} not found; channels look like {list(names[:4])}"
        )
    if not chosen:
        raise ParameterError("channels is an empty list; give at least one channel name")
    return chosen


def _nonconstant(values: np.ndarray) -> np.ndarray:
    """Boolean mask of channels kept by the documented near-constant rule."""
    std = values.std(axis=0)
    top = std.max() if std.size else 0.0
    return (std > CONSTANT_REL_STD * top) & (std > 1e-9)


def _standardise(values: np.ndarray) -> np.ndarray:
    """Per-channel z-score, returned channel-first ``(C, n)`` (r is invariant to it)."""
    x = values - values.mean(axis=0)
    x = x / x.std(axis=0)
    return np.ascontiguousarray(x.T)


# ------------------------------------------------------------------ Pearson distances


def _resample_weights(d0: int, d1: Any) -> tuple[np.ndarray, np.ndarray]:
    """Linear resampling of ``d1 + 1`` samples onto ``d0 + 1`` (end points aligned).

    Output sample ``k`` (0..d0) is ``(1 - w_k) B[j_k] + w_k B[j_k + 1]`` with
    ``j_k + w_k = k d1 / d0`` (exact integer arithmetic). ``d1`` may be an int
    (returns shape ``(d0 + 1,)``) or an array of ints (shape ``d1.shape + (d0 + 1,)``).
    """
    d1 = np.asarray(d1, dtype=np.int64)
    d1 = d1[..., None] if d1.ndim else d1
    k = np.arange(d0 + 1)
    j = (k * d1) // d0
    w = (k * d1 - j * d0) / d0
    last = j >= d1
    j = np.where(last, d1 - 1, j)
    w = np.where(last, 1.0, w)
    return j, w


def _pair_costs(x: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Pearson distance, summed over channels, for arbitrary boundary triples.

    Parameters
    ----------
    x : np.ndarray [shape=(C, n)], standardised channels
    a, b, c : np.ndarray [frames], int
        Triples ``a < b < c``: earlier period ``x[a..b]``, later period ``x[b..c]``.

    Returns
    -------
    np.ndarray [shape=(len(a),)]
        ``sum_c 1 - r_c``.
    """
    a, b, c = (np.asarray(v, dtype=np.int64) for v in (a, b, c))
    out = np.empty(a.size)
    d0_all, d1_all = b - a, c - b
    n_ch = x.shape[0]
    # group by earlier length so the sample grid is rectangular
    for d0 in np.unique(d0_all):
        sel = np.nonzero(d0_all == d0)[0]
        for start in range(0, sel.size, 4096):
            s = sel[start : start + 4096]
            k = np.arange(d0 + 1)
            j, w = _resample_weights(int(d0), d1_all[s])  # (T, d0+1)
            pos = b[s][:, None] + j
            A = x[:, a[s][:, None] + k[None, :]]  # (C, T, d0+1)
            B = x[:, pos] * (1 - w) + x[:, pos + 1] * w
            out[s] = n_ch - _pearson(A, B).sum(axis=0)
    return out


def _pearson(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Pearson r along the last axis with the flat-period floor."""
    m = A.shape[-1]
    A = A - A.mean(axis=-1, keepdims=True)
    B = B - B.mean(axis=-1, keepdims=True)
    floor = _FLAT_REL_VAR * m
    num = np.sum(A * B, axis=-1)
    return num / np.sqrt((np.sum(A * A, axis=-1) + floor) * (np.sum(B * B, axis=-1) + floor))


@lru_cache(maxsize=32)
def _kernels(lo: int, hi: int) -> tuple[Any, ...]:
    """Constant kernels turning windowed lagged products into the Pearson sums.

    For middle boundary ``b``, earlier length ``d0`` and later length ``d1`` (combo
    ``q = (d0-lo)*band + (d1-lo)``), the resampled later period is
    ``B_k = (1-w_k) X[b+j_k] + w_k X[b+j_k+1]``. Then

    - ``sum_k B_k = sum_m U[m, q] X[b+m]``,
    - ``sum_k B_k^2 = sum_m G0[m, q] X[b+m]^2 + G1[m, q] X[b+m] X[b+m+1]``,
    - ``sum_k A_k B_k = sum_l sum_s H_l[s, q] X[b+s] X[b+s+l]`` with ``A_k = X[b-d0+k]``.
    """
    band = hi - lo + 1
    nq = band * band
    width_b = hi + 1  # offsets m = 0..hi (j+1 <= d1 <= hi)
    U = np.zeros((width_b, nq))
    G0 = np.zeros((width_b, nq))
    G1 = np.zeros((width_b, nq))
    # lag l = d0 + j - k (or +1): within [lo, hi] wherever the weight is non-zero;
    # zero-weight end terms may touch lo-1 or hi+1, so those slots exist (and stay 0)
    lags = np.arange(lo - 1, hi + 2)
    H = np.zeros((lags.size, hi + 1, nq))  # offset s = -hi..0 -> row s + hi
    for i0, d0 in enumerate(range(lo, hi + 1)):
        for i1, d1 in enumerate(range(lo, hi + 1)):
            q = i0 * band + i1
            j, w = _resample_weights(d0, d1)
            k = np.arange(d0 + 1)
            np.add.at(U[:, q], j, 1 - w)
            np.add.at(U[:, q], j + 1, w)
            np.add.at(G0[:, q], j, (1 - w) ** 2)
            np.add.at(G0[:, q], j + 1, w**2)
            np.add.at(G1[:, q], j, 2 * w * (1 - w))
            s = k - d0 + hi
            np.add.at(H, (d0 + j - k - lo + 1, s, np.full_like(k, q)), 1 - w)
            np.add.at(H, (d0 + j + 1 - k - lo + 1, s, np.full_like(k, q)), w)
    # keep only the rows each lag uses, stacked into one kernel for a single product
    rows = [np.nonzero(np.any(H[i] != 0, axis=1))[0] for i in range(lags.size)]
    used = [i for i in range(lags.size) if rows[i].size]
    H_stack = np.concatenate([H[i][rows[i]] for i in used], axis=0)
    spans = [(int(lags[i]), int(rows[i][0]) - hi, int(rows[i][-1]) - hi) for i in used]
    for (_lag, s0, s1), i in zip(spans, used, strict=False):
        assert rows[i].size == s1 - s0 + 1, "lag rows must be contiguous"
    return U, np.concatenate([G0, G1], axis=0), H_stack, spans


def _edge_costs(x: np.ndarray, lo: int, hi: int, *, dtype: type = np.float64) -> np.ndarray:
    """All DAG edge costs, vectorised: ``cost[b, i0, i1]`` (inf where invalid).

    ``b`` is the middle boundary [frames], the earlier period ``x[b-d0 .. b]`` has
    ``d0 = lo + i0`` frames and the later ``x[b .. b+d1]`` has ``d1 = lo + i1``.
    The sums of the later (resampled) period and the cross sums are matrix products
    of windowed (lagged) products with the constant kernels of :func:`_kernels`,
    in blocks of middle boundaries that fit in cache. ``dtype=np.float32`` halves the
    memory traffic (edge costs then differ by ~1e-5 from float64).
    """
    n_ch, n = x.shape
    band = hi - lo + 1
    U, G, H, spans = (k.astype(dtype) if isinstance(k, np.ndarray) else k for k in _kernels(lo, hi))
    pad = hi + 2
    xp = np.zeros((n_ch, n + 2 * pad), dtype=dtype)
    xp[:, pad : pad + n] = x
    wb = hi + 1
    # signals whose windows feed each product: offsets relative to the middle boundary
    q1 = np.zeros_like(xp)
    q1[:, :-1] = xp[:, :-1] * xp[:, 1:]
    b_sigs = [(xp * xp, 0, wb), (q1, 0, wb)]
    ab_sigs = []
    for lag, s0, s1 in spans:
        q = np.zeros_like(xp)
        q[:, :-lag] = xp[:, :-lag] * xp[:, lag:]
        ab_sigs.append((q, s0, s1 - s0 + 1))
    cs = np.concatenate([np.zeros((n_ch, 1)), np.cumsum(x, axis=1)], axis=1)
    cs2 = np.concatenate([np.zeros((n_ch, 1)), np.cumsum(x * x, axis=1)], axis=1)
    d0s = np.arange(lo, hi + 1)
    n0 = (d0s + 1.0)[:, None]  # samples per (resampled) period, by earlier length
    floor = _FLAT_REL_VAR * n0
    cost = np.full((n, band, band), np.inf)
    b_all = np.arange(lo, n - lo)  # middle boundaries that can have both neighbours
    w_ab = sum(length for _, _, length in ab_sigs)
    chunk = max(16, int(_CHUNK_ELEMENTS // (n_ch * w_ab)))
    buf_b = np.empty((n_ch, chunk, 2 * wb), dtype=dtype)
    buf_ab = np.empty((n_ch, chunk, w_ab), dtype=dtype)

    # full-length window views, made once; each block slices them (no copy until fill)
    b_views = [(sliding_window_view(sig, length, axis=1), off0) for sig, off0, length in b_sigs]
    ab_views = [(sliding_window_view(sig, length, axis=1), off0) for sig, off0, length in ab_sigs]
    x_view = sliding_window_view(xp, wb, axis=1)

    def fill(buf: np.ndarray, views: list, o: int, m: int) -> np.ndarray:
        col = 0
        for view, off0 in views:
            length = view.shape[2]
            buf[:, :m, col : col + length] = view[:, o + off0 : o + off0 + m]
            col += length
        return buf[:, :m].reshape(n_ch * m, col)

    for start in range(0, b_all.size, chunk):
        b = b_all[start : start + chunk]
        m = b.size
        o = pad + b[0]  # padded index of the first middle boundary
        sb = (x_view[:, o : o + m].reshape(n_ch * m, wb) @ U).reshape(n_ch, m, band, band)
        sbb = (fill(buf_b, b_views, o, m) @ G).reshape(n_ch, m, band, band)
        sab = (fill(buf_ab, ab_views, o, m) @ H).reshape(n_ch, m, band, band)
        st = np.clip(b[:, None] - d0s[None, :], 0, None)
        sa = cs[:, b[:, None] + 1] - cs[:, st]  # (C, m, band)
        saa = cs2[:, b[:, None] + 1] - cs2[:, st]
        ss_a = (np.maximum(saa - sa * sa / n0[:, 0], 0.0) + floor[:, 0]).astype(dtype)
        sa = sa.astype(dtype)
        # cov = sab - sa * sb / n0 ; ss_b = sbb - sb^2 / n0 (in place, to save passes)
        sb /= n0.astype(dtype)
        sab -= sa[..., None] * sb
        sb *= sb
        sb *= n0.astype(dtype)
        sbb -= sb
        np.maximum(sbb, 0, out=sbb)  # rounding can leave a flat period slightly negative
        sbb += floor.astype(dtype)
        sbb *= ss_a[..., None]
        np.sqrt(sbb, out=sbb)
        sab /= sbb
        np.clip(sab, -1.0, 1.0, out=sab)  # r of a (near-)flat period: rounding noise
        cost[b] = n_ch - sab.sum(axis=0, dtype=np.float64)
    bb = np.arange(n)[:, None, None]
    valid = (bb - d0s[None, :, None] >= 0) & (bb + d0s[None, None, :] <= n - 1)
    cost[~valid] = np.inf
    return cost


# ---------------------------------------------------------------------- the optimum


def _shortest_path(
    cost: np.ndarray, n: int, lo: int, hi: int, reward: float = 0.0
) -> tuple[np.ndarray, float]:
    """DP over the forward DAG of boundary pairs, in frame order (eqs. 4-5).

    ``V[b, i]`` is the least energy of a chain of periods ending at frame ``b`` whose
    last period has ``lo + i`` frames. A chain may start at any frame ``t_0 < lo``
    (the lead-in before the first full period is shorter than any period) and joins
    the virtual end node from any frame ``t_p >= n - lo`` (likewise for the tail).
    Frames are processed in blocks of ``lo`` (a block only depends on earlier
    blocks), so the loop runs ``n / lo`` times.
    """
    band = hi - lo + 1
    d = np.arange(lo, hi + 1)
    V0 = np.full((n, band), np.inf)  # chains of one period (start states)
    t0 = np.arange(lo)[:, None]
    t1 = t0 + d[None, :]  # first pairs (t0, t0 + d)
    ok0 = t1 <= n - 1
    V0[t1[ok0], np.broadcast_to(np.arange(band), t1.shape)[ok0]] = 0.0
    V1 = np.full((n, band), np.inf)  # chains of >= 2 periods (at least one edge)
    ptr = np.full((n, band), -1, dtype=np.int64)
    from_start = np.zeros((n, band), dtype=bool)
    Vb = V0.copy()  # min(V0, V1), final once its block is done
    for start in range(lo, n, lo):
        b = np.arange(start, min(start + lo, n))
        prev = b[:, None] - d[None, :]  # (m, band_i1): middle boundary
        ok = prev >= lo
        pc = np.where(ok, prev, 0)
        # total[m, i1, i0] = Vb[prev, i0] + cost[prev, i0, i1]
        total = Vb[pc] + (cost[pc, :, np.arange(band)[None, :]] - reward)
        total = np.where(ok[..., None], total, np.inf)
        best = np.argmin(total, axis=2)
        V1[b] = np.take_along_axis(total, best[..., None], axis=2)[..., 0]
        ptr[b] = best
        from_start[b] = V0[b] <= V1[b]
        Vb[b] = np.minimum(V0[b], V1[b])
    tail = V1[n - lo :]  # candidates for the virtual end node
    flat = int(np.argmin(tail))
    end, i = n - lo + flat // band, flat % band
    value = float(V1[end, i])
    if not np.isfinite(value):
        raise ParameterError(
            "the clip is too short for two periods within the alpha band (internal)"
        )
    frames = [end]
    b = end
    while True:  # (b, i) is a state of V1
        i_prev = int(ptr[b, i])
        b_prev = b - (lo + i)
        frames.append(b_prev)
        if from_start[b_prev, i_prev]:
            frames.append(b_prev - (lo + i_prev))
            break
        b, i = b_prev, i_prev
    frames = np.array(frames[::-1], dtype=np.int64)
    if frames[0] >= lo or frames.size < 3:
        raise ParameterError("internal error: optimal path does not start in the lead-in")
    return frames, value + reward * (frames.size - 2)


def _min_mean_energy(solve: Any, max_iter: int = 30) -> tuple[np.ndarray, float]:
    """Dinkelbach iteration: the segmentation minimising ``E / (p - 1)``.

    ``solve(reward)`` returns the frames and energy ``E`` of ``argmin E - reward (p-1)``.
    Starting from ``reward = 0`` (plain ``argmin E``), the reward is set to the mean
    energy per pair of the current solution until it no longer decreases (a few DP
    passes). With a fixed period count this is the paper's ``argmin E``; with free
    ends it stops the optimum from dropping a period at an end just to have one term
    fewer.
    """
    frames, energy = solve(0.0)
    ratio = energy / (frames.size - 2)
    for _ in range(max_iter):
        f_new, e_new = solve(ratio)
        r_new = e_new / (f_new.size - 2)
        if r_new >= ratio - 1e-12:
            break
        frames, energy, ratio = f_new, e_new, r_new
    return frames, energy


def _count_windows(n: int, lo: int, hi: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Feasible frames ``first[k] .. last[k]`` of boundary ``t_k`` (k = 0..count).

    From the start (``t_0 < lo``, periods of ``lo..hi`` frames) and from the end
    (``n - lo <= t_count <= n - 1``).
    """
    k = np.arange(count + 1)
    first = np.maximum(k * lo, (n - lo) - (count - k) * hi)
    last = np.minimum(lo - 1 + k * hi, (n - 1) - (count - k) * lo)
    return first, last


def _shortest_path_count(
    cost: np.ndarray, n: int, lo: int, hi: int, count: int
) -> tuple[np.ndarray, float]:
    """DP of :func:`_shortest_path` constrained to exactly ``count`` periods (eqs. 4-5).

    Layer ``k`` holds ``V_k[b, i]``, the least energy of a chain of ``k`` periods ending
    at frame ``b`` whose last period has ``lo + i`` frames, for the frames ``b`` where
    boundary ``t_k`` can lie (:func:`_count_windows`; same free ends: ``t_0 < lo``,
    ``t_p >= n - lo``). With the count fixed, ``argmin E`` is the paper's objective (no
    Dinkelbach iteration needed).

    Raises
    ------
    ParameterError
        ``count`` periods of ``lo..hi`` frames do not fit the clip.
    """
    band = hi - lo + 1
    d = np.arange(lo, hi + 1)
    i1 = np.arange(band)[None, :]
    first, last = _count_windows(n, lo, hi, count)
    if np.any(first > last):
        raise ParameterError(
            f"{count} periods of {lo}-{hi} frames (the alpha band) do not fit in {n} frames "
            f"with a lead-in and a tail shorter than {lo} frames; check n_periods (the period "
            "count, not a period length) or increase alpha"
        )
    b = np.arange(first[1], last[1] + 1)
    start = b[:, None] - d[None, :]
    V = np.where((start >= first[0]) & (start <= last[0]), 0.0, np.inf)  # layer 1
    ptrs = []
    for k in range(2, count + 1):
        b_all = np.arange(first[k], last[k] + 1)
        Vk = np.full((b_all.size, band), np.inf)
        pk = np.zeros((b_all.size, band), dtype=np.int32)
        rows = max(1, int(_DP_BLOCK_ELEMENTS // (band * band)))
        for s0 in range(0, b_all.size, rows):
            b = b_all[s0 : s0 + rows]
            prev = b[:, None] - d[None, :]  # (m, band_i1): middle boundary t_{k-1}
            ok = (prev >= first[k - 1]) & (prev <= last[k - 1])
            pc = np.clip(prev, first[k - 1], last[k - 1])
            # total[m, i1, i0] = V_{k-1}[prev, i0] + cost[prev, i0, i1]
            total = V[pc - first[k - 1]] + cost[pc, :, i1]
            total[~ok] = np.inf
            best = np.argmin(total, axis=2)
            Vk[s0 : s0 + b.size] = np.take_along_axis(total, best[..., None], axis=2)[..., 0]
            pk[s0 : s0 + b.size] = best
        V = Vk
        ptrs.append(pk)
    flat = int(np.argmin(V))
    value = float(V.flat[flat])
    if not np.isfinite(value):
        raise ParameterError(
            f"{count} periods of {lo}-{hi} frames (the alpha band) do not fit in {n} frames "
            f"with a lead-in and a tail shorter than {lo} frames; check n_periods (the period "
            "count, not a period length) or increase alpha"
        )
    b, i = first[count] + flat // band, flat % band
    frames = [int(b)]
    for k in range(count, 1, -1):
        i_prev = int(ptrs[k - 2][b - first[k], i])
        b = b - (lo + i)
        frames.append(int(b))
        i = i_prev
    frames.append(int(b - (lo + i)))
    return np.array(frames[::-1], dtype=np.int64), value


def _coarse_band(lo: int, hi: int, factor: int) -> tuple[int, int]:
    """Period band [coarse frames] at 1/``factor`` of the rate, inside ``[lo, hi]`` if possible."""
    lo_c, hi_c = -(-lo // factor), hi // factor
    if lo_c > hi_c:
        lo_c, hi_c = lo // factor, -(-hi // factor)
    return lo_c, hi_c


def _search_bytes(n: int, lo: int, hi: int, n_ch: int, count: int | None) -> float:
    """Estimated peak memory [bytes] of the exact search (kernels, edge costs, DP)."""
    band = hi - lo + 1
    nq = band * band
    kernels = 8.0 * nq * (hi + 1) * (2 * (band + 2) + 6)  # H (dense and stacked), U, G
    chunk = max(16.0, _CHUNK_ELEMENTS / (n_ch * (hi + 1)))
    blocks = 3 * 4.0 * n_ch * chunk * nq  # float32 block products
    costs = 11.0 * n * nq  # float64 cost table and its validity masks
    if count is None:
        dp = 8.0 * 4 * lo * nq + 8.0 * 6 * n * band
    else:
        first, last = _count_windows(n, lo, hi, count)
        states = float(np.clip(last - first + 1, 0, None).sum()) * band
        dp = 12.0 * states + 24.0 * min(_DP_BLOCK_ELEMENTS, n * nq)
    return kernels + blocks + costs + dp


def _decimate(x: np.ndarray, factor: int) -> np.ndarray:
    """Box-filtered, every ``factor``-th frame (coarse frame ``k`` is frame ``k * factor``)."""
    from scipy.ndimage import uniform_filter1d

    xs = uniform_filter1d(x, size=factor, axis=1, mode="nearest")[:, ::factor]
    xs = xs - xs.mean(axis=1, keepdims=True)
    return xs / np.maximum(xs.std(axis=1, keepdims=True), 1e-12)


def _refine(
    x: np.ndarray, guess: np.ndarray, lo: int, hi: int, radius: int
) -> tuple[np.ndarray, float]:
    """Exact ``argmin E`` at full rate with each boundary within ``radius`` of ``guess``.

    A DP over the boundary index (states: pairs of candidate frames for consecutive
    boundaries), keeping the count, the band ``lo..hi`` and the free-end rules.
    """
    n = x.shape[1]
    p = guess.size - 1
    off = np.arange(-radius, radius + 1)
    cands = []
    for i, g in enumerate(guess):
        c = np.unique(np.clip(g + off, 0, n - 1))
        if i == 0:
            c = c[c < lo]
        if i == p:
            c = c[c >= n - lo]
        cands.append(c)
    length = cands[1][None, :] - cands[0][:, None]
    S = np.where((length >= lo) & (length <= hi), 0.0, np.inf)  # S[u, v]
    ptrs = []
    for i in range(2, p + 1):
        U, Vv, W = np.meshgrid(cands[i - 2], cands[i - 1], cands[i], indexing="ij")
        ok = np.isfinite(S)[:, :, None] & (W - Vv >= lo) & (W - Vv <= hi)
        c = np.full(U.shape, np.inf)
        if ok.any():
            c[ok] = _pair_costs(x, U[ok], Vv[ok], W[ok])
        total = S[:, :, None] + c
        arg = np.argmin(total, axis=0)  # (v, w) -> u
        S = np.take_along_axis(total, arg[None], axis=0)[0]
        ptrs.append(arg)
    flat = int(np.argmin(S)) if S.size else 0
    if not S.size or not np.isfinite(S.flat[flat]):
        raise ParameterError(
            "internal error: no full-rate segmentation near the decimated optimum fits the "
            "alpha band; try a lower fps or another period_range"
        )
    iv, iw = divmod(flat, S.shape[1])
    idx = [iw, iv]  # boundary indices p, p-1, ...
    for arg in reversed(ptrs):
        idx.append(int(arg[idx[-1], idx[-2]]))
    idx = idx[::-1]
    frames = np.array([cands[i][j] for i, j in enumerate(idx)], dtype=np.int64)
    return frames, float(S.flat[flat])


def _optimum(x: np.ndarray, lo: int, hi: int, count: int | None) -> tuple[np.ndarray, float, int]:
    """Optimal boundary frames, energy and the search decimation factor.

    If the exact search at full rate fits :data:`SEARCH_MEMORY_BUDGET`, it is run as is
    (factor 1). Otherwise the signal is decimated in time by the smallest integer
    factor ``f`` whose search fits (box filter of ``f`` frames, every ``f``-th frame,
    band ``ceil(lo/f)..floor(hi/f)``), the optimum is found on it, and every boundary
    is then refined at full rate within ``+-f`` frames (exact ``argmin E`` for the
    count found, float64 costs), re-centring the window until the energy stops
    decreasing. This is a local refinement: the result equals the full-rate optimum
    whenever that lies within the window (on the synthetic tests: the same boundaries).
    """
    n_ch, n = x.shape

    def search(xx: np.ndarray, lo_: int, hi_: int) -> tuple[np.ndarray, float]:
        nn = xx.shape[1]
        cost = _edge_costs(xx, lo_, hi_, dtype=_FAST_DTYPE)
        if count is None:
            return _min_mean_energy(lambda r: _shortest_path(cost, nn, lo_, hi_, r))
        return _shortest_path_count(cost, nn, lo_, hi_, count)

    if _search_bytes(n, lo, hi, n_ch, count) <= SEARCH_MEMORY_BUDGET:
        frames, energy = search(x, lo, hi)
        return frames, energy, 1
    factor = 2
    while True:
        lo_c, hi_c = _coarse_band(lo, hi, factor)
        n_c = (n - 1) // factor + 1
        if lo_c < 2:
            raise ParameterError(
                f"the period of ~{(lo + hi) / 2:.0f} frames (band {lo}-{hi}) needs more than "
                f"{SEARCH_MEMORY_BUDGET / 2**20:.0f} MiB to search and cannot be decimated "
                "further; give a lower --fps or a shorter --period-range / more periods"
            )
        if _search_bytes(n_c, lo_c, hi_c, n_ch, count) <= SEARCH_MEMORY_BUDGET:
            break
        factor += 1
    frames_c, _ = search(_decimate(x, factor), lo_c, hi_c)
    frames, energy = _refine(x, frames_c * factor, lo, hi, radius=factor)
    for _ in range(_MAX_REFINE_PASSES):  # re-centre the window until it no longer moves
        f_new, e_new = _refine(x, frames, lo, hi, radius=factor)
        if e_new >= energy - 1e-12:
            break
        frames, energy = f_new, e_new
    return frames, energy, factor


def _literal_edge_cost(x: np.ndarray, t0: int, t1: int, t2: int) -> float:
    """Eqs. 1-2 for one pair of consecutive periods, written out with loops."""
    n_ch = x.shape[0]
    d0, d1 = t1 - t0, t2 - t1
    e = 0.0
    for ch in range(n_ch):
        a_seg = x[ch, t0 : t1 + 1]
        b_seg = np.interp(np.arange(d0 + 1) * (d1 / d0), np.arange(d1 + 1), x[ch, t1 : t2 + 1])
        ma, mb = a_seg.mean(), b_seg.mean()
        num = 0.0
        va = _FLAT_REL_VAR * (d0 + 1)
        vb = _FLAT_REL_VAR * (d0 + 1)
        for k in range(d0 + 1):
            num += (a_seg[k] - ma) * (b_seg[k] - mb)
            va += (a_seg[k] - ma) ** 2
            vb += (b_seg[k] - mb) ** 2
        e += 1.0 - num / np.sqrt(va * vb)
    return e


def _segment_literal(
    x: np.ndarray, lo: int, hi: int, reward: float | None = None
) -> tuple[np.ndarray, float]:
    """Reference: direct, loop-by-loop implementation of eqs. 1-5 (no vectorisation).

    Builds every edge of the DAG of boundary pairs with one Python loop per edge, per
    channel and per sample (:func:`_literal_edge_cost`: resampling with ``np.interp``
    and the Pearson correlation written out), once; then relaxes the edges in
    topological order with Python loops. Same optimum as the fast path; used by the
    tests and by ``benchmarks/bench_segment.py`` as the baseline.

    Parameters
    ----------
    x : np.ndarray [shape=(C, n)]
        Standardised channels (see :func:`_standardise`).
    lo, hi : int [frames]
        Alpha band of period lengths.
    reward : float or None
        Solve ``argmin E - reward (p - 1)`` (0: the plain ``argmin E``); ``None``: the
        Dinkelbach iteration of :func:`_min_mean_energy` (the objective of
        :func:`segment`), reusing the edge costs.

    Returns
    -------
    boundary frames, energy E
    """
    n = x.shape[1]
    edges: dict[tuple[int, int, int], float] = {}
    for t1 in range(lo, n):  # every edge (t0, t1) -> (t1, t2) of the DAG
        for t0 in range(max(t1 - hi, 0), t1 - lo + 1):
            for t2 in range(t1 + lo, min(t1 + hi, n - 1) + 1):
                edges[(t0, t1, t2)] = _literal_edge_cost(x, t0, t1, t2)
    solve = lambda r: _literal_dp(edges, n, lo, hi, r)  # noqa: E731
    if reward is None:
        return _min_mean_energy(solve)
    return solve(reward)


def _literal_dp(
    edges: dict[tuple[int, int, int], float], n: int, lo: int, hi: int, reward: float
) -> tuple[np.ndarray, float]:
    """Shortest path over the DAG of boundary pairs with plain loops (eqs. 4-5)."""
    start: set[tuple[int, int]] = set()
    for t0 in range(lo):  # first pairs (t0, t1): lead-in shorter than any period
        for t1 in range(t0 + lo, min(t0 + hi, n - 1) + 1):
            start.add((t0, t1))
    best: dict[tuple[int, int], float] = {}  # chains with at least one edge
    back: dict[tuple[int, int], tuple[int, int]] = {}
    for t1 in range(lo, n):  # topological order: by middle boundary
        for t0 in range(t1 - hi, t1 - lo + 1):
            here = min(0.0 if (t0, t1) in start else np.inf, best.get((t0, t1), np.inf))
            if not np.isfinite(here):
                continue
            for t2 in range(t1 + lo, min(t1 + hi, n - 1) + 1):
                cand = here + edges[(t0, t1, t2)] - reward
                if cand < best.get((t1, t2), np.inf):
                    best[(t1, t2)] = cand
                    back[(t1, t2)] = (t0, t1)
    ends = [(k, v) for k, v in best.items() if k[1] >= n - lo]  # tail shorter than lo
    if not ends:
        raise ParameterError("no segmentation into two or more periods fits the alpha band")
    node, energy = min(ends, key=lambda kv: kv[1])
    frames = [node[1], node[0]]
    while True:
        prev = back[node]
        frames.append(prev[0])
        if prev in start and (prev not in best or 0.0 <= best[prev]):
            break
        node = prev
    frames_arr = np.array(frames[::-1], dtype=np.int64)
    return frames_arr, float(energy) + reward * (frames_arr.size - 2)


def _band(nominal: float, alpha: float) -> tuple[int, int]:
    """Whole-frame period lengths allowed around ``nominal`` [frames] (eq. 3).

    The band ``[(1-alpha) L, (1+alpha) L]`` is rounded outward to whole frames, so a
    period that is within alpha before rounding to frames is never excluded.
    """
    return int(np.floor((1 - alpha) * nominal + 1e-9)), int(np.ceil((1 + alpha) * nominal - 1e-9))


def segmentation_energy(x: np.ndarray, frames: np.ndarray) -> float:
    """Energy E (eq. 2) of given boundary frames on standardised channels ``(C, n)``."""
    frames = np.asarray(frames, dtype=np.int64)
    if frames.size < 3:
        return 0.0
    return float(_pair_costs(x, frames[:-2], frames[1:-1], frames[2:]).sum())


# ------------------------------------------------------------------- period count


def _check_enough(n: int, fps: float, period_range: tuple[float, float]) -> None:
    span = float(frames_to_time(n - 1, fps=fps))
    if span < 2 * period_range[0]:
        raise ParameterError(
            f"clip of {n} frames lasts {span:.3f} s at fps={fps:g}, shorter than two periods "
            f"of the shortest requested period {period_range[0]:g} s; give a longer clip, a "
            "shorter --period-range, or check fps (frames vs seconds)"
        )


def _uniform_frames(n: int, period: float) -> np.ndarray:
    """Uniform boundaries 0, L, 2L, ... (rounded) that fit in frames 0..n-1."""
    count = int(np.floor((n - 1) / period + 1e-9))
    return np.rint(np.arange(count + 1) * period).astype(np.int64)


def _uniform_energy(x: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Mean Pearson distance per channel and pair of uniform segmentations (NaN if < 2)."""
    n_ch, n = x.shape
    a_l, b_l, c_l, owner = [], [], [], []
    for i, per in enumerate(periods):
        f = _uniform_frames(n, float(per))
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
    costs = _pair_costs(x, np.concatenate(a_l), np.concatenate(b_l), np.concatenate(c_l))
    tot = np.bincount(own, weights=costs, minlength=len(periods))
    cnt = np.bincount(own, minlength=len(periods))
    ok = cnt > 0
    out[ok] = tot[ok] / (cnt[ok] * n_ch)
    return out


def _estimate_period(
    x: np.ndarray, fps: float, period_range: tuple[float, float], method: str
) -> float:
    """Nominal period [frames] by FFT peak or by the uniform-segmentation energy."""
    n = x.shape[1]
    lo_p, hi_p = time_to_frames(period_range, fps=fps, round_to_int=False)  # [frames]
    lo_f = max(float(lo_p), 2.0)
    hi_f = min(float(hi_p), (n - 1) / 2.0)
    if hi_f < lo_f:
        raise ParameterError(
            f"no period of {period_range[0]:g}-{period_range[1]:g} s fits twice in "
            f"{float(frames_to_time(n - 1, fps=fps)):.3f} s at fps={fps:g}; widen period_range "
            "or give a longer clip"
        )
    if method == "fft":
        nfft = int(2 ** np.ceil(np.log2(8 * n)))
        spec = np.abs(np.fft.rfft(x * np.hanning(n)[None, :], n=nfft, axis=1)) ** 2
        power = spec.sum(axis=0)
        freqs = np.fft.rfftfreq(nfft, d=1.0)  # [1/frame]
        band = (freqs >= 1.0 / hi_f) & (freqs <= 1.0 / lo_f)
        if not band.any():
            raise ParameterError("period_range too narrow for the FFT resolution")
        return float(1.0 / freqs[band][np.argmax(power[band])])
    if method != "energy":
        raise ParameterError(f"period_method={method!r}: choose one of {_PERIOD_METHODS}")
    step = 0.25  # [frames]
    count = int(np.floor((hi_f - lo_f) / step)) + 1
    if count > _MAX_COUNT_CANDIDATES:
        cands = np.geomspace(lo_f, hi_f, _MAX_COUNT_CANDIDATES)
    else:
        cands = lo_f + step * np.arange(count)
    e = _uniform_energy(x, cands)
    if np.all(np.isnan(e)):
        raise ParameterError("clip too short for two periods of the requested range")
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


def estimate_period_count(
    values: Any,
    *,
    fps: float,
    period_range: tuple[float, float] = (0.25, 1.25),
    method: str = "energy",
) -> int:
    """Number of whole periods ``p`` in a clip, by FFT peak or uniform-segmentation energy.

    Parameters
    ----------
    values : np.ndarray [shape=(n_frames, n_channels)]
        Channels to analyse (near-constant channels are ignored).
    fps : float > 0 [Hz]
    period_range : (float, float) [s]
        Shortest and longest period considered (paper: 0.25-1.25 s).
    method : {"energy", "fft"}
        ``"fft"``: the peak of the channel-summed power spectrum (z-scored channels,
        Hann window, 8x zero padding) within ``1/period_range``. ``"energy"``: the
        period ``T`` minimising the energy of the uniform segmentation ``0, T, 2T, ...``
        per pair of consecutive periods (``E(U) / (s - 1)``; the paper writes ``E/s``,
        which favours fewer, longer periods on short clips), over a 0.25-frame grid
        (at most 400 log-spaced candidates). If the minimum lies at the short end of
        the range (where short windows of a slow signal correlate trivially), the
        lowest interior local minimum is taken instead (if any).

    Returns
    -------
    int >= 2
        ``floor((n_frames - 1) / (T * fps))``.

    Raises
    ------
    ParameterError
        Bad ``fps``/range/values, or a clip shorter than two of the shortest periods.
    """
    fps = check_fps(fps)
    lo_s, hi_s = check_range(*period_range, name="period_range", unit="s")
    vals = _as_values(values)
    n = vals.shape[0]
    _check_enough(n, fps, (lo_s, hi_s))
    keep = _nonconstant(vals)
    if not keep.any():
        raise ParameterError("every channel is constant: there is no motion to segment")
    x = _standardise(vals[:, keep])
    per = _estimate_period(x, fps, (lo_s, hi_s), method)
    return max(2, int(np.floor((n - 1) / per + 1e-9)))


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
    e = _uniform_energy(xs, period * np.array((1.0,) + _OFF_PERIOD_FACTORS))
    if np.isnan(e[0]) or np.all(np.isnan(e[1:])):
        return float("nan")
    return float(np.nanmin(e[1:]) - e[0])


# --------------------------------------------------------------------------- public


def _as_values(values: Any) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError("values must be a numeric array (n_frames, n_channels)") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise ParameterError(f"values must be 2-D (n_frames, n_channels), got shape {arr.shape}")
    if arr.shape[0] < 3:
        raise ParameterError(f"values have {arr.shape[0]} frame(s); a segmentation needs more")
    return check_finite(arr, name="motion values")


def _check_alpha(alpha: Any) -> float:
    try:
        a = float(alpha)
    except (TypeError, ValueError):
        raise ParameterError(f"alpha={alpha!r} is not a number in (0, 0.5)") from None
    if not (np.isfinite(a) and 0.0 < a < 0.5):
        hint = " (a fraction of the period, e.g. 0.1, not a percentage)" if a >= 0.5 else ""
        raise ParameterError(f"alpha={alpha!r} must be in (0, 0.5){hint}")
    return a


def segment_values(
    values: Any,
    *,
    fps: float,
    alpha: float = 0.1,
    n_periods: int | None = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    period_method: str = "energy",
    channel_names: Sequence[str] | None = None,
) -> Segmentation:
    """Globally optimal segmentation of a periodic multi-channel signal (paper A, sec. 3).

    Parameters
    ----------
    values : np.ndarray [shape=(n_frames, n_channels)]
        Joint angles (any unit; each channel is z-scored, which leaves r unchanged).
        Angles must already be unwrapped (:func:`segment` does it for BVH rotations).
    fps : float > 0 [Hz]
    alpha : float in (0, 0.5)
        Allowed relative deviation of every period from the nominal period (eq. 3).
    n_periods : int >= 2, optional
        Number of periods (e.g. from the music). Overrides ``period_method``; the result
        then has exactly this many periods, each within the alpha band around
        ``(n_frames - 1) / n_periods`` frames (or a ParameterError if they do not fit
        or the forced segmentation is not periodic).
    period_range : (float, float) [s]
        Shortest and longest period for estimating the count (paper: 0.25-1.25 s).
    period_method : {"energy", "fft", "given"}
        How to get the count when ``n_periods`` is None (see
        :func:`estimate_period_count`). ``"given"`` requires ``n_periods``.
    channel_names : sequence of str, optional
        Names of the columns (reported in :attr:`Segmentation.channels`).

    Returns
    -------
    Segmentation

    Raises
    ------
    ParameterError
        NaN/inf values, ``fps <= 0``, alpha outside (0, 0.5), reversed period range, a
        clip shorter than two periods of the requested range, all channels constant,
        ``n_periods`` periods that do not fit the clip within the alpha band, or a
        clip that is not periodic (normalised energy above
        :data:`MAX_NORMALISED_ENERGY`; with ``n_periods`` given, often a wrong count).

    Examples
    --------
    >>> from beatsync.synth.motion import periodic_motion
    >>> s = periodic_motion(n_frames=300, n_periods=10, snr_db=30, seed=1)
    >>> seg = segment_values(s.motion.values, fps=25, n_periods=10)
    >>> int(abs(seg.boundary_frames - s.boundary_frames).max()) <= 1
    True
    """
    fps = check_fps(fps)
    alpha = _check_alpha(alpha)
    lo_s, hi_s = check_range(*period_range, name="period_range", unit="s")
    if period_method not in _PERIOD_METHODS:
        raise ParameterError(f"period_method={period_method!r}: choose one of {_PERIOD_METHODS}")
    vals = _as_values(values)
    n = vals.shape[0]
    names = (
        tuple(str(c) for c in channel_names)
        if channel_names is not None
        else tuple(f"ch{i}" for i in range(vals.shape[1]))
    )
    if len(names) != vals.shape[1]:
        raise ParameterError(
            f"{len(names)} channel names for {vals.shape[1]} value columns; is the array "
            "transposed (it must be frames x channels)?"
        )
    keep = _nonconstant(vals)
    if not keep.any():
        raise ParameterError(
            "every selected channel is constant: there is no motion to segment "
            "(choose other channels, e.g. channels='all')"
        )
    used = tuple(nm for nm, k in zip(names, keep, strict=False) if k)
    x = _standardise(vals[:, keep])

    if n_periods is not None:
        try:
            p = int(n_periods)
        except (TypeError, ValueError):
            raise ParameterError(f"n_periods={n_periods!r} must be an integer >= 2") from None
        if p != n_periods or p < 2:
            raise ParameterError(f"n_periods={n_periods!r} must be an integer >= 2")
        method = "given"
        nominal = (n - 1) / p  # [frames]
    else:
        if period_method == "given":
            raise ParameterError("period_method='given' needs n_periods (the period count)")
        _check_enough(n, fps, (lo_s, hi_s))
        nominal = _estimate_period(x, fps, (lo_s, hi_s), period_method)
        method = period_method
        p = max(2, int(np.floor((n - 1) / nominal + 1e-9)))
    lo, hi = _band(nominal, alpha)
    if lo < 2:
        raise ParameterError(
            f"{p} periods in {n} frames is {nominal:.2f} frames per period: too short to "
            "segment (need >= 2 frames per period); fewer periods or a higher frame rate"
        )
    if lo > hi:
        raise ParameterError(
            f"alpha={alpha:g} allows no whole-frame period length around {nominal:.2f} "
            "frames; increase alpha"
        )
    frames, energy, factor = _optimum(x, lo, hi, p if method == "given" else None)
    n_found = frames.size - 1
    e_norm = energy / (x.shape[0] * max(n_found - 1, 1))
    contrast = periodicity_contrast(x, frames)
    if e_norm >= MAX_NORMALISED_ENERGY or (
        np.isfinite(contrast) and contrast < MIN_PERIODICITY_CONTRAST
    ):
        hint = ""
        if method == "given":
            try:
                est = _estimate_period(x, fps, (lo_s, hi_s), "energy")
                hint = (
                    f"; n_periods={p} was given: is it right? The energy estimate of the "
                    f"count in {lo_s:g}-{hi_s:g} s periods is "
                    f"{max(2, int(np.floor((n - 1) / est + 1e-9)))}"
                )
            except ParameterError:
                hint = f"; n_periods={p} was given: check the count"
        raise ParameterError(
            f"the motion is not periodic: the best segmentation into {n_found} periods of "
            f"~{float(frames_to_time((frames[-1] - frames[0]) / n_found, fps=fps)):.3f} s has "
            f"mean Pearson distance "
            f"{e_norm:.3f} between consecutive periods, and uniform segmentations at this "
            f"period beat those at wrong periods by only {contrast:.3f} (periodic needs "
            f"< {MAX_NORMALISED_ENERGY} and a "
            f"contrast >= {MIN_PERIODICITY_CONTRAST}); no boundaries are reported. Try other "
            "channels, another period_range, or a clip with repeated movement" + hint
        )
    times = frames_to_time(frames, fps=fps)
    return Segmentation(
        boundaries=times,
        n_periods=int(n_found),
        mean_period=float((times[-1] - times[0]) / n_found),
        energy=float(energy),
        channels=used,
        fps=fps,
        period_method=method,
        search_decimation=factor,
    )


def _unwrap_rotations(values: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """Unwrap rotation channels [deg] across the +-180 wrap (analysis only)."""
    rot = [i for i, nm in enumerate(names) if nm.lower().endswith("rotation")]
    if not rot:
        return values
    out = values.copy()
    out[:, rot] = np.unwrap(values[:, rot], axis=0, period=360.0)
    return out


def segment(
    motion: Motion,
    *,
    alpha: float = 0.1,
    n_periods: int | None = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    period_method: str = "energy",
    channels: str | Sequence[str] = "default",
) -> Segmentation:
    """Split a periodic motion into its periods, globally optimally (paper A, sec. 3).

    Parameters
    ----------
    motion : Motion
        Joint angles (BVH rotations, degrees) or marker-derived ``*_angle`` channels
        (:func:`beatsync.motion.marker_angles`).
    alpha : float in (0, 0.5)
        Allowed relative deviation of each period from the nominal period (eq. 3).
    n_periods : int >= 2, optional
        Period count if known (e.g. from the music); the result has exactly this many
        periods (see :func:`segment_values`).
    period_range : (float, float) [s]
        Shortest and longest period when estimating the count.
    period_method : {"energy", "fft", "given"}
    channels : "default", "all" or list of str
        See :func:`select_channels`.

    Returns
    -------
    Segmentation
        ``boundaries`` [s] within ``[0, (n_frames-1)/fps]``; ``mean_period`` [s].

    Raises
    ------
    ParameterError
        See :func:`segment_values`.

    Examples
    --------
    >>> from beatsync.synth.motion import periodic_motion
    >>> s = periodic_motion(n_frames=300, n_periods=10, seed=1)
    >>> seg = segment(s.motion, n_periods=10)
    >>> seg.n_periods, round(seg.mean_period, 3)
    (10, 1.196)
    """
    names = select_channels(motion.channels, channels)
    idx = [motion.channel_index(nm) for nm in names]
    values = check_finite(motion.values[:, idx], name=f"motion {motion.name!r} values")
    values = _unwrap_rotations(values, names)
    return segment_values(
        values,
        fps=motion.fps,
        alpha=alpha,
        n_periods=n_periods,
        period_range=period_range,
        period_method=period_method,
        channel_names=names,
    )


# ---------------------------------------------- evaluation and figures (notebook fig02)


def boundary_errors(estimated: Any, reference: Any, *, remove_offset: bool = False) -> dict:
    """Boundary error [frames] of estimated against reference boundary frames.

    Each reference boundary inside the estimated span is matched to the nearest
    estimated boundary.

    Parameters
    ----------
    estimated, reference : array_like [frames]
    remove_offset : bool
        Subtract the median signed error first (for baselines whose boundaries sit at
        another phase of the cycle, e.g. minima of one angle).

    Returns
    -------
    dict
        ``mean``, ``max`` [frames], ``n_matched``, ``count_error`` (estimated minus
        reference number of periods) and ``offset`` [frames].
    """
    est = np.asarray(estimated, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    if est.size == 0 or ref.size == 0:
        return {"mean": np.nan, "max": np.nan, "n_matched": 0, "count_error": est.size - ref.size,
                "offset": 0.0}  # fmt: skip
    idx = np.clip(np.searchsorted(est, ref), 1, max(est.size - 1, 1))
    left = est[idx - 1]
    right = est[np.minimum(idx, est.size - 1)]
    nearest = np.where(np.abs(ref - left) <= np.abs(ref - right), left, right)
    signed = nearest - ref
    offset = float(np.median(signed)) if remove_offset else 0.0
    if remove_offset:
        shifted = est - offset
        return boundary_errors(shifted, ref) | {"offset": offset}
    inside = (ref >= est[0] - 0.5) & (ref <= est[-1] + 0.5)
    err = np.abs(signed[inside]) if inside.any() else np.abs(signed)
    return {
        "mean": float(err.mean()),
        "max": float(err.max()),
        "n_matched": int(err.size),
        "count_error": int(est.size - ref.size),
        "offset": offset,
    }


def uniform_baseline(
    values: Any,
    *,
    fps: float,
    period_range: tuple[float, float] = (0.25, 1.25),
    method: str = "fft",
) -> np.ndarray:
    """Baseline: one period estimate, uniform boundaries ``0, T, 2T, ...`` [frames].

    Parameters
    ----------
    values : np.ndarray [shape=(n_frames, n_channels)]
    fps : float > 0 [Hz]
    period_range : (float, float) [s]
    method : {"fft", "energy"}
        Period estimate (see :func:`estimate_period_count`).
    """
    fps = check_fps(fps)
    vals = _as_values(values)
    keep = _nonconstant(vals)
    x = _standardise(vals[:, keep])
    per = _estimate_period(x, fps, check_range(*period_range, name="period_range", unit="s"),
                           method)  # fmt: skip
    return _uniform_frames(vals.shape[0], per)


def minima_baseline(signal: Any, *, fps: float, period: float) -> np.ndarray:
    """Baseline: local minima of one joint angle as period boundaries [frames].

    Minima at least ``0.7 * period`` apart (``scipy.signal.find_peaks`` on the negated,
    lightly smoothed signal).

    Parameters
    ----------
    signal : np.ndarray [shape=(n_frames,)]
        One angle, e.g. a knee.
    fps : float > 0 [Hz]
    period : float > 0 [s]
        Expected period (e.g. from :func:`uniform_baseline`'s estimate).
    """
    from scipy.ndimage import uniform_filter1d
    from scipy.signal import find_peaks

    fps = check_fps(fps)
    y = check_finite(np.asarray(signal, dtype=np.float64).ravel(), name="signal")
    dist = max(1, int(time_to_frames(0.7 * float(period), fps=fps, mode="floor")))
    smooth = uniform_filter1d(y, size=max(1, int(time_to_frames(0.05, fps=fps))) | 1)
    peaks, _ = find_peaks(-smooth, distance=dist)
    return peaks.astype(np.int64)


def synthetic_error_table(
    *,
    snr_dbs: Sequence[float | None] = (30.0, 20.0, 10.0, 5.0),
    alphas: Sequence[float] = (0.1, 0.2),
    seeds: Sequence[int] = (0, 1, 2),
    n_frames: int = 750,
    n_channels: int = 29,
    fps: float = 25.0,
    n_periods: int = 25,
    jitter: float = 0.08,
    variation: float = 0.05,
) -> Any:
    """Boundary error vs ground truth over noise levels and alpha (notebook fig02).

    For every SNR, alpha and seed: a :func:`beatsync.synth.motion.periodic_motion`
    signal, segmented (a) by :func:`segment` with the period count estimated
    (``"energy"``), (b) with the count given, and baselines (c) FFT period + uniform
    boundaries and (d) local minima of channel 0 (offset-corrected, see
    :func:`boundary_errors`). Errors in frames, averaged over seeds (``max``: max).

    Returns
    -------
    pandas.DataFrame
        One row per (SNR, alpha, method).
    """
    import pandas as pd

    from .synth.motion import periodic_motion

    rows = []
    for snr in snr_dbs:
        for alpha in alphas:
            per_method: dict[str, list[dict]] = {}
            for seed in seeds:
                s = periodic_motion(n_frames=n_frames, n_channels=n_channels, fps=fps,
                                    n_periods=n_periods, jitter=jitter, variation=variation,
                                    snr_db=snr, seed=seed)  # fmt: skip
                truth = s.boundary_frames
                vals = s.motion.values
                found = {}
                for name, kw in (("optimal, count estimated", {}),
                                 ("optimal, count given", {"n_periods": n_periods})):  # fmt: skip
                    try:
                        seg = segment_values(vals, fps=fps, alpha=alpha, **kw)
                        found[name] = (seg.boundary_frames, False)
                    except ParameterError:
                        found[name] = (np.array([], dtype=np.int64), False)
                uni = uniform_baseline(vals, fps=fps, method="fft")
                found["baseline: FFT period + uniform"] = (uni, False)
                per = float(frames_to_time((uni[-1] - uni[0]) / max(uni.size - 1, 1), fps=fps))
                found["baseline: minima of channel 0"] = (
                    minima_baseline(vals[:, 0], fps=fps, period=per),
                    True,
                )
                for name, (fr, off) in found.items():
                    per_method.setdefault(name, []).append(
                        boundary_errors(fr, truth, remove_offset=off)
                    )
            for name, errs in per_method.items():
                rows.append({
                    "snr_db": snr if snr is not None else np.inf,
                    "alpha": alpha,
                    "method": name,
                    "mean_error_frames": float(np.nanmean([e["mean"] for e in errs])),
                    "max_error_frames": float(np.nanmax([e["max"] for e in errs])),
                    "failed_runs": int(sum(e["n_matched"] == 0 for e in errs)),
                    "count_error": float(np.mean([abs(e["count_error"]) for e in errs])),
                })  # fmt: skip
    return pd.DataFrame(rows)


def plot_segmentation(
    motion: Motion,
    seg: Segmentation,
    channels: Sequence[str],
    *,
    title: str = "",
    truth: Any = None,
    ax: Any = None,
) -> Any:
    """Plot joint angles with the found period boundaries (paper A, Figure 2 style).

    Parameters
    ----------
    motion : Motion
    seg : Segmentation
    channels : sequence of str
        Channels to draw, e.g. left and right knee.
    title : str
    truth : array_like [s], optional
        Ground-truth boundaries, drawn dashed.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(10, 2.8))
    else:
        fig = ax.figure
    t = motion.times
    for name in channels:
        v = motion.values[:, motion.channel_index(name)]
        if name.lower().endswith("rotation"):
            v = np.unwrap(v, period=360.0)
        ax.plot(t, v, lw=1.0, label=name)
    for i, b in enumerate(seg.boundaries):
        ax.axvline(b, color="k", lw=0.8, alpha=0.7, label="found boundaries" if i == 0 else None)
    if truth is not None:
        for i, b in enumerate(np.asarray(truth)):
            ax.axvline(b, color="r", lw=0.8, ls="--", label="ground truth" if i == 0 else None)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("angle [deg]")
    ax.set_title(title or f"{motion.name}: {seg.n_periods} periods, mean {seg.mean_period:.3f} s")
    ax.legend(loc="upper right", fontsize=7, ncol=4)
    return fig
