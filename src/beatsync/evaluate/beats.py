"""Beat-tracking scores: a validated wrapper around :mod:`mir_eval.beat`.

Data contract
-------------
Reference and estimated beats are 1-D ``float64`` arrays of times in seconds,
strictly increasing and >= 0. ``min_beat_time`` [s] is always explicit: mir_eval's
default (5 s) silently drops the first 5 s, which is most of a short clip.

All mir_eval.beat metrics are returned: F-measure, Cemgil (and its max-over-variants
form), Goto, P-score, CMLc, CMLt, AMLc, AMLt and information gain.

Notebook: ``notebooks/tab_beat_tracking.ipynb``; paper A, section 4.
"""

from __future__ import annotations

import warnings
from typing import Any

import mir_eval
import numpy as np

from ..errors import BeatsyncWarning, ParameterError
from ..units import check_times

__all__ = ["evaluate_beats", "METRICS", "octave_relation", "MAX_BEAT_INTERVAL"]

#: Beat sequences whose median interval exceeds this [s] are refused (not seconds).
MAX_BEAT_INTERVAL = 10.0

#: Keys of the dict returned by :func:`evaluate_beats`.
METRICS = (
    "F-measure",
    "Cemgil",
    "Cemgil Best Metric Level",
    "Goto",
    "P-score",
    "Correct Metric Level Continuous",
    "Correct Metric Level Total",
    "Any Metric Level Continuous",
    "Any Metric Level Total",
    "Information gain",
)


def _check(beats: Any, name: str) -> np.ndarray:
    arr = np.asarray(beats, dtype=np.float64) if not isinstance(beats, np.ndarray) else beats
    arr = check_times(arr, name=name)
    if arr.size and arr[-1] > mir_eval.beat.MAX_TIME:
        raise ParameterError(
            f"{name} ends at {arr[-1]!r} s, more than {mir_eval.beat.MAX_TIME:g} s: "
            "these look like milliseconds or sample indices, not seconds"
        )
    if arr.size > 2 and np.median(np.diff(arr)) > MAX_BEAT_INTERVAL:
        raise ParameterError(
            f"{name} are {np.median(np.diff(arr)):g} s apart (median): slower than "
            f"{60 / MAX_BEAT_INTERVAL:g} BPM; these look like milliseconds or frame "
            "indices, not seconds"
        )
    return arr.astype(np.float64)


def evaluate_beats(
    reference: np.ndarray,
    estimated: np.ndarray,
    *,
    min_beat_time: float,
) -> dict[str, float]:
    """All mir_eval.beat metrics of an estimate against a reference.

    Parameters
    ----------
    reference : np.ndarray [shape=(n,)] [s]
        Annotated beats, strictly increasing seconds.
    estimated : np.ndarray [shape=(m,)] [s]
        Estimated beats, strictly increasing seconds.
    min_beat_time : float >= 0 [s], keyword-only, required
        Beats before this time are ignored in both sequences (mir_eval uses 5 s by
        default; use 0 for short clips).

    Returns
    -------
    scores : dict
        Keys :data:`METRICS`, values in [0, 1] (mir_eval normalises the information gain).

    Raises
    ------
    ParameterError
        Times not 1-D, negative, non-finite, not strictly increasing, or in
        milliseconds; ``min_beat_time`` negative or not finite.

    Warns
    -----
    BeatsyncWarning
        If either sequence is empty after trimming: every score is 0.

    Examples
    --------
    >>> ref = np.arange(0.5, 10, 0.5)
    >>> evaluate_beats(ref, ref, min_beat_time=0.0)["F-measure"]
    1.0
    """
    try:
        mbt = float(min_beat_time)
    except (TypeError, ValueError):
        raise ParameterError(f"min_beat_time={min_beat_time!r} is not a number [s]") from None
    if not np.isfinite(mbt) or mbt < 0:
        raise ParameterError(f"min_beat_time={min_beat_time!r} must be a time >= 0 [s]")
    ref = _check(reference, "reference beats")
    est = _check(estimated, "estimated beats")
    ref = mir_eval.beat.trim_beats(ref, min_beat_time=mbt)
    est = mir_eval.beat.trim_beats(est, min_beat_time=mbt)
    if ref.size == 0 or est.size == 0:
        which = "reference" if ref.size == 0 else "estimated"
        warnings.warn(
            f"the {which} beats are empty after min_beat_time={mbt:g} s: every score is 0",
            BeatsyncWarning,
            stacklevel=2,
        )
        return {k: 0.0 for k in METRICS}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # mir_eval warns about what we have checked
        f = mir_eval.beat.f_measure(ref, est)
        cem, cem_best = mir_eval.beat.cemgil(ref, est)
        goto = mir_eval.beat.goto(ref, est)
        p = mir_eval.beat.p_score(ref, est)
        cmlc, cmlt, amlc, amlt = mir_eval.beat.continuity(ref, est)
        ig = mir_eval.beat.information_gain(ref, est)
    values = (f, cem, cem_best, goto, p, cmlc, cmlt, amlc, amlt, ig)
    return {k: float(v) for k, v in zip(METRICS, values, strict=True)}


def octave_relation(estimated_bpm: float, reference_bpm: float, *, tol: float = 0.08) -> str:
    """Name the metrical relation of an estimated tempo to the reference.

    Parameters
    ----------
    estimated_bpm, reference_bpm : float > 0 [bpm]
    tol : float
        Relative tolerance.

    Returns
    -------
    str
        ``"correct"``, ``"double"`` (estimate 2x), ``"half"``, ``"triple"``, ``"third"``
        or ``"other"``.
    """
    if not (np.isfinite(estimated_bpm) and np.isfinite(reference_bpm)) or reference_bpm <= 0:
        return "other"
    r = estimated_bpm / reference_bpm
    for name, target in (
        ("correct", 1.0),
        ("double", 2.0),
        ("half", 0.5),
        ("triple", 3.0),
        ("third", 1 / 3),
    ):
        if abs(r / target - 1.0) <= tol:
            return name
    return "other"
