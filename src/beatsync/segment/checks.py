"""Validation of the segmentation's arguments (called once, at the public entry).

Each ``check_*`` returns what the user passed in the form the package uses, or raises
:class:`~beatsync.errors.ParameterError` naming the value and the likely mistake.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from ..validation import as_float, as_int, check_choice, check_finite, check_interval
from .period import PERIOD_METHODS

__all__ = [
    "check_values",
    "check_alpha",
    "check_period_range",
    "check_n_periods",
    "check_period_method",
]


def check_values(values: Any) -> np.ndarray:
    """Values as a finite float64 ``(n_frames, n_channels)`` array (1-D: one channel)."""
    arr = check_finite(values, name="motion values")
    arr = arr[:, None] if arr.ndim == 1 else arr
    if arr.ndim != 2:
        raise ParameterError(f"values must be 2-D (n_frames, n_channels), got shape {arr.shape}")
    if arr.shape[0] < 3:
        raise ParameterError(f"values have {arr.shape[0]} frame(s); a segmentation needs more")
    return arr


def check_alpha(alpha: Any) -> float:
    """The alpha of eq. 3: a fraction of the period in (0, 0.5)."""
    a = as_float(alpha, name="alpha", unit="")
    if not 0.0 < a < 0.5:
        hint = " (a fraction of the period, e.g. 0.1, not a percentage)" if a >= 0.5 else ""
        raise ParameterError(f"alpha={alpha!r} must be in (0, 0.5){hint}")
    return a


def check_period_range(period_range: Any) -> tuple[float, float]:
    """Shortest and longest period [s]: two finite numbers, ``0 < lo < hi``."""
    return check_interval(period_range, name="period_range", unit="s")


def check_n_periods(n_periods: Any) -> int | None:
    """A period count: None (estimate it) or an integer >= 2."""
    if n_periods is None:
        return None
    return as_int(n_periods, name="n_periods", minimum=2)


def check_period_method(period_method: Any, n_periods: int | None) -> str:
    """The method actually used: ``"given"`` when a count is given, else the one asked."""
    check_choice(period_method, PERIOD_METHODS, name="period_method")
    if period_method == "given" and n_periods is None:
        raise ParameterError("period_method='given' needs n_periods (the period count)")
    return "given" if n_periods is not None else str(period_method)
