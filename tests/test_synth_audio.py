"""Tests of the synthetic beat test set (beatsync.synth.audio)."""

import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.synth.audio import (
    GROUPS,
    DrumSong,
    add_noise,
    beat_times,
    click_track,
    drum_pattern,
    drum_song,
    make_beat_test_set,
)


def test_beat_times_constant_tempo():
    b = beat_times(120, duration=10.0, start=0.3)
    np.testing.assert_allclose(np.diff(b), 0.5, atol=1e-6)
    assert b[0] == pytest.approx(0.3)
    assert b[-1] < 10.0


def test_beat_times_drift_and_change():
    d = np.diff(beat_times(120, duration=30.0, start=0.3, drift=0.05))
    assert d.min() == pytest.approx(0.5 / 1.05, rel=0.01)
    assert d.max() == pytest.approx(0.5 / 0.95, rel=0.01)
    b = beat_times(90, duration=20.0, start=0.3, bpm_end=120)
    d = np.diff(b)
    np.testing.assert_allclose(d[b[1:] < 9.0], 60 / 90, atol=1e-3)
    np.testing.assert_allclose(d[b[:-1] > 10.5], 0.5, atol=1e-3)


def test_click_track_onsets_sample_exact():
    sr = 22050
    beats = np.array([0.25, 0.75, 1.25])
    y = click_track(beats, sr=sr, duration=2.0)
    assert y.dtype == np.float32 and y.size == 2 * sr
    first = np.flatnonzero(np.abs(y) > 1e-6)[0]
    assert abs(first / sr - 0.25) < 2 / sr


def test_drum_pattern_deterministic_and_swing_offbeats():
    beats = beat_times(100, duration=6.0, start=0.2)
    a = drum_pattern(beats, sr=16000, duration=6.0, seed=3)
    b = drum_pattern(beats, sr=16000, duration=6.0, seed=3)
    np.testing.assert_array_equal(a, b)
    c = drum_pattern(beats, sr=16000, duration=6.0, swing=2 / 3, seed=3)
    assert not np.allclose(a, c)


def test_add_noise_snr():
    rng = np.random.default_rng(0)
    y = rng.standard_normal(20000)
    out = add_noise(y, snr_db=10.0, seed=1).astype(np.float64)
    scale = np.dot(out, y) / np.dot(y, y)  # out = scale * (y + noise)
    noise = out / scale - y
    snr = 10 * np.log10(np.mean(y**2) / np.mean(noise**2))
    assert snr == pytest.approx(10.0, abs=0.3)


def test_make_beat_test_set_shape():
    items = make_beat_test_set(duration=6.0, bpms=[60, 180], seed=1)
    assert len(items) == 2 * len(GROUPS) * 2
    assert len({it.name for it in items}) == len(items)
    for it in items:
        assert np.all(np.diff(it.beats) > 0) and it.beats[-1] < it.duration
        assert np.all(np.isfinite(it.y))
    change = [it for it in items if it.group == "change"]
    assert all(it.bpm_end != it.bpm for it in change)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"duration": 2.0},
        {"kinds": ["piano"]},
        {"groups": ["reverb"]},
        {"bpms": [0.5]},
        {"sr": 0},
    ],
)
def test_make_beat_test_set_bad(kwargs):
    with pytest.raises(ParameterError):
        make_beat_test_set(**kwargs)


def test_click_track_bad_beats():
    with pytest.raises(ParameterError):
        click_track([1.0, 0.5], sr=22050, duration=2.0)


def test_drum_song_known_beats_and_gains():
    song = drum_song(10.0, bpm=120, sr=8000, section_beats=4, level_range_db=(-20.0, -6.0), seed=1)
    assert isinstance(song, DrumSong)
    assert song.y.dtype == np.float32 and song.y.size == 10 * 8000
    np.testing.assert_allclose(song.beats, beat_times(120, duration=10.0, start=0.5))
    assert song.duration == pytest.approx(10.0)
    # one gain per 4-beat section, inside the range, seeded
    assert np.all((song.gain_db >= -20.0) & (song.gain_db <= -6.0))
    assert np.all(song.gain_db[:4] == song.gain_db[0]) and song.gain_db[4] != song.gain_db[0]
    again = drum_song(10.0, bpm=120, sr=8000, section_beats=4, level_range_db=(-20.0, -6.0), seed=1)
    np.testing.assert_array_equal(song.y, again.y)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"level_range_db": (-10.0, 5.0)},
        {"section_beats": 0},
        {"bpm": -120.0},
    ],
)
def test_drum_song_bad_input(kwargs):
    with pytest.raises(ParameterError):
        drum_song(10.0, **kwargs)


def test_music_stage_does_not_import_synth():
    import ast
    import inspect

    from beatsync import music

    tree = ast.parse(inspect.getsource(music))
    names = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    assert not any("synth" in name for name in names)
    assert not hasattr(music, "drum_song")


def test_meter_pattern_accents_the_downbeats():
    from beatsync.synth.audio import meter_pattern

    ref = beat_times(90, duration=8.0, start=0.5)
    y = meter_pattern(ref, meter="3/4", sr=8000, duration=8.0).astype(np.float64)
    assert y.size == 64000
    # the kick (on every third beat) carries the most energy in the 20 ms after its onset
    energy = [np.sum(y[int(t * 8000) : int(t * 8000) + 160] ** 2) for t in ref[:9]]
    assert np.argmax(energy[:3]) == 0 and energy[3] > energy[4]


def test_meter_pattern_unknown_meter():
    from beatsync.synth.audio import meter_pattern

    with pytest.raises(ParameterError, match="meter='5/4'"):
        meter_pattern([0.5, 1.0], meter="5/4", duration=2.0)
