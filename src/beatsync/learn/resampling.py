"""Exercises of ``notebooks/tutorials/03_resampling.ipynb`` (paper A, section 5), judged
with :mod:`beatsync.sync` on a synthetic periodic motion and a slowing beat."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from . import exercise

__all__ = ["compare_arrays"]


def compare_arrays(
    got: Any,
    expected: np.ndarray,
    *,
    what: str,
    unit: str = "",
    rtol: float = 1e-6,
    atol: float = 0.0,
) -> str | None:
    """None if ``got`` equals ``expected`` (to ``rtol``, ``atol``), else a hint naming the
    mismatch (shape, first element that differs, an offset, factor or sign), never the
    expected values."""
    if got is None:
        return f"{what} returned None: fill in the skeleton."
    try:
        g = np.asarray(got, dtype=np.float64)
    except (TypeError, ValueError):
        return f"{what} returned {type(got).__name__}, not an array of numbers."
    e = np.asarray(expected, dtype=np.float64)
    if g.shape != e.shape:
        return f"{what} has shape {g.shape}; it should have shape {e.shape}."
    scale = max(1.0, float(np.abs(e).max(initial=0)))
    close = np.isclose(g, e, rtol=rtol, atol=max(atol, 1e-9 * scale))
    if close.all():
        return None
    i = int(np.flatnonzero(~close.ravel())[0])
    u = f" {unit}" if unit else ""
    diff = g - e
    if np.allclose(diff, diff.ravel()[i], rtol=rtol, atol=max(atol, 1e-9)):
        return f"{what} is off by a constant{u} everywhere (from element {i} on)."
    if np.allclose(g, -e, rtol=rtol, atol=atol):
        return f"{what} has the wrong sign."
    ratio = g.ravel()[i] / e.ravel()[i] if e.ravel()[i] != 0 else np.inf
    if np.isfinite(ratio) and np.allclose(g, ratio * e, rtol=rtol, atol=atol):
        return f"{what} is off by a constant factor everywhere."
    n_bad = int((~close).sum())
    return f"{what}: element {i} (and {n_bad - 1} more of {e.size}) differs{u}."


@functools.cache
def _case() -> tuple[Any, np.ndarray]:
    """A periodic motion (0.9-1.1 s periods) and beats that slow from 120 to 100 BPM."""
    from ..synth.motion import periodic_motion

    syn = periodic_motion(n_frames=301, fps=30.0, n_periods=10, seed=3, snr_db=None)
    gaps = np.linspace(0.5, 0.6, 40)
    return syn, 0.25 + np.concatenate([[0.0], np.cumsum(gaps)])


@exercise("resampling.landing_beats")
def _landing_beats(answer: Any) -> str | None:
    """``landing_beats(beats, n_periods, m, first_beat)``: the beat of every boundary."""
    from ..sync import synchronize

    syn, beats = _case()
    beats = beats.copy()  # the student's code may change its arguments
    n_periods = syn.boundaries.size - 1
    for m, first in ((2, 0), (3, 1)):
        res = synchronize(syn.motion, syn.boundaries, beats, beats_per_period=m, first_beat=first)
        expected = res.report["target_beats_s"]
        got = answer(beats, n_periods, m, first)
        what = f"landing_beats(beats, {n_periods}, m={m}, first_beat={first})"
        hint = compare_arrays(got, expected, what=what, unit="s")
        if hint is not None:
            got = np.asarray(got, dtype=np.float64).ravel()
            if got.size == expected.size - 1:
                hint += (
                    f" {n_periods} periods have {n_periods + 1} boundaries: the last "
                    "period's end lands on a beat too."
                )
            return hint
    return None


@exercise("resampling.period_rates")
def _period_rates(answer: Any) -> str | None:
    """``period_rates(boundaries, targets)``: r_i of every period (paper A, sec. 5)."""
    from ..sync import time_warp

    syn, beats = _case()
    boundaries, beats = syn.boundaries.copy(), beats.copy()
    targets = beats[: 2 * boundaries.size : 2][: boundaries.size]
    expected = time_warp(boundaries, targets).period_rates
    got = answer(boundaries, targets)
    hint = compare_arrays(got, expected, what="period_rates(boundaries, targets)")
    if hint is None:
        return None
    g = np.asarray(got, dtype=np.float64).ravel()
    if g.shape == expected.shape and np.allclose(g * expected, 1.0, rtol=1e-6):
        return (
            "you returned source duration / music duration, the playback speed; the rate "
            "is music duration / source duration (> 1 slows the dance down)."
        )
    return hint
