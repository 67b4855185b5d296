"""Beat-tracking scores on arrays, in the style of :mod:`mir_eval.beat`.

Reference and estimated beats are 1-D times in seconds, strictly increasing, >= 0
(:func:`validate` diagnoses frame indices or milliseconds). ``min_beat_time`` [s] is
always explicit: mir_eval's default (5 s) silently drops most of a short clip.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import ParameterError, warn
from ..validation import MIN_BPM, check_positive, check_times

__all__ = [
    "EMPTY_REFERENCE_TEXT",
    "validate",
    "diagnose_times",
    "not_seconds_detail",
    "evaluate",
    "median_tempo",
    "octave_relation",
    "tempo_octave",
    "count_octave_errors",
    "count_other_tempo",
    "METRICS",
    "OCTAVE_ERRORS",
    "MAX_BEAT_INTERVAL",
]

#: Beat sequences whose median interval exceeds this [s] are refused (not seconds):
#: the beat period at :data:`beatsync.validation.MIN_BPM`.
MAX_BEAT_INTERVAL = 60.0 / MIN_BPM

#: mir_eval's limit on beat times [s] (``mir_eval.beat.MAX_TIME``), copied so that
#: reading an annotation does not import mir_eval (slow).
MIR_EVAL_MAX_TIME = 30000.0


#: Keys of the dict returned by :func:`evaluate`.
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

#: Relations of :func:`octave_relation`: estimated over reference tempo.
TEMPO_RATIOS = {"correct": 1.0, "double": 2.0, "half": 0.5, "triple": 3.0, "third": 1 / 3}

#: Values of :func:`octave_relation` that are octave errors.
OCTAVE_ERRORS = tuple(k for k in TEMPO_RATIOS if k != "correct")


def diagnose_times(times: np.ndarray) -> str | None:
    """What finite increasing event times look like if not seconds (frame, sample indices,
    milliseconds, ...), or ``None`` for plausible beat times (a median spacing of at most
    :data:`MAX_BEAT_INTERVAL`, the last within mir_eval's limit)."""
    if times.size == 0:
        return None
    if times.size < 3:
        return "milliseconds or frame indices" if times[-1] > MIR_EVAL_MAX_TIME else None
    step = float(np.median(np.diff(times)))
    if step <= MAX_BEAT_INTERVAL and times[-1] <= MIR_EVAL_MAX_TIME:
        return None
    integers = bool(np.all(times == np.round(times)))
    if step <= MAX_BEAT_INTERVAL and not integers:
        return f"a recording longer than mir_eval's {MIR_EVAL_MAX_TIME:g} s"
    if integers and step < 150.0:
        return "frame indices"
    if 150.0 <= step <= 3000.0:
        return "milliseconds"
    if integers:
        return "sample indices"
    return "something slower than any beat (bars? a wrong unit?)"


#: The start of the warning :func:`evaluate` gives when no reference beat is left to score.
EMPTY_REFERENCE_TEXT = "the reference beats are empty"


def validate(reference: Any, estimated: Any) -> tuple[np.ndarray, np.ndarray]:
    """Check reference and estimated beats (1-D, >= 0, finite, strictly increasing, in
    seconds: :func:`diagnose_times`); return them as ``float64`` arrays.
    """
    return _check(reference, "reference beats"), _check(estimated, "estimated beats")


def not_seconds_detail(times: np.ndarray) -> str | None:
    """Why increasing event times look like something other than seconds (the last time, the
    median spacing and :func:`diagnose_times`), for an error message; ``None`` if they do not.
    """
    looks = diagnose_times(times)
    if looks is None:
        return None
    step = float(np.median(np.diff(times))) if times.size > 1 else float("nan")
    return f"{times[-1]:g} with a median spacing of {step:g}, which looks like {looks}"


def _check(beats: Any, name: str) -> np.ndarray:
    arr = check_times(beats, name=name)
    detail = not_seconds_detail(arr)
    if detail is not None:
        raise ParameterError(
            f"{name} are not times in seconds: they end at {detail}; convert them to seconds"
        )
    return arr


def evaluate(
    reference: Any,
    estimated: Any,
    *,
    min_beat_time: float,
) -> dict[str, float]:
    """Every metric of :func:`mir_eval.beat.evaluate` (keys :data:`METRICS`, values in [0, 1]).

    Beats before ``min_beat_time`` [s] are ignored in both sequences (0 for short clips).
    Warns, and every score is 0, when either sequence is empty after trimming.

    Examples
    --------
    >>> ref = np.arange(0.5, 10, 0.5)
    >>> evaluate(ref, ref, min_beat_time=0.0)["F-measure"]
    1.0
    """
    import mir_eval.beat  # here, not at the top: see MIR_EVAL_MAX_TIME

    mbt = check_positive(min_beat_time, name="min_beat_time", unit="s", allow_zero=True)
    ref, est = validate(reference, estimated)
    ref = mir_eval.beat.trim_beats(ref, min_beat_time=mbt)
    est = mir_eval.beat.trim_beats(est, min_beat_time=mbt)
    if ref.size == 0 or est.size == 0:
        which = EMPTY_REFERENCE_TEXT if ref.size == 0 else "the estimated beats are empty"
        warn(f"{which} after min_beat_time={mbt:g} s: every score is 0", stacklevel=2)
        return {k: 0.0 for k in METRICS}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # mir_eval warns about what we have checked
        scores = mir_eval.beat.evaluate(ref, est, min_beat_time=mbt)
    return {k: float(scores[k]) for k in METRICS}


def median_tempo(beats: Any) -> float:
    """Tempo [BPM] of the median inter-beat interval; NaN with fewer than two beats."""
    b = np.asarray(beats, dtype=np.float64)
    if b.size < 2:
        return float("nan")
    return 60.0 / float(np.median(np.diff(b)))


def octave_relation(estimated_bpm: float, reference_bpm: float, *, tol: float = 0.08) -> str:
    """The relation (a key of :data:`TEMPO_RATIOS`, or ``"other"``) of an estimated tempo
    to the reference [bpm], within the relative tolerance ``tol``."""
    if not (np.isfinite(estimated_bpm) and np.isfinite(reference_bpm)) or reference_bpm <= 0:
        return "other"
    r = estimated_bpm / reference_bpm
    return next((k for k, t in TEMPO_RATIOS.items() if abs(r / t - 1.0) <= tol), "other")


def count_octave_errors(octaves: Any) -> int:
    """How many relations of :func:`octave_relation` are octave errors (:data:`OCTAVE_ERRORS`)."""
    return int(np.isin(np.asarray(octaves, dtype=object), OCTAVE_ERRORS).sum())


def count_other_tempo(octaves: Any) -> int:
    """How many relations of :func:`octave_relation` are ``"other"`` (not a metrical level)."""
    return int((np.asarray(octaves, dtype=object) == "other").sum())


def tempo_octave(reference: Any, estimated: Any) -> dict[str, Any]:
    """Median tempi ``tempo_ref``, ``tempo_est`` [BPM] (NaN with fewer than two beats) and
    their ``octave`` relation (:func:`octave_relation`).
    """
    ref, est = validate(reference, estimated)
    t_ref, t_est = median_tempo(ref), median_tempo(est)
    return {"tempo_ref": t_ref, "tempo_est": t_est, "octave": octave_relation(t_est, t_ref)}
