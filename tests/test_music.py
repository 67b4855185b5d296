"""Tests of beatsync.music: beat-interval sound level, synthetic songs, beat tracking."""

from __future__ import annotations

import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.music import beat_rms_db, music_intensity, track_music_beats
from beatsync.synth.audio import drum_song

SR = 8000


def test_sine_level_known_answer():
    t = np.arange(4 * SR) / SR
    y = 0.5 * np.sin(2 * np.pi * 100 * t)
    beats = np.array([0.0, 1.0, 2.0, 3.0])
    level = beat_rms_db(y, SR, beats)
    np.testing.assert_allclose(level, 20 * np.log10(0.5 / np.sqrt(2)), atol=1e-3)


def test_levels_follow_gain_and_silence_floor():
    t = np.arange(3 * SR) / SR
    y = np.sin(2 * np.pi * 50 * t)
    y[SR : 2 * SR] *= 0.1  # -20 dB
    y[2 * SR :] = 0.0
    level = beat_rms_db(y, SR, [0.0, 1.0, 2.0, 2.99])
    np.testing.assert_allclose(level[0] - level[1], 20.0, atol=1e-2)
    assert level[2] == pytest.approx(-100.0)
    z = music_intensity(y, SR, [0.0, 1.0, 2.0, 2.99])
    np.testing.assert_allclose([z.mean(), z.std()], [0, 1], atol=1e-12)
    assert z[0] > z[1] > z[2]


def test_drum_song_sections_are_audible():
    song = drum_song(20.0, bpm=120, sr=SR, section_beats=8, seed=3)
    level = beat_rms_db(song.y, song.sr, song.beats)
    gains = song.gain_db[:-1]
    # mean level per section tracks the section gain
    secs = np.arange(level.size) // 8
    mean_level = np.array([level[secs == s].mean() for s in np.unique(secs)])
    mean_gain = np.array([gains[secs == s].mean() for s in np.unique(secs)])
    assert np.corrcoef(mean_level, mean_gain)[0, 1] > 0.95
    np.testing.assert_allclose(np.diff(song.beats), 0.5, atol=2e-3)


def test_tracker_finds_song_beats():
    song = drum_song(12.0, bpm=120, sr=22050, seed=0)
    est = track_music_beats(song.y, song.sr)
    ref = song.beats[song.beats > 2.0]
    hit = np.min(np.abs(ref[:, None] - est[None, :]), axis=1) < 0.07
    assert hit.mean() > 0.8


@pytest.mark.parametrize(
    ("y", "beats"),
    [
        (np.zeros(SR), [0.0, 0.5]),  # fine for levels, refused by the tracker below
    ],
)
def test_silence_has_no_beats(y, beats):
    assert beat_rms_db(y, SR, beats)[0] == pytest.approx(-100.0)
    with pytest.raises(ParameterError, match="silent"):
        track_music_beats(y, SR)


@pytest.mark.parametrize(
    "beats",
    [
        [0.5],  # a single beat: no interval
        [500.0, 1000.0],  # milliseconds
        [0.2, 0.1],  # not increasing
        [],
    ],
)
def test_bad_beats(beats):
    y = np.random.default_rng(0).normal(size=2 * SR)
    with pytest.raises(ParameterError):
        beat_rms_db(y, SR, beats)


def test_quiet_music_is_not_silence():
    # one silence threshold (beatsync.beats.SILENCE_PEAK = 1e-7) for level and tracker;
    # music.py used 1e-6 and refused this -130 dBFS click track as "silent"
    from beatsync.synth.audio import beat_times, click_track

    ref = beat_times(120, duration=8.0, start=0.3)
    y = click_track(ref, sr=22050, duration=8.0)
    y = y / np.max(np.abs(y)) * 3e-7
    est = track_music_beats(y, 22050)
    hit = np.min(np.abs(ref[:, None] - est[None, :]), axis=1) < 0.07
    assert hit.mean() > 0.9
    with pytest.raises(ParameterError, match="silent"):
        track_music_beats(y * 0.1, 22050)


def test_tempo_range_reaches_the_tracker():
    # a drum song at 120 BPM; searched at 50-70 BPM, every other beat is taken
    song = drum_song(12.0, bpm=120, sr=22050, seed=0)
    est = track_music_beats(song.y, song.sr, min_bpm=50, max_bpm=70)
    assert np.median(np.diff(est)) == pytest.approx(1.0, rel=0.03)
    with pytest.raises(ParameterError, match="min_bpm"):
        track_music_beats(song.y, song.sr, min_bpm=5)


@pytest.mark.parametrize("bpm", [0.0, 2.0, 1200.0])
def test_bpm_checked_like_the_tracker(bpm):
    y = np.random.default_rng(0).normal(size=4 * SR)
    with pytest.raises(ParameterError, match=f"bpm={bpm!r}"):
        track_music_beats(y, SR, bpm=bpm)


def test_too_short_music_is_refused():
    y = np.random.default_rng(0).normal(size=SR // 2)  # 0.5 s
    with pytest.raises(ParameterError, match=r"0\.500 s"):
        track_music_beats(y, SR)


def test_beat_samples_go_through_units(monkeypatch):
    import beatsync.music as music
    from beatsync import validation as units

    calls = []

    def spy(times, **kw):
        calls.append(kw)
        return units.time_to_frames(times, **kw)

    monkeypatch.setattr(music, "time_to_frames", spy)
    beat_rms_db(np.ones(SR), SR, [0.0, 0.5, 1.0])
    assert calls and calls[0]["fps"] == SR and calls[0]["mode"] == "round"


def test_bad_audio():
    with pytest.raises(ParameterError, match="mono"):
        beat_rms_db(np.zeros((SR, 2)), SR, [0.0, 0.5])
    with pytest.raises(ParameterError):
        beat_rms_db(np.zeros(SR), 0, [0.0, 0.5])
    with pytest.raises(ParameterError):
        drum_song(10.0, level_range_db=(-10.0, 5.0))
