"""Paper A, section 4: the beat-tracking study (our tracker beside other trackers).

One function per step of ``notebooks/paper_a_sec4_beat_tracking.ipynb``: the items
(the synthetic set with exact beats, and the real recordings with human annotations
in ``data/``) tracked by every method of :mod:`beatsync.other_trackers` that runs here
and scored with :func:`beatsync.evaluate.beats.evaluate`, the targets, the tempo
curves, and the sweeps of the front end and of the drum-pattern cue. Synthetic items
use the notebook's ``min_beat_time``; the two long real recordings mir_eval's 5 s
(their annotations' convention), the 2.8 s madmom sample 0 s. Two or three
recordings are a sanity check, not a benchmark.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from .. import datasets, other_trackers
from ..beats import FRONTEND_DEFAULTS, beat_tempo, track_beats
from ..errors import silenced
from ..evaluate.beats import evaluate, tempo_octave
from ..synth.audio import BeatTestItem, make_beat_test_set

__all__ = [
    "SHORT_NAMES",
    "TARGETS",
    "available_methods",
    "synthetic_items",
    "real_items",
    "score_items",
    "meter_estimates",
    "summarize",
    "check_targets",
    "tempo_change_figure",
    "frontend_sweep",
    "SWEEP_ITEMS_LISTED",
    "drum_weight_sweep",
]

#: Column names of the study tables.
SHORT_NAMES = {
    "F-measure": "F",
    "Correct Metric Level Total": "CMLt",
    "Any Metric Level Total": "AMLt",
}


#: Targets of the tracker: (description, item selection, metric, threshold).
TARGETS = (
    ("synthetic: mean F, clean items", "group == 'clean'", "F", 0.98),
    ("synthetic: mean AMLt, all items", "group != 'real'", "AMLt", 0.98),
    ("synthetic: mean F, tempo-change items", "group == 'change'", "F", 0.95),
    ("hainsworth_001: F", "item == 'hainsworth_001'", "F", 0.95),
    ("hainsworth_001: CMLt", "item == 'hainsworth_001'", "CMLt", 0.90),
    ("ballroom_waltz: F", "item == 'ballroom_waltz'", "F", 0.95),
    ("ballroom_waltz: CMLt", "item == 'ballroom_waltz'", "CMLt", 0.90),
    ("madmom_sample: at its own level (tempo octave)", "item == 'madmom_sample'", "octave", 1.0),
)

#: mir_eval's ``min_beat_time`` per real recording [s].
_REAL_MIN_BEAT_TIME = {"hainsworth_001": 5.0, "ballroom_waltz": 5.0, "madmom_sample": 0.0}


def available_methods() -> list[str]:
    """Trackers that can run here, ours first (essentia's only when it is installed)."""
    return [name for name, ok in other_trackers.available().items() if ok]


def methods_note(methods: Sequence[str]) -> str:
    """The trackers that run here, and what is left out (essentia, when not installed)."""
    text = f"methods: {list(methods)}"
    if not any(name.startswith("essentia") for name in methods):
        text += "\nessentia is not installed here: its trackers are left out of every table below"
    return text


def items_overview(items: Sequence[BeatTestItem], per_group: int = 3) -> pd.DataFrame:
    """The first ``per_group`` items of each group: name, group, tempo [BPM], beats and
    length [s] (what the study scores)."""
    table = pd.DataFrame(
        [
            {"item": it.name, "group": it.group, "bpm": round(it.bpm, 1),
             "beats": it.beats.size, "seconds": round(it.duration, 1)}
            for it in items
        ]
    )  # fmt: skip
    return table.groupby("group", sort=False).head(per_group)


def synthetic_items(**kwargs: Any) -> list[BeatTestItem]:
    """The synthetic test set (:func:`beatsync.synth.audio.make_beat_test_set`)."""
    return make_beat_test_set(**kwargs)


def real_items() -> list[BeatTestItem]:
    """Every bundled real recording with human beat annotations, as test items of group
    ``"real"`` whose ``bpm`` is the median annotated tempo."""
    out = []
    for name in datasets.REAL_DEV_ITEMS:
        y, sr, ref = datasets.load_real_dev(name)
        out.append(_real_item(name, y, sr, ref))
    y, sr, ref = datasets.load_madmom_sample()
    out.append(_real_item("madmom_sample", y, sr, ref))
    return out


def _real_item(name, y, sr, ref) -> BeatTestItem:
    bpm = 60.0 / float(np.median(np.diff(ref)))
    return BeatTestItem(name, "real", "recording", y, int(sr), ref, bpm, bpm)


def _min_beat_time(item: BeatTestItem, default: float) -> float:
    return _REAL_MIN_BEAT_TIME.get(item.name, default) if item.group == "real" else default


def score_items(
    items: Sequence[BeatTestItem],
    *,
    methods: Sequence[str] | None = None,
    min_beat_time: float = 0.0,
    **track_kwargs: Any,
) -> pd.DataFrame:
    """Track and score every item with every method; one row per item and method, with
    the study's short metric names and ``seconds`` (tracking time, not for display).
    ``track_kwargs`` go to the ``psf`` tracker (front-end parameters)."""
    methods = available_methods() if methods is None else list(methods)
    for m in methods:
        other_trackers.get(m)
    rows = []
    for it, method in itertools.product(items, methods):
        t0 = time.perf_counter()
        with silenced():
            if method == "psf" and track_kwargs:
                est = track_beats(it.y, it.sr, **track_kwargs).beats
            else:
                est = other_trackers.track(method, it.y, it.sr)
            seconds = time.perf_counter() - t0
            scores = evaluate(it.beats, est, min_beat_time=_min_beat_time(it, min_beat_time))
        rows.append(
            {"item": it.name, "group": it.group, "method": method,
             **tempo_octave(it.beats, est), **scores, "seconds": seconds}
        )  # fmt: skip
    cols = ["item", "group", "method", "tempo_ref", "tempo_est", "octave", "F", "CMLt", "AMLt"]
    return pd.DataFrame(rows).rename(columns=SHORT_NAMES)[[*cols, "seconds"]]


def meter_estimates(items: Sequence[BeatTestItem]) -> pd.DataFrame:
    """Our meter estimate (beats per bar) and tempo for each item (``psf`` only)."""
    rows = []
    for it in items:
        with silenced():
            bt = track_beats(it.y, it.sr)
        rows.append({"item": it.name, "tempo": bt.tempo, "beats_per_bar": bt.beats_per_bar})
    return pd.DataFrame(rows)


def summarize(scores: pd.DataFrame, by: str = "group") -> pd.DataFrame:
    """Mean F, CMLt, AMLt per ``by`` and method, with the count of tempo-octave errors."""
    octave_err = scores["octave"].isin(["double", "half", "triple", "third"])
    df = scores.assign(octave_errors=octave_err.astype(int), n=1)
    agg = {"F": "mean", "CMLt": "mean", "AMLt": "mean", "octave_errors": "sum", "n": "sum"}
    return df.groupby([by, "method"], sort=False).agg(agg).reset_index()


def check_targets(scores: pd.DataFrame) -> pd.DataFrame:
    """The tracker's targets per method: value, threshold and PASS/FAIL.

    The madmom target is 1 when the tempo is at the annotated level (``octave`` is
    ``"correct"``), else 0.
    """
    rows = []
    for method, sc in scores.groupby("method", sort=False):
        for desc, query, metric, threshold in TARGETS:
            sel = sc.query(query)
            if sel.empty:
                continue
            at_level = sel["octave"] == "correct"
            value = float(at_level.mean() if metric == "octave" else sel[metric].mean())
            rows.append(
                {
                    "target": desc,
                    "method": method,
                    "n": len(sel),
                    "value": value,
                    "threshold": threshold,
                    "result": "PASS" if value >= threshold else "FAIL",
                }
            )
    return pd.DataFrame(rows)


def drum_weight_sweep(
    items: Sequence[BeatTestItem], weights: Sequence[float], *, min_beat_time: float = 0.0
) -> pd.DataFrame:
    """Our tracker at each weight of the drum-pattern cue (0: without it).

    One row per weight and group (the synthetic groups, and each real recording as a
    group of its own): mean F, CMLt and AMLt, the count of tempo-octave errors, and
    whether the weight is the default (:data:`beatsync.beats.drums.DRUM_WEIGHT`).
    """
    from ..beats.drums import DRUM_WEIGHT  # noqa: PLC0415

    frames = []
    for w in weights:
        sc = score_items(items, methods=["psf"], min_beat_time=min_beat_time, drum_weight=w)
        sc["group"] = np.where(sc["group"] == "real", sc["item"], sc["group"])
        table = summarize(sc).drop(columns="method")
        frames.append(table.assign(drum_weight=float(w), default=float(w) == DRUM_WEIGHT))
    cols = ["drum_weight", "default", "group", "F", "CMLt", "AMLt", "octave_errors", "n"]
    return pd.concat(frames, ignore_index=True)[cols]


def tempo_change_figure(items: Sequence[BeatTestItem], max_items: int = 4):
    """Tempo curves of the ``psf`` tempo HMM against the true tempo on tempo-change items."""
    import matplotlib.pyplot as plt  # noqa: PLC0415

    change = [it for it in items if it.group == "change"][:max_items]
    fig, axes = plt.subplots(
        1, max(len(change), 1), figsize=(3.2 * max(len(change), 1), 2.6), squeeze=False
    )
    for ax, it in zip(axes[0], change, strict=False):
        track = track_beats(it.y, it.sr)
        ax.step(*beat_tempo(it.beats), where="post", color="0.6", label="truth")
        ax.plot(track.tempo_times, track.tempo_curve, "o-", ms=3, label="psf tempo HMM")
        ax.set_title(it.name, fontsize=9)
        ax.set_xlabel("time [s]")
    axes[0, 0].set_ylabel("tempo [BPM]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


#: Item sets of :func:`frontend_sweep` up to this size get the F of each item.
SWEEP_ITEMS_LISTED = 5


def frontend_sweep(
    item_sets: dict[str, Sequence[BeatTestItem]],
    grid: dict[str, Sequence[Any]],
    *,
    min_beat_time: float = 0.0,
) -> pd.DataFrame:
    """Score the ``psf`` tracker for every combination of the front-end ``grid``
    (parameter -> values; ``hop_s > win_s / 2`` skipped) on each non-empty item set.

    One row per combination and set: the parameters, whether they are the defaults,
    mean F, CMLt and AMLt, and for sets of at most :data:`SWEEP_ITEMS_LISTED` items the
    F of each (a mean of three recordings can move with one of them).
    """
    keys = list(grid)
    rows = []
    for combo in itertools.product(*(grid[k] for k in keys)):
        params = dict(zip(keys, combo, strict=True))
        if params.get("hop_s", 0.0) > params.get("win_s", FRONTEND_DEFAULTS["win_s"]) / 2:
            continue
        default = all(
            np.allclose(np.asarray(v, float), np.asarray(FRONTEND_DEFAULTS[k], float))
            for k, v in params.items()
        )
        for set_name, items in item_sets.items():
            if not len(items):
                continue
            sc = score_items(items, methods=["psf"], min_beat_time=min_beat_time, **params)
            row = {
                k: str(list(v)) if isinstance(v, (list, tuple)) else v for k, v in params.items()
            }
            row.update({"set": set_name, "default": default})
            row.update({m: float(sc[m].mean()) for m in ("F", "CMLt", "AMLt")})
            row["F per item"] = (
                ", ".join(f"{r.item} {r.F:.3f}" for r in sc.itertuples())
                if len(items) <= SWEEP_ITEMS_LISTED
                else ""
            )
            rows.append(row)
    return pd.DataFrame(rows)
