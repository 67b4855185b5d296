"""Exercises of ``notebooks/tutorials/01_segmentation.ipynb`` (paper A, sec. 3), judged
with :mod:`beatsync.segment` on the CMU salsa take 60_01."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from .. import datasets
from ..segment import segmentation_energy
from ..segment.channels import standardise, unwrap_rotations
from ..segment.period import estimate_period
from . import exercise

__all__ = ["judge_pearson_distance", "judge_energy", "judge_fft_period"]

KNEES = ("lShin_Xrotation", "rShin_Xrotation")
#: boundary triples (earlier period a..b, later b..c) [frames at 60 fps], of unequal lengths
TRIPLES = ((100, 160, 219), (300, 355, 420), (1000, 1062, 1120))


@functools.cache
def _salsa() -> tuple[np.ndarray, np.ndarray]:
    """Salsa 60_01: the knees [deg] ``(n, 2)``, the z-scored default channels ``(C, n)``."""
    from ..segment import select_channels

    m = datasets.load_salsa("60_01")
    knees = unwrap_rotations(m.select(list(KNEES)).values, KNEES)
    names = select_channels(m.channels)
    vals = unwrap_rotations(m.select(list(names)).values, names)
    return knees, standardise(vals[:, vals.std(axis=0) > 1e-9])


def _number(value: Any, what: str) -> float | str:
    arr = np.asarray(value)
    if arr.shape != ():
        return f"return one number ({what}), not an array of shape {arr.shape}."
    if not np.isfinite(arr):
        return f"your {what} is {float(arr)}: is a period flat, or a length zero?"
    return float(arr)


@exercise("segmentation.pearson_distance")
def judge_pearson_distance(pearson_distance: Any) -> str | None:
    """``pearson_distance(a, b)``: eq. 1, ``1 - r(a, b resampled onto len(a))``."""
    knees, _ = _salsa()
    x = knees[:, 1]
    for a, b, c in TRIPLES:
        first, later = x[a : b + 1].copy(), x[b : c + 1].copy()
        got = _number(pearson_distance(first, later), "the distance")
        if isinstance(got, str):
            return got
        want = segmentation_energy(((x - x.mean()) / x.std())[None, :], np.array([a, b, c]))
        if abs(got - want) < 1e-4:
            continue
        where = f"periods of {b - a + 1} and {c - b + 1} samples (frames {a}-{b}-{c})"
        if abs(got - (1 - want)) < 1e-4:
            return f"for the {where} you returned the correlation r: the distance is 1 - r."
        m = min(first.size, later.size)
        if abs(got - (1 - np.corrcoef(first[:m], later[:m])[0, 1])) < 1e-4:
            return (
                f"for the {where} you cut both to the shorter length: resample the later "
                "period onto the earlier one's samples (end points aligned) instead."
            )
        grid = np.linspace(0, first.size - 1, later.size)
        resampled = np.interp(grid, np.arange(first.size), first)
        if abs(got - (1 - np.corrcoef(resampled, later)[0, 1])) < 1e-4:
            return f"for the {where} you resampled the earlier period: resample the later one."
        return f"for the {where} your distance is {got:.4f}, off by {got - want:+.4f}."
    return None


@exercise("segmentation.energy")
def judge_energy(energy: Any) -> str | None:
    """``energy(x, frames)``: eq. 2, the Pearson distances summed over pairs and channels."""
    _, x = _salsa()
    frames = np.rint(np.arange(20, 1000, 59.7)).astype(np.int64)  # 16 periods of ~1 s
    want = segmentation_energy(x, frames)
    got = _number(energy(x.copy(), frames.copy()), "the energy E")
    if isinstance(got, str):
        return got
    if abs(got - want) < 1e-3 * max(1.0, abs(want)):
        return None
    one = _number(energy(x.copy(), frames[:3].copy()), "the energy E")
    if isinstance(one, str):
        return one
    one_want = segmentation_energy(x, frames[:3])
    pairs, n_ch = frames.size - 2, x.shape[0]
    if abs(one - one_want) > 1e-3 * max(1.0, one_want):
        if abs(one * n_ch - one_want) < 1e-3 * one_want:
            return "for one pair of periods you averaged over the channels: E sums them."
        if abs(one - one_want / n_ch) < 0.5 * one_want / n_ch:
            return f"for one pair of periods, sum 1 - r over all {n_ch} channels (rows of x)."
        return "already wrong for one pair of periods (3 boundaries): check each channel's 1 - r."
    if abs(got * pairs - want) < 1e-3 * want:
        return f"you averaged over the {pairs} pairs: E (eq. 2) is their sum."
    return (
        f"right for one pair of periods, not for {frames.size} boundaries ({pairs} consecutive "
        f"pairs): off by {got - want:+.3f}."
    )


@exercise("segmentation.fft_period")
def judge_fft_period(fft_period: Any) -> str | None:
    """``fft_period(x, fps, period_range)``: the period [s] of the summed spectrum's peak."""
    _, x = _salsa()
    fps, prange = 60.0, (0.25, 1.25)
    want = estimate_period(x, prange[0] * fps, prange[1] * fps, "fft") / fps
    got = _number(fft_period(x.copy(), fps, prange), "the period in seconds")
    if isinstance(got, str):
        return got
    if abs(got / want - 1) < 0.05:
        return None
    for factor, hint in (
        (fps, "that is the period in frames: divide by fps for seconds."),
        (
            1 / want**2 if abs(want - 1) > 0.1 else np.nan,
            "a frequency [Hz]? The period is its inverse.",
        ),
        (2.0, "twice the period: search the peak only within 1/period_range."),
        (0.5, "half the period (a harmonic): search the peak only within 1/period_range."),
    ):
        if abs(got / (want * factor) - 1) < 0.04:
            return f"you returned {got:.4g}; {hint}"
    return (
        f"you returned {got:.3f} s, off by {100 * (got / want - 1):+.0f} % (within 5 % is right)."
    )
