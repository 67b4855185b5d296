"""Beat-tracking scores: a validated wrapper around :mod:`mir_eval.beat`.

Data contract
-------------
Reference and estimated beats are 1-D ``float64`` arrays of times in seconds,
strictly increasing and >= 0. ``min_beat_time`` [s] is always explicit: mir_eval's
default (5 s) silently drops the first 5 s, which is most of a short clip.

All mir_eval.beat metrics are returned: F-measure, Cemgil (and its max-over-variants
form), Goto, P-score, CMLc, CMLt, AMLc, AMLt and information gain.

Notebook: ``notebooks/paper_a_sec4_beat_tracking.ipynb``; paper A, section 4.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import mir_eval
import numpy as np
import pandas as pd

from ..errors import BeatsyncWarning, ParameterError
from ..units import check_times

__all__ = [
    "evaluate_beats",
    "METRICS",
    "TABLE_METRICS",
    "MAX_BEAT_INTERVAL",
    "octave_relation",
    "score_items",
    "summarize_scores",
    "OCTAVE_ERRORS",
    "beat_targets",
    "sweep_frontend",
]

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


# --------------------------------------------------------------------------- study helpers

#: Metrics shown in the study table (``notebooks/paper_a_sec4_beat_tracking.ipynb``).
TABLE_METRICS = (
    "F-measure",
    "Cemgil",
    "P-score",
    "Correct Metric Level Total",
    "Any Metric Level Total",
    "Information gain",
)


def score_items(
    items: Sequence[Any],
    *,
    methods: Sequence[str] = ("psf", "librosa"),
    min_beat_time: float,
    track_kwargs: dict[str, Any] | None = None,
    progress: bool = False,
) -> pd.DataFrame:
    """Track and score every test item with every method.

    Parameters
    ----------
    items : sequence of objects with ``name, group, kind, y, sr, beats, bpm``
        E.g. :func:`beatsync.synth.audio.make_beat_test_set`.
    methods : sequence of {"psf", "librosa"}
    min_beat_time : float >= 0 [s]
        Passed to :func:`evaluate_beats`.
    track_kwargs : dict, optional
        Extra keyword arguments of :func:`beatsync.beats.track_beats` (``psf`` only).
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    pandas.DataFrame
        One row per (item, method): ``item, group, kind, bpm, method, tempo_ref,
        tempo_est, octave`` (see :func:`octave_relation`, from median beat intervals),
        all :data:`METRICS`, and ``seconds`` (tracking time, not for display).
    """
    import time

    from ..beats import track_beats

    rows = []
    jobs = [(it, m) for it in items for m in methods]
    if progress:
        from tqdm import tqdm

        jobs = tqdm(jobs, desc="beat tracking", leave=False)
    for it, method in jobs:
        kw = dict(track_kwargs or {}) if method == "psf" else {}
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BeatsyncWarning)
            track = track_beats(it.y, it.sr, method=method, **kw)
        seconds = time.perf_counter() - t0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BeatsyncWarning)
            scores = evaluate_beats(it.beats, track.beats, min_beat_time=min_beat_time)
        ref_tempo = 60.0 / float(np.median(np.diff(it.beats)))
        est_tempo = (
            60.0 / float(np.median(np.diff(track.beats))) if track.beats.size > 1 else np.nan
        )
        rows.append(
            {
                "item": it.name,
                "group": it.group,
                "kind": it.kind,
                "bpm": float(it.bpm),
                "method": method,
                "tempo_ref": ref_tempo,
                "tempo_est": est_tempo,
                "octave": octave_relation(est_tempo, ref_tempo),
                **scores,
                "seconds": seconds,
                "audio_seconds": len(it.y) / it.sr,
            }
        )
    return pd.DataFrame(rows)


#: Values of the ``octave`` column (:func:`octave_relation`) that are octave errors.
OCTAVE_ERRORS = ("double", "half", "triple", "third")


def _count_octave_errors(octave: pd.Series) -> int:
    return int(octave.isin(OCTAVE_ERRORS).sum())


def _count_other_tempo(octave: pd.Series) -> int:
    return int((octave == "other").sum())


def summarize_scores(
    scores: pd.DataFrame, *, by: str | None = "group", metrics: Sequence[str] = TABLE_METRICS
) -> pd.DataFrame:
    """Mean of ``metrics`` per ``by`` and method, with octave-error counts.

    Parameters
    ----------
    scores : pandas.DataFrame
        Output of :func:`score_items`.
    by : str or None
        Column to group by besides ``method`` (e.g. ``"group"``, ``"kind"``); ``None``:
        one row per method over all items.
    metrics : sequence of str

    Returns
    -------
    pandas.DataFrame
        Index ``(by, method)`` (or ``method`` if ``by`` is None); columns the metrics
        (means), ``n`` (items), ``octave errors`` (tempo double/half/triple/third,
        :data:`OCTAVE_ERRORS`) and ``other tempo``.
    """
    keys = ["method"] if by is None else [by, "method"]
    missing = [k for k in [*keys, "octave", *metrics] if k not in scores.columns]
    if missing:
        raise ParameterError(
            f"scores has no column(s) {missing}; pass the table from score_items "
            f"(columns: {list(scores.columns)})"
        )
    g = scores.groupby(keys, sort=False)
    out = g[list(metrics)].mean()
    out["n"] = g.size()
    out["octave errors"] = g["octave"].agg(_count_octave_errors)
    out["other tempo"] = g["octave"].agg(_count_other_tempo)
    return out


def beat_targets(scores: pd.DataFrame, *, method: str = "psf") -> pd.DataFrame:
    """The issue's accuracy targets on the synthetic set, with PASS/FAIL.

    Targets: mean F-measure >= 0.95 on ``clean`` items, mean AMLt >= 0.98 over all
    items, mean F-measure >= 0.95 on ``change`` (abrupt tempo change) items.
    """
    s = scores[scores["method"] == method]
    rows = []
    for name, sel, metric, thr in (
        ("mean F, clean items", s["group"] == "clean", "F-measure", 0.95),
        ("mean AMLt, all items", slice(None), "Any Metric Level Total", 0.98),
        ("mean F, tempo-change items", s["group"] == "change", "F-measure", 0.95),
    ):
        sub = s.loc[sel]
        value = float(sub[metric].mean()) if len(sub) else float("nan")
        rows.append(
            {
                "target": name,
                "method": method,
                "n": len(sub),
                "value": value,
                "threshold": thr,
                "result": "PASS" if value >= thr else "FAIL",
            }
        )
    return pd.DataFrame(rows)


def sweep_frontend(
    items: Sequence[Any],
    grid: dict[str, Sequence[Any]],
    *,
    min_beat_time: float,
    metrics: Sequence[str] = ("F-measure", "Any Metric Level Total", "Cemgil"),
) -> pd.DataFrame:
    """Score the ``psf`` tracker for every combination of front-end parameters.

    Parameters
    ----------
    items : sequence of test items
    grid : dict
        Parameter name (``win_s``, ``hop_s``, ``n_fft``, ``band_edges_hz``,
        ``flux_norm_s``) -> values. Combinations with ``hop_s > win_s / 2`` are skipped.
    min_beat_time : float >= 0 [s]

    Returns
    -------
    pandas.DataFrame
        One row per combination: the parameters and the mean of ``metrics``.
    """
    import itertools

    keys = list(grid)
    rows = []
    for combo in itertools.product(*(grid[k] for k in keys)):
        params = dict(zip(keys, combo, strict=True))
        if "hop_s" in params and params["hop_s"] > params.get("win_s", 0.023) / 2:
            continue
        sc = score_items(items, methods=("psf",), min_beat_time=min_beat_time, track_kwargs=params)
        row = {k: (str(tuple(v)) if isinstance(v, (list, tuple)) else v) for k, v in params.items()}
        row.update({m: float(sc[m].mean()) for m in metrics})
        rows.append(row)
    return pd.DataFrame(rows)
