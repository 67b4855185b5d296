"""Exercises of ``notebooks/tutorials/05_real_dancers.ipynb`` (the two beat-alignment
scores), judged with :mod:`beatsync.evaluate.alignment` on a bundled dancer's beats."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from . import exercise

__all__: list[str] = []


@functools.cache
def _case() -> tuple[np.ndarray, np.ndarray]:
    """Kinematic beats of the rumba dancer and a steady 100 BPM pulse over them [s]."""
    from ..datasets import load_dance_pair
    from ..motion_beats import kinematic_beats

    mb = kinematic_beats(load_dance_pair("DANCE_R_3").motion)
    return mb, np.arange(0.3, float(mb[-1]) + 0.6, 0.6)


def _score_hint(answer: Any, name: str, mine: Any, other: Any) -> str | None:
    """Judge one alignment score on the case, at two sigmas; say if it is the other score."""
    mb, yb = (a.copy() for a in _case())  # the student's code may change its arguments
    for sigma in (0.05, 0.1):
        expected = mine(mb, yb, sigma=sigma)
        got = answer(mb, yb, sigma)
        if got is None:
            return f"{name} returned None: fill in the skeleton."
        try:
            g = float(got)
        except (TypeError, ValueError):
            return f"{name} returned {type(got).__name__}; it should return one number in [0, 1]."
        if np.isclose(g, expected, rtol=1e-6, atol=1e-12):
            continue
        if np.isclose(g, other(mb, yb, sigma=sigma), rtol=1e-6):
            return "that is the other score: check which set of beats you average over."
        frames = sigma * 60.0
        if np.isclose(g, mine(mb, yb, sigma=min(frames, 0.999)), rtol=1e-6):
            return "sigma is in seconds here (0.05 s = 3 frames at 60 fps), not in frames."
        if not 0.0 <= g <= 1.0:
            return f"{name} gave {g:.3f}, outside [0, 1]: each term is a Gaussian in (0, 1]."
        return f"{name} differs at sigma = {sigma} s (got {g:.4f})."
    return None


@exercise("dancers.alignment_motion")
def _alignment_motion(answer: Any) -> str | None:
    """``alignment_motion(motion_beats, music_beats, sigma)``: averaged over motion beats."""
    from ..evaluate.alignment import beat_alignment_motion, beat_alignment_music

    return _score_hint(answer, "alignment_motion", beat_alignment_motion, beat_alignment_music)


@exercise("dancers.alignment_music")
def _alignment_music(answer: Any) -> str | None:
    """``alignment_music(motion_beats, music_beats, sigma)``: averaged over music beats."""
    from ..evaluate.alignment import beat_alignment_motion, beat_alignment_music

    return _score_hint(answer, "alignment_music", beat_alignment_music, beat_alignment_motion)


@exercise("dancers.every_other_beat")
def _every_other_beat(answer: Any) -> str | None:
    """``(motion-averaged, music-averaged)`` scores of a dancer who marks every second
    beat exactly, on a steady song: a value, not a function."""
    from ..evaluate.alignment import alignment_scores

    music = np.arange(0.5, 20.5, 0.5)  # 40 beats; the dancer marks 20 of them
    sc = alignment_scores(music[::2], music)
    expected = (sc["alignment_motion"], sc["alignment_music"])
    if answer is None:
        return "every_other_beat is None: give the pair (motion-averaged, music-averaged)."
    try:
        a, b = (float(x) for x in answer)
    except (TypeError, ValueError):
        return "give a pair of two numbers: (score over motion beats, score over music beats)."
    ok = np.isclose([a, b], expected, atol=0.02)
    if ok.all():
        return None
    if np.isclose(a, expected[1], atol=0.02) and np.isclose(b, expected[0], atol=0.02):
        return "the two scores are swapped: the first averages over the motion beats."
    which = "first (over motion beats)" if not ok[0] else "second (over music beats)"
    return (
        f"the {which} score is not right: how far is each averaged beat from the "
        "nearest beat of the other kind?"
    )
