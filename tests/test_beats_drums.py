"""Tests of the drum-pattern cue of the metrical level (beatsync.beats.drums)."""

import numpy as np
import pytest

from beatsync.beats import track_beats
from beatsync.beats.drums import (
    NOISE_LEVEL,
    alternation_cue,
    drum_envelopes,
)
from beatsync.beats.tempo import analysis_windows
from beatsync.errors import ParameterError
from beatsync.evaluate.beats import evaluate
from beatsync.synth.audio import beat_times, click_track, drum_pattern, make_beat_test_set

SR = 22050
FPS = SR / 128


def _cue_at(y, bpms, seconds):
    """The cue's mean over the windows at each tempo in ``bpms``."""
    n = int(seconds * FPS)
    starts, stops, _ = analysis_windows(n, FPS, 8.0, 1.0)
    periods = 60.0 / np.asarray(bpms, dtype=float)
    cue = alternation_cue(drum_envelopes(y, SR, FPS, n), FPS, starts, stops, periods)
    return cue.mean(axis=1)


@pytest.mark.parametrize("bpm", [120.0, 180.0])
def test_cue_marks_the_beat_of_a_rock_pattern(bpm):
    # kick on beats 1 and 3, snare on 2 and 4: they alternate at the beat, and each
    # repeats every two beats (at 60 BPM, two beats do not fit 4 times in a window)
    ref = beat_times(bpm, duration=20.0, start=0.3)
    y = drum_pattern(ref, sr=SR, duration=20.0, seed=2)
    eighth, beat, half = _cue_at(y, [2 * bpm, bpm, bpm / 2], 20.0)
    assert beat > 0.3
    assert half == 0.0  # each drum repeats at twice the beat: no alternation there
    assert eighth < 0.05


def test_cue_is_silent_on_click_tracks_and_noise():
    ref = beat_times(120, duration=20.0, start=0.3)
    clicks = click_track(ref, sr=SR, duration=20.0)
    noise = np.random.default_rng(3).standard_normal(20 * SR)
    for y in (clicks, noise):
        cue = _cue_at(y, np.linspace(40, 240, 81), 20.0)
        assert np.all(cue < 0.05)


def test_envelopes_put_the_kick_low_and_the_snare_higher():
    ref = beat_times(100, duration=10.0, start=0.3)
    y = drum_pattern(ref, sr=SR, duration=10.0, seed=0)
    n = int(10.0 * FPS)
    low, mid = drum_envelopes(y, SR, FPS, n)
    assert low.shape == mid.shape == (n,)
    frames = np.rint(ref * FPS).astype(int)
    near = lambda env, f: env[max(f - 6, 0) : f + 7].max()  # noqa: E731
    kicks = np.array([near(low, f) for f in frames[0::2]])
    snares = np.array([near(low, f) for f in frames[1::2]])
    assert np.median(kicks) > 3 * np.median(snares)  # the low band hears the kick
    mid_snares = np.median([near(mid, f) for f in frames[1::2]])
    assert mid_snares > 2 * np.median([near(mid, f) for f in frames[0::2]])  # the other the snare


def test_envelopes_at_44k_match_22k():
    # audio above 11.025 kHz is resampled first: the same drums give the same envelopes
    ref = beat_times(100, duration=10.0, start=0.3)
    n = int(10.0 * FPS)
    e22 = drum_envelopes(drum_pattern(ref, sr=SR, duration=10.0, seed=0), SR, FPS, n)
    e44 = drum_envelopes(drum_pattern(ref, sr=2 * SR, duration=10.0, seed=0), 2 * SR, FPS, n)
    for a, b in zip(e22, e44, strict=True):
        assert np.corrcoef(a, b)[0, 1] > 0.95


def test_alternation_cue_by_hand():
    # a kick every 40 frames, a snare 20 frames after each: alternation at lag 20
    n = 400
    env = np.zeros((2, n))
    env[0, 5::40] = 1.0
    env[1, 25::40] = 1.0
    periods = np.array([10, 20, 40]) / FPS
    cue = alternation_cue(env, FPS, np.array([0]), np.array([n]), periods)[:, 0]
    assert cue[1] > 0.5
    assert cue[0] == 0.0 and cue[2] == 0.0
    # fewer than four cycles in the window: not scored (at lag 140 the kick and the
    # snare do alternate, 20 frames off a whole period)
    assert alternation_cue(env, FPS, np.array([0]), np.array([n]), np.array([140 / FPS]))[0, 0] == 0
    # a silent band: nothing to correlate
    quiet = env.copy()
    quiet[1] = 0.0
    assert not alternation_cue(quiet, FPS, np.array([0]), np.array([n]), periods).any()


def test_noise_level_is_subtracted(monkeypatch):
    import beatsync.beats.drums as drums

    n = 400
    env = np.zeros((2, n))
    env[0, 5::40] = 1.0
    env[1, 25::40] = 1.0
    args = (FPS, np.array([0]), np.array([n]), np.array([20 / FPS]))
    cue = alternation_cue(env, *args)[0, 0]
    monkeypatch.setattr(drums, "NOISE_LEVEL", 0.0)
    raw = alternation_cue(env, *args)[0, 0]
    assert raw - cue == pytest.approx(NOISE_LEVEL, abs=1e-12)
    # uncorrelated noise on top: less alternation, and never below 0 once the level is off
    monkeypatch.setattr(drums, "NOISE_LEVEL", NOISE_LEVEL)
    noisy = env + 3.0 * np.random.default_rng(0).random((2, n))
    assert 0.0 <= alternation_cue(noisy, *args)[0, 0] < cue


@pytest.mark.parametrize("bpm, without", [(60.0, 120.0), (180.0, 90.0)])
def test_drum_pattern_at_the_edges_is_tapped_at_its_beat(bpm, without):
    # the same pattern at 60 and 180 BPM (the synthetic set's items, seed 1)
    (item,) = make_beat_test_set(bpms=[bpm], kinds=["drums"], groups=["clean"], seed=1)
    bt = track_beats(item.y, item.sr)
    assert bt.tempo == pytest.approx(bpm, rel=0.03)
    assert evaluate(item.beats, bt.beats, min_beat_time=0.0)["F-measure"] >= 0.95
    # the metrical model alone (a known gap it leaves): the tactus prior puts both an
    # octave towards 110 BPM
    alone = track_beats(item.y, item.sr, drum_weight=0)
    assert alone.tempo == pytest.approx(without, rel=0.03)


def test_tempo_change_of_drums_keeps_the_level():
    # 120 -> 160 BPM halfway: the second half was tapped at 80 BPM
    (item,) = make_beat_test_set(bpms=[120], kinds=["drums"], groups=["change"], seed=0)
    bt = track_beats(item.y, item.sr)
    s = evaluate(item.beats, bt.beats, min_beat_time=0.0)
    assert s["F-measure"] >= 0.95
    assert bt.tempo_curve[-1] == pytest.approx(160, rel=0.03)


def test_known_tempo_skips_the_cue(monkeypatch):
    import beatsync.beats.tracker as tracker

    def boom(*args, **kwargs):
        raise AssertionError("the drum cue was computed for a known tempo")

    monkeypatch.setattr(tracker, "drum_envelopes", boom)
    ref = beat_times(120, duration=10.0, start=0.3)
    bt = track_beats(drum_pattern(ref, sr=SR, duration=10.0), SR, bpm=120)
    assert bt.tempo == pytest.approx(120, rel=0.01)
    with pytest.raises(AssertionError, match="drum cue"):
        track_beats(drum_pattern(ref, sr=SR, duration=10.0), SR)


@pytest.mark.parametrize("weight", [-1.0, float("nan"), "heavy"])
def test_bad_drum_weight(weight):
    y = click_track(beat_times(120, duration=5.0, start=0.3), sr=SR, duration=5.0)
    with pytest.raises(ParameterError, match="drum_weight"):
        track_beats(y, SR, drum_weight=weight)


def test_study_sweeps_the_drum_weight():
    from beatsync.study import paper_a_beats as study

    items = make_beat_test_set(duration=20.0, bpms=[180], kinds=["drums"], groups=["clean"])
    sweep = study.drum_weight_sweep(items, [0.0, 4.0])
    assert sweep["drum_weight"].tolist() == [0.0, 4.0]
    assert sweep["default"].tolist() == [False, True]
    without, with_cue = sweep["F"]
    assert without < 0.7 and with_cue >= 0.95  # tapped at half without the cue
