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
  Frames are used only inside this package; conversion goes through
  :func:`beatsync.units.frames_to_time`.

Modules
-------
- :mod:`.core`: the public entry (:func:`segment`, :func:`segment_values`,
  :func:`estimate_period_count`, :class:`Segmentation`); validates once (:mod:`.checks`).
- :mod:`.channels`: which channels (:func:`select_channels`), constant ones dropped,
  rotations unwrapped, z-scored.
- :mod:`.costs`: edge costs, the Pearson distance between consecutive periods
  (eqs. 1-2), vectorised.
- :mod:`.search`: the DP over the forward DAG (eqs. 3-5) and the decimated search.
- :mod:`.period`: period estimation and the periodicity test.
- :mod:`.reference`: the literal loop-by-loop implementation of eqs. 1-5, the
  reference of the tests and of ``benchmarks/bench_segment.py``.

Scores of a segmentation against ground truth are in
:mod:`beatsync.evaluate.segmentation`; the baselines, tables and figure of the
notebook in :mod:`beatsync.study.paper_a_segmentation`.

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
:func:`.costs.edge_costs`). :func:`.reference.segment_literal` is the direct loop implementation of
the same equations, kept as the reference for tests and the benchmark.

Documented rules (choices the paper leaves open)
------------------------------------------------
- Near-constant channels (Pearson undefined): a channel is excluded when its standard
  deviation over the clip is at most ``CONSTANT_REL_STD`` (1e-3) times the largest
  standard deviation among the selected channels, or at most 1e-9. Inside a kept
  channel, a period whose own variance is below 1e-6 of the channel's variance is
  treated as flat: its correlation is ~0 (cost ~1).
- Period range: by default the paper's 0.25-1.25 s (``DEFAULT_PERIOD_RANGE``). Real
  dance cycles can be longer (a waltz box: 6 beats, about 4 s):
  ``DANCE_PERIOD_RANGE`` (0.25-6.25 s) or :func:`period_range_from_beat` (1 to 8 beats
  of the music). A range wider than a factor 5 is searched in tiers of a factor 5,
  shortest first (:func:`.period.period_tiers`); the first tier whose optimum passes
  the periodicity test gives the period, the shortest repeating cycle (otherwise the
  energy estimate prefers multiples of a step: a salsa clip searched over the whole
  range at once comes out as three steps). The wide range is not the default because
  the periodicity test accepts a non-periodic pirouette in the long tier. Long
  periods stay within memory through the decimated search.
- Clip length: a clip shorter than ``MIN_CLIP_PERIODS`` (3) of the shortest period
  of the range is refused first. With the count estimated, a clip shorter than 3 of
  its own estimated period (the optimum then has a single pair of consecutive periods)
  is accepted only if that pair is clearly alike, mean Pearson distance below
  ``SHORT_CLIP_MAX_ENERGY`` (0.5, i.e. mean r above 0.5), else refused as too short.
  Set between short real walks and a short salsa excerpt at a wrong period
  (docs/tuning.md#short-clips). The period is estimated among periods that fit twice
  in the clip. With the count given (``n_periods >= 2``) the caller vouches for it.
- Periodicity: a clip is refused as not periodic when the optimum's mean Pearson
  distance per channel and pair, ``E / (n_channels * (p - 1))``, reaches
  ``MAX_NORMALISED_ENERGY`` (1.0: consecutive periods uncorrelated on average), or
  when its periodicity contrast (:func:`periodicity_contrast`: how much better the
  uniform segmentation at the found period is than uniform segmentations at 0.5,
  0.75, 1.25 and 1.5 times it) is below ``MIN_PERIODICITY_CONTRAST`` (0.05).
  Set between real periodic dances and walks on one side and a pirouette and white
  noise on the other; the margin to real salsa is small, and integrated noise
  (a random walk) can pass (docs/tuning.md#periodicity-check-of-the-segmentation).
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

from .channels import CONSTANT_REL_STD, select_channels
from .core import (
    DANCE_PERIOD_RANGE,
    DEFAULT_PERIOD_RANGE,
    MIN_CLIP_PERIODS,
    SHORT_CLIP_MAX_ENERGY,
    Segmentation,
    estimate_period_count,
    period_range_from_beat,
    segment,
    segment_values,
)
from .costs import segmentation_energy
from .period import MAX_NORMALISED_ENERGY, MIN_PERIODICITY_CONTRAST, periodicity_contrast
from .search import SEARCH_MEMORY_BUDGET

__all__ = [
    "Segmentation",
    "segment",
    "segment_values",
    "estimate_period_count",
    "select_channels",
    "segmentation_energy",
    "periodicity_contrast",
    "period_range_from_beat",
    "DEFAULT_PERIOD_RANGE",
    "DANCE_PERIOD_RANGE",
    "MIN_CLIP_PERIODS",
    "SHORT_CLIP_MAX_ENERGY",
    "CONSTANT_REL_STD",
    "MAX_NORMALISED_ENERGY",
    "MIN_PERIODICITY_CONTRAST",
    "SEARCH_MEMORY_BUDGET",
]
