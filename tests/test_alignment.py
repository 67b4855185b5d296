"""Tests of the dance-music beat alignment scores (beatsync.evaluate.alignment)."""

from __future__ import annotations

import numpy as np
import pytest

from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.evaluate.alignment import (
    alignment_scores,
    beat_alignment_motion,
    beat_alignment_music,
    motion_alignment,
    nearest_distance,
    offset_control,
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


def test_motion_alignment_on_motion(monkeypatch):
    from beatsync.evaluate import alignment

    monkeypatch.setattr(alignment, "_kinematic_beats", lambda motion, **kw: MUSIC[:8] - 0.5)

    class _M:
        duration = 3.7

    d = motion_alignment(_M(), MUSIC, offset=0.5)
    assert d["alignment_motion"] == 1.0 and d["alignment_music"] == 1.0


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


def test_kinematic_phase_offset():
    from beatsync.evaluate.alignment import kinematic_phase_offset

    assert np.isclose(kinematic_phase_offset(MUSIC + 0.1, MUSIC), 0.1)
    assert np.isclose(kinematic_phase_offset(MUSIC[1:] - 0.1, MUSIC), -0.1)
    with pytest.raises(ParameterError, match="no motion beat"):
        kinematic_phase_offset([30.0], MUSIC)


def test_evaluate_sync_aligned_accents_hit_the_beat():
    from beatsync.evaluate.alignment import evaluate_sync
    from beatsync.motion import Joint, Motion, Skeleton

    fps = 60.0
    skel = Skeleton((
        Joint("hip", -1, np.zeros(3), ("Xposition", "Yposition", "Zposition")),
        Joint("end", 0, np.array([0.0, 0.5, 0.0]), (), True),
    ))
    t = np.arange(int(12 * fps)) / fps
    # a bounce of period 1.1 s whose speed minima (turning points) sit at phase 0.3
    v = np.zeros((t.size, 3))
    v[:, 1] = np.cos(2 * np.pi * (t / 1.1 - 0.3))
    m = Motion(v, fps, skel.channel_names(), skel, "bounce")
    bounds = np.arange(0.0, 11.9, 1.1)
    beats = 0.5 + np.arange(40) * 0.5  # 1 period -> 2 beats of 0.5 s
    row = evaluate_sync(m, beats, boundaries=bounds, n_control=20)
    assert row["max_residual_frames"] <= 0.5 + 1e-6
    assert row["after_phase"] > 0.9  # phase-locked after sync
    assert row["aligned_motion"] > 0.9  # and on the beat once the lag is removed
    assert row["aligned_motion"] > row["control_motion"]
