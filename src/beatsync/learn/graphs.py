"""Exercises of ``notebooks/tutorials/04_motion_graphs.ipynb`` (paper B), judged on a
CMU salsa clip and a synthetic drum song."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import exercise
from .resampling import compare_arrays

__all__: list[str] = []


@exercise("graphs.transition_weight")
def _transition_weight(answer: Any) -> str | None:
    """``transition_weight(rd)``: eq. 2 as the paper writes it, on an array of rd."""
    from ..graph import transition_weight

    rd = np.array([0.3, 1.0, 1.99, 2.0, 2.01, 2.5, 2.999])
    expected = transition_weight(rd, "paper")
    got = answer(rd)
    hint = compare_arrays(got, expected, what="transition_weight(rd)")
    if hint is None:
        return None
    g = np.asarray(got, dtype=np.float64)
    if g.shape == rd.shape and np.allclose(g, rd):
        return "you returned rd itself (the 'rd' rule); eq. 2 as written has a floor."
    small = rd < 2.0
    if g.shape == rd.shape and np.allclose(g[~small], rd[~small]):
        return "right above 2; check the transitions with rd below 2."
    return hint


@exercise("graphs.interval_intensity")
def _interval_intensity(answer: Any) -> str | None:
    """``interval_intensity(positions, beat_frames, fps)``: mean kinetic energy per interval."""
    from .. import datasets
    from ..motion_beats import interval_intensity, kinematic_beat_frames, motion_positions

    motion = datasets.load_salsa("60_01").slice_frames(0, 600)
    pos = motion_positions(motion)
    frames = kinematic_beat_frames(pos, fps=motion.fps)
    expected = interval_intensity(pos, frames, fps=motion.fps)
    got = answer(pos, frames, motion.fps)
    hint = compare_arrays(
        got, expected, what="interval_intensity(positions, beat_frames, fps)", unit="m^2/s^2"
    )
    if hint is None:
        return None
    g = np.asarray(got, dtype=np.float64)
    if g.shape == expected.shape:
        if np.allclose(g, 2 * expected, rtol=1e-6):
            return "off by a factor of 2: kinetic energy is half of mass times speed squared."
        if np.allclose(g, expected / motion.fps**2, rtol=1e-3):
            return "velocities are per frame here; multiply the frame differences by fps."
    return hint


@exercise("graphs.music_z")
def _music_z(answer: Any) -> str | None:
    """``music_z(y, sr, beats)``: z-scored sound pressure level per beat interval."""
    from ..music import beat_rms_db, music_intensity
    from ..synth.audio import drum_song

    song = drum_song(12.0, bpm=110.0, seed=1, sr=22050)
    expected = music_intensity(song.y, song.sr, song.beats)
    got = answer(song.y, song.sr, song.beats)
    # float32 audio: sums in another order differ in the 6th digit
    hint = compare_arrays(got, expected, what="music_z(y, sr, beats)", rtol=1e-4, atol=1e-4)
    if hint is None:
        return None
    g = np.asarray(got, dtype=np.float64)
    level = beat_rms_db(song.y, song.sr, song.beats)
    if g.shape == expected.shape:
        if np.allclose(g, level, rtol=1e-4):
            return "that is the level in dB; the search needs it z-scored over the song."
        lin = 10 ** (level / 20)
        if np.allclose(g, (lin - lin.mean()) / lin.std(), rtol=1e-4, atol=1e-4):
            return "you z-scored the RMS amplitude; z-score the level in dB (20 log10 RMS)."
        if np.allclose(g, (level - level.mean()) / level.std(ddof=1), rtol=1e-4, atol=1e-4):
            return "the standard deviation is the population one (numpy's default, ddof=0)."
    return hint
