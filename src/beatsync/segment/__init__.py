"""Optimal temporal segmentation of periodic motion into its periods (paper A, sec. 3).

Panagiotakis, Holzapfel, Michel, Argyros, "Beat synchronous dance animation based on
visual analysis of human motion and audio analysis of music tempo", section 3.
Notebook: ``notebooks/paper_a_fig02_segmentation.ipynb`` (Figure 2 and boundary-error table).

Data contract: motion values ``(n_frames, n_channels)``, time first, at ``fps > 0``
[Hz], rotation channels in degrees (unwrapped across +-180 deg before analysis). The
result's ``boundaries`` are ``n_periods + 1`` strictly increasing times [s] within
``[0, (n_frames - 1) / fps]``: lead-in and tail shorter than a period are left out.
Inside the package the channels are z-scored and channel-first ``(C, n)`` and every
period and boundary is in frames.

Modules: :mod:`.core` (the public entry, validates once via :mod:`.checks`),
:mod:`.channels` (channel choice), :mod:`.costs` (edge costs, eqs. 1-2),
:mod:`.search` (the DP, eqs. 3-5), :mod:`.period` (period estimate, periodicity
test), :mod:`.reference` (the literal loop implementation: the tests' reference).

The method
----------
A segmentation ``T_p = (t_0 < t_1 < ... < t_p)`` (frames) splits the signal
into periods ``S_i = X[t_i .. t_{i+1}]`` (both ends included). Its energy (eqs. 1-2) is

    E(T_p) = sum_{i=1}^{p-1} sum_c  1 - r( S_{i-1,c}, resample(S_{i,c}, len(S_{i-1})) )

with ``r`` the Pearson correlation and ``resample`` linear interpolation of the later
period onto the earlier one's samples (end points aligned). Every period length stays
in the alpha band around the nominal period ``L`` (eq. 3; ``L = (n-1)/p`` for a given
count, else the estimated period): ``(1-alpha) L <= t_{i+1} - t_i <= (1+alpha) L``.
The optimal ``T_p`` (eqs. 4-5) is a shortest path in a forward DAG whose nodes are
consecutive boundary pairs ``(t_{i-1}, t_i)``, solved by DP in frame order. With the
count given the DP carries it in its state (``argmin E``, as in the paper); with the
count estimated the optimum minimises ``E / (p - 1)`` (Dinkelbach iteration), since
``E`` itself would favour one period fewer.

Choices the paper leaves open are the constants below, each documented where it is
defined (calibration in ``docs/tuning.md``). Free ends: ``t_0`` in the lead-in
(``t_0 < lo``, the shortest allowed period) and ``t_p`` in the tail (``t_p >= n - lo``);
a period range wider than a factor 5 is searched in tiers, shortest first.
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
