"""Exercises of ``notebooks/tutorials/02_beat_tracking.ipynb`` (paper A, sec. 4), judged
with :mod:`beatsync.evaluate.beats` on the annotations of Hainsworth 001."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from .. import datasets
from ..errors import silenced
from ..evaluate.beats import evaluate, median_tempo
from . import exercise

__all__ = ["judge_score", "judge_off_beats", "judge_bpm"]

#: the scores :func:`judge_score` asks for, in this order (mir_eval's names)
SCORES = ("F-measure", "Correct Metric Level Total", "Any Metric Level Total")
_SHORT = dict(zip(SCORES, ("F-measure", "CMLt", "AMLt"), strict=True))


@functools.cache
def _reference() -> np.ndarray:
    return datasets.load_real_dev("hainsworth_001")[2]


def _estimates(ref: np.ndarray) -> dict[str, np.ndarray]:
    """Estimates whose scores differ: late by 30 ms, the off-beats, every other beat."""
    return {
        "the annotations 30 ms late": ref + 0.03,
        "the off-beats": (ref[1:] + ref[:-1]) / 2,
        "every other beat": ref[::2].copy(),
    }


@exercise("beats.score")
def judge_score(score: Any) -> str | None:
    """``score(reference, estimated) -> (F, CMLt, AMLt)``, beats before 5 s left out."""
    ref = _reference()
    for name, est in _estimates(ref).items():
        got = score(ref.copy(), est.copy())
        if not isinstance(got, (tuple, list)) or len(got) != 3:
            return f"return three numbers (F-measure, CMLt, AMLt), not {type(got).__name__}."
        with silenced():
            want = evaluate(ref, est, min_beat_time=5.0)
            untrimmed = evaluate(ref, est, min_beat_time=0.0)
        wanted = np.array([want[k] for k in SCORES])
        got_arr = np.asarray(got, dtype=np.float64)
        if np.allclose(got_arr, wanted, atol=1e-6):
            continue
        if np.allclose(got_arr, [untrimmed[k] for k in SCORES], atol=1e-6):
            return f"on {name}: leave out the beats before 5 s of both lists (trim_beats)."
        if np.allclose(np.sort(got_arr), np.sort(wanted), atol=1e-6):
            return f"on {name}: the right numbers in another order: return (F-measure, CMLt, AMLt)."
        wrong = [k for k, g, w in zip(SCORES, got_arr, wanted, strict=True) if abs(g - w) > 1e-6]
        return f"on {name}: {', '.join(_SHORT[k] for k in wrong)} differ from mir_eval's."
    return None


@exercise("beats.off_beats")
def judge_off_beats(off_beats: Any) -> str | None:
    """``off_beats(reference)``: beats halfway between the annotated ones (CMLt 0, AMLt 1)."""
    ref = _reference()
    got = np.asarray(off_beats(ref.copy()), dtype=np.float64)
    if got.ndim != 1 or got.size < 2:
        return f"return a 1-D array of beat times [s], not shape {got.shape}."
    if np.any(np.diff(got) <= 0):
        return "the beat times must increase strictly."
    with silenced():
        s = evaluate(ref, got, min_beat_time=5.0)
    cmlt, amlt = s[SCORES[1]], s[SCORES[2]]
    if cmlt > 0:
        return f"CMLt is {cmlt:.2f}: some of your beats are still on the annotated beats."
    if amlt < 0.9:
        if abs(median_tempo(got) / median_tempo(ref) - 1) > 0.05:
            return (
                f"your tempo is {median_tempo(got):.1f} BPM, the annotations' "
                f"{median_tempo(ref):.1f}: keep one beat per annotated beat."
            )
        return f"AMLt is {amlt:.2f}: your beats are off the beat, but not halfway between."
    return None


@exercise("beats.bpm")
def judge_bpm(bpm: Any) -> str | None:
    """``bpm(beats)``: the tempo [BPM] of the median inter-beat interval."""
    ref = _reference()
    gappy = np.delete(ref, np.arange(10, ref.size, 7))  # some beats missed by a tracker
    for name, beats in (("the annotations", ref), ("the annotations with beats missing", gappy)):
        got = np.asarray(bpm(beats.copy()))
        if got.shape != ():
            return f"return one number (BPM), not an array of shape {got.shape}."
        want = median_tempo(beats)
        g = float(got)
        if abs(g - want) < 1e-6 * want:
            continue
        if abs(g - 60.0 / want) < 1e-3:
            return f"on {name}: {g:.3f} is seconds per beat; a tempo is beats per minute."
        if abs(g - 1.0 / (60.0 / want)) < 1e-3:
            return f"on {name}: {g:.3f} is beats per second; a tempo is beats per minute."
        if abs(g - 60.0 / np.mean(np.diff(beats))) < 1e-6 * want:
            return (
                f"on {name}: the mean interval is pulled by odd intervals (a missed beat "
                "doubles one): use the median."
            )
        return f"on {name}: {g:.2f} BPM, off by {g - want:+.2f}."
    return None
