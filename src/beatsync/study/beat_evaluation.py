"""Beat tracking run and scored on in-memory test items, for the study.

The trackers run here and are scored with :mod:`beatsync.evaluate.beats` (which
never runs one): :func:`score_items` tracks test items with each method,
:func:`summarize_scores` and :func:`beat_targets` build the tables,
:func:`sweep_frontend` sweeps the front-end settings. Datasets of files are run by
:mod:`beatsync.study.beat_dataset` (``beatsync evaluate beats``).

Methods are named as in :data:`beatsync.peers.PEERS` (``psf`` is ours). Every time is
in seconds, every tempo in BPM.

Notebook: ``notebooks/paper_a_sec4_beat_tracking.ipynb``; paper A, section 4.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from .. import peers
from ..errors import ParameterError, silenced
from ..evaluate.beats import (
    TABLE_METRICS,
    count_octave_errors,
    count_other_tempo,
    evaluate,
    tempo_octave,
)

__all__ = [
    "score_items",
    "summarize_scores",
    "beat_targets",
    "sweep_frontend",
]


def _track(method: str, y: np.ndarray, sr: float, track_kwargs: dict[str, Any]) -> np.ndarray:
    if method == "psf" and track_kwargs:
        from ..beats import track_beats

        return track_beats(y, sr, **track_kwargs).beats
    return peers.track(method, y, sr)


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
    methods : sequence of str
        Names of :data:`beatsync.peers.PEERS`.
    min_beat_time : float >= 0 [s]
        Passed to :func:`beatsync.evaluate.beats.evaluate`.
    track_kwargs : dict, optional
        Extra keyword arguments of :func:`beatsync.beats.track_beats` (``psf`` only).
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    pandas.DataFrame
        One row per (item, method): ``item, group, kind, bpm, method, tempo_ref,
        tempo_est, octave`` (see :func:`~beatsync.evaluate.beats.tempo_octave`), all
        :data:`~beatsync.evaluate.beats.METRICS`, ``seconds`` (tracking time, not for
        display) and ``audio_seconds``.
    """
    for m in methods:
        peers.get(m)
    rows = []
    jobs: Any = [(it, m) for it in items for m in methods]
    if progress:
        from tqdm import tqdm

        jobs = tqdm(jobs, desc="beat tracking", leave=False)
    for it, method in jobs:
        kw = dict(track_kwargs or {}) if method == "psf" else {}
        t0 = time.perf_counter()
        with silenced():
            est = _track(method, it.y, it.sr, kw)
        seconds = time.perf_counter() - t0
        with silenced():
            scores = evaluate(it.beats, est, min_beat_time=min_beat_time)
        rows.append(
            {
                "item": it.name,
                "group": it.group,
                "kind": it.kind,
                "bpm": float(it.bpm),
                "method": method,
                **tempo_octave(it.beats, est),
                **scores,
                "seconds": seconds,
                "audio_seconds": len(it.y) / it.sr,
            }
        )
    return pd.DataFrame(rows)


def summarize_scores(
    scores: pd.DataFrame, *, by: str | None = "group", metrics: Sequence[str] = TABLE_METRICS
) -> pd.DataFrame:
    """Mean of ``metrics`` per ``by`` and method, with octave-error counts.

    Parameters
    ----------
    scores : pandas.DataFrame
        Output of :func:`score_items` (or the ``ok`` rows of a dataset run).
    by : str or None
        Column to group by besides ``method`` (e.g. ``"group"``, ``"kind"``); ``None``:
        one row per method over all items.
    metrics : sequence of str

    Returns
    -------
    pandas.DataFrame
        Index ``(by, method)`` (or ``method`` if ``by`` is None); columns the metrics
        (means), ``n`` (items), ``octave errors`` (tempo double/half/triple/third,
        :data:`~beatsync.evaluate.beats.OCTAVE_ERRORS`) and ``other tempo``.
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
    out["octave errors"] = g["octave"].agg(count_octave_errors)
    out["other tempo"] = g["octave"].agg(count_other_tempo)
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
