"""Tests of the dance-music beat alignment scores (beatsync.evaluate.alignment)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.evaluate.alignment import (
    alignment_scores,
    beat_alignment_motion,
    beat_alignment_music,
    nearest_distance,
    offset_control,
    sync_residuals,
)

MUSIC = np.arange(0.5, 20.0, 0.5)  # 120 BPM impulse train


def test_perfect_alignment_scores_one():
    assert beat_alignment_motion(MUSIC, MUSIC) == 1.0
    assert beat_alignment_music(MUSIC, MUSIC) == 1.0


@pytest.mark.parametrize("shift", [0.01, 0.03, 0.05, 0.1])
def test_shift_lowers_score_by_gaussian(shift):
    expected = np.exp(-(shift**2) / (2 * 0.05**2))
    assert np.isclose(beat_alignment_motion(MUSIC + shift, MUSIC), expected)
    assert np.isclose(beat_alignment_music(MUSIC + shift, MUSIC), expected)


def test_scores_decrease_with_shift():
    s = [beat_alignment_motion(MUSIC + d, MUSIC) for d in (0.0, 0.02, 0.05, 0.1, 0.25)]
    assert all(a > b for a, b in zip(s, s[1:], strict=False))
    assert s[-1] < 1e-5


def test_the_two_scores_differ_on_half_tempo_dance():
    dance = MUSIC[::2]  # dancer marks every other beat
    assert beat_alignment_motion(dance, MUSIC) == 1.0  # every motion beat is on a beat
    assert np.isclose(beat_alignment_music(dance, MUSIC), 0.5, atol=0.02)  # half the beats danced
    extra = np.sort(np.r_[MUSIC, MUSIC[:-1] + 0.25])  # double-time dance
    assert np.isclose(beat_alignment_music(extra, MUSIC), 1.0)
    assert np.isclose(beat_alignment_motion(extra, MUSIC), 0.5, atol=0.02)


def test_sigma_scales():
    a = beat_alignment_motion(MUSIC + 0.05, MUSIC, sigma=0.1)
    assert np.isclose(a, np.exp(-0.125))


def test_alignment_scores_dict_and_span():
    d = alignment_scores(MUSIC[:10], MUSIC, span=(0.0, 5.2))
    assert d["alignment_motion"] == 1.0 and d["alignment_music"] == 1.0
    assert d["n_music_beats"] == 10 and d["sigma_s"] == 0.05


def test_a_beat_on_the_span_edge_matches_one_just_outside():
    # the song's last beat at 5.0 s is danced one 25 fps frame later, just after the span
    # ends there: it is danced (it counted 0 when the other side was cut at the span too)
    motion = MUSIC[:10] + 0.04
    d = alignment_scores(motion, MUSIC, span=(0.5, 5.0))
    assert d["n_music_beats"] == 10 and d["n_motion_beats"] == 9
    assert d["alignment_music"] == pytest.approx(np.exp(-0.04**2 / (2 * 0.05**2)))
    # a beat far outside still does not count
    d = alignment_scores(MUSIC[:9], MUSIC, span=(0.5, 5.0))
    assert d["alignment_music"] == pytest.approx(0.9)


@pytest.mark.parametrize(
    "span, named",
    [(("a", 2.0), "span start='a'"), ((0.0, None), "span end=None"), (5.0, "span=5.0"),
     ((1.0, 2.0, 3.0), "span=(1.0, 2.0, 3.0)"), ((0.0, float("nan")), "span end=nan")],
)  # fmt: skip
def test_a_bad_span_is_refused_by_name(span, named):
    with pytest.raises(ParameterError, match=re.escape(named)):
        alignment_scores(MUSIC[:10], MUSIC, span=span)


def test_nearest_distance():
    d = nearest_distance([0.1, 0.74, 3.0], [0.0, 0.5, 1.0])
    assert np.allclose(d, [0.1, 0.24, 2.0])


def test_empty_warns_and_scores_zero():
    with pytest.warns(BeatsyncWarning):
        assert beat_alignment_motion([], MUSIC) == 0.0
    with pytest.warns(BeatsyncWarning):
        assert beat_alignment_music(MUSIC, []) == 0.0


def test_offset_control_is_lower_than_perfect():
    c = offset_control(MUSIC, MUSIC, n_trials=200, seed=0)
    # uniform offsets over a 0.5 s beat: mean Gaussian about sqrt(2 pi) 0.05 / 0.5 = 0.25
    assert 0.15 < c["alignment_motion_mean"] < 0.35
    assert c["n_trials"] == 200
    assert offset_control(MUSIC, MUSIC, seed=0) == offset_control(MUSIC, MUSIC, seed=0)


@pytest.mark.parametrize(
    "motion, music, sigma, match",
    [
        (MUSIC, MUSIC, 3, "frames"),  # sigma in frames
        (MUSIC, MUSIC, 0.0, "sigma"),
        (MUSIC, MUSIC, float("nan"), "sigma"),
        (MUSIC[::-1], MUSIC, 0.05, "increasing"),
        (MUSIC, np.c_[MUSIC, MUSIC], 0.05, "1-D"),
        (np.r_[-1.0, MUSIC], MUSIC, 0.05, "negative"),
    ],
)
def test_bad_inputs(motion, music, sigma, match):
    with pytest.raises(ParameterError, match=match):
        beat_alignment_motion(motion, music, sigma=sigma)


def test_phase_consistency_locked_and_drifting():
    from beatsync.evaluate.alignment import beat_phase_consistency

    assert np.isclose(beat_phase_consistency(MUSIC + 0.1, MUSIC), 1.0)  # locked at 0.2 phase
    drift = np.arange(0.5, 19.0, 0.5 * 1.0556)  # 5.6 % slower: phase turns twice
    assert beat_phase_consistency(drift, MUSIC) < 0.3


def test_sync_residuals_and_nearest_frame():
    r = sync_residuals([1.0, 2.004], [1.0, 2.0], fps=100.0)
    assert np.allclose(r["residual_ms"], [0.0, 4.0])
    assert r["max_abs_residual_ms"] == pytest.approx(4.0)
    assert np.allclose(r["residual_nearest_frame_ms"], [0.0, 0.0], atol=1e-9)  # frame 200
    assert r["max_abs_residual_frames"] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(
    "landed, targets, fps, match",
    [
        ([1.0, 2.0], [1.0], None, "one target"),
        ([2.0, 1.0], [1.0, 2.0], None, "increasing"),
        ([1.0, 2.0], [1.0, 2.0], 0.0, "fps"),
    ],
)
def test_sync_residuals_bad_inputs(landed, targets, fps, match):
    with pytest.raises(ParameterError, match=match):
        sync_residuals(landed, targets, fps=fps)


def test_alignment_module_runs_no_stage():
    import ast
    from pathlib import Path

    import beatsync.evaluate.alignment as mod

    tree = ast.parse(Path(mod.__file__).read_text())
    imported = {n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    imported |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    for stage in ("segment", "sync", "motion_beats", "beats", "music", "graph"):
        assert not any(m.lstrip(".").split(".")[0] == stage for m in imported), imported


def test_evaluate_returns_every_metric():
    from beatsync.evaluate.alignment import evaluate

    d = evaluate(MUSIC + 0.01, MUSIC)
    assert {"alignment_motion", "alignment_music", "phase_consistency"} <= set(d)
    assert d["phase_consistency"] == pytest.approx(1.0)
