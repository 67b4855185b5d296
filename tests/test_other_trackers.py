"""The registry of beat trackers (ours and the others a user would pick instead)."""

import dataclasses
import importlib.util
import warnings

import numpy as np
import pytest

from beatsync import other_trackers as trackers
from beatsync.beats import track_beats
from beatsync.errors import ParameterError
from beatsync.evaluate.beats import evaluate
from beatsync.synth.audio import beat_times, drum_pattern

SR = 22050
HAS_ESSENTIA = importlib.util.find_spec("essentia") is not None


@pytest.fixture(scope="module")
def song():
    ref = beat_times(120, duration=10.0, start=0.37)
    return drum_pattern(ref, sr=SR, duration=10.0), ref


def test_registry_names_and_descriptions():
    assert list(trackers.TRACKERS) == ["psf", "librosa", "essentia-degara", "essentia-multifeature"]
    for name, tracker in trackers.TRACKERS.items():
        assert tracker.name == name and tracker.description
    avail = trackers.available()
    assert avail["psf"] and avail["librosa"]
    assert avail["essentia-degara"] == HAS_ESSENTIA


_METHODS = [
    "psf",
    "librosa",
    pytest.param(
        "essentia-degara",
        marks=pytest.mark.skipif(not HAS_ESSENTIA, reason="optional essentia not installed"),
    ),
    pytest.param(
        "essentia-multifeature",
        marks=pytest.mark.skipif(not HAS_ESSENTIA, reason="optional essentia not installed"),
    ),
]


@pytest.mark.parametrize("name", _METHODS)
def test_every_method_tracks_a_drum_pattern(song, name):
    y, ref = song
    est = trackers.track(name, y, SR)
    assert est.dtype == np.float64 and est.ndim == 1
    assert np.all(np.diff(est) > 0)
    assert evaluate(ref, est, min_beat_time=1.0)["F-measure"] >= 0.9, name


@pytest.mark.parametrize("name", _METHODS)
def test_every_method_searches_the_tempo_range_given(song, name):
    # the 120 BPM pattern, told to look between 45 and 75 BPM: its half tempo, on the
    # kicks or on the snares
    y, ref = song
    est = trackers.track(name, y, SR, min_bpm=45, max_bpm=75)
    assert 55 <= 60.0 / np.median(np.diff(est)) <= 65, name
    f = max(evaluate(r, est, min_beat_time=1.0)["F-measure"] for r in (ref[::2], ref[1::2]))
    assert f >= 0.9, name


@pytest.mark.parametrize("name", _METHODS)
def test_a_range_puts_every_method_on_the_real_samples_beat(name):
    # the madmom sample (2.8 s, 88 BPM) is tapped at another level by every method told
    # nothing here; a range around its tempo puts ours and librosa on its 4 annotated
    # beats and essentia's two on 3 of them (F 0.857)
    from beatsync import datasets

    y, sr, ref = datasets.load_madmom_sample()
    est = trackers.track(name, y, sr, min_bpm=75, max_bpm=101)
    assert evaluate(ref, est, min_beat_time=0.0)["F-measure"] >= 0.85, name


@pytest.fixture(scope="module")
def song80():
    ref = beat_times(80, duration=12.0, start=0.37)
    return drum_pattern(ref, sr=SR, duration=12.0)


@pytest.mark.parametrize("name", _METHODS)
def test_one_bound_alone_moves_every_method(song80, name):
    # an 80 BPM pattern: librosa taps it at 160 BPM told nothing, the others at 80; a
    # single bound across the other level moves each (the other bound stays the default)
    def bpm(**tempo):
        return 60.0 / np.median(np.diff(trackers.track(name, song80, SR, **tempo)))

    if name == "librosa":
        assert 155 <= bpm() <= 165 and 77 <= bpm(max_bpm=100) <= 83
    else:
        assert 77 <= bpm() <= 83 and 155 <= bpm(min_bpm=110) <= 165


@pytest.mark.parametrize("name", _METHODS)
def test_beats_outside_the_range_given_warn(song80, name):
    # told 180-250 BPM, the 80 BPM pattern is tapped at 240 by ours (three beats per
    # beat, inside the range) and at 161 by librosa (its range bounds a tempo estimate,
    # not the beats); essentia's two take the range as a preference and answer 80-162
    # BPM, different from one call to the next, so for them the test checks only that
    # the warning matches where their beats are
    from beatsync.errors import BeatsyncWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        est = trackers.track(name, song80, SR, min_bpm=180, max_bpm=250)
    outside = [w for w in caught if issubclass(w.category, BeatsyncWarning)]
    bpm = 60.0 / np.median(np.diff(est))
    inside = 180 / 1.05 <= bpm <= 250 * 1.05
    if name == "psf":
        assert 180 <= bpm <= 250, bpm
    if name == "librosa":
        assert 155 <= bpm <= 165, bpm
    if inside:
        assert not outside, name
    else:
        assert len(outside) == 1, name
        assert (
            f"{name} tapped a median tempo of {bpm:.0f} BPM, outside the range it was "
            "given (180-250 BPM)" in str(outside[0].message)
        )
        assert "psf keeps to the range" in str(outside[0].message)
    with warnings.catch_warnings(record=True) as caught:  # inside the range: silent
        warnings.simplefilter("always")
        trackers.track(name, song80, SR, min_bpm=60, max_bpm=100)
    assert not [w for w in caught if issubclass(w.category, BeatsyncWarning)], name


def test_librosa_range_without_a_tempo_step_is_refused(song):
    # librosa's tempo is one lag of its onset autocorrelation: at 22.05 kHz and hop 512
    # the steps near 190 BPM are 184.6 and 198.8, so 185-198 holds none; unchecked it
    # returned a single beat at an infinite tempo
    from beatsync.beats.tracker import librosa_tempo_steps

    steps = librosa_tempo_steps(SR)
    assert not np.any((steps >= 185) & (steps <= 198))
    y, _ = song
    with pytest.raises(ParameterError, match=r"185-198 BPM.* 184\.6 and 198\.8 BPM"):
        trackers.track("librosa", y, SR, min_bpm=185, max_bpm=198)
    with pytest.raises(ParameterError, match="185-198 BPM"):
        track_beats(y, SR, method="librosa", min_bpm=185, max_bpm=198)
    est = trackers.track("librosa", y, SR, min_bpm=180, max_bpm=200)  # holds two steps
    assert 180 <= 60.0 / np.median(np.diff(est)) <= 200
    from beatsync.beats.tracker import LIBROSA_MAX_TEMPO, librosa_tempo_prior

    top = steps[steps <= LIBROSA_MAX_TEMPO][-1]  # above the fastest step: one neighbour
    with pytest.raises(ParameterError, match=rf"nearest is {top:.1f} BPM"):
        librosa_tempo_prior(top + 0.5, LIBROSA_MAX_TEMPO - 0.1, sr=SR)
    with pytest.raises(ParameterError, match=r"60-100 BPM.*none at this sample rate$"):
        librosa_tempo_prior(60, 100, sr=100)  # no tempo step at all


def test_out_of_range_warning_for_ours_names_skipped_beats():
    # ours decodes only tempi inside the range, so a median outside it means beats
    # were skipped or doubled; the advice to use psf is for the other methods
    from beatsync.errors import BeatsyncWarning

    with pytest.warns(
        BeatsyncWarning, match="some beats were skipped or doubled; check the beats$"
    ):
        trackers._warn_out_of_range("psf", np.arange(0.0, 10.0, 0.5), {"min_bpm": 180.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        trackers._warn_out_of_range("psf", np.arange(0.0, 10.0, 0.5), {})  # no range given
        trackers._warn_out_of_range("psf", np.array([0.0, 0.5]), {"min_bpm": 180.0})  # 2 beats


def test_tempo_range_bounds_equal_to_the_default_are_none():
    # the same search as no bound, so a folder scored without it resumes with it
    assert trackers.check_tempo_range("librosa", 40, 240) == {}
    assert trackers.check_tempo_range("psf", 40.0, 200) == {"max_bpm": 200.0}
    assert trackers.check_tempo_range("essentia-degara", 40, 208) == {}
    narrowest = trackers.check_tempo_range("essentia-degara", 100, 120)  # exactly 20 apart
    assert narrowest == {"min_bpm": 100.0, "max_bpm": 120.0}


@pytest.mark.parametrize(
    "name, lo, hi, match",
    [
        ("psf", 120, 90, r"min_bpm 120\b.*max_bpm 90$"),
        ("psf", None, 30, r"max_bpm 30\b.*default min_bpm 40\b"),
        ("librosa", 300, None, r"min_bpm 300\b.*default max_bpm 240\b"),
        ("librosa", 330, 400, r"min_bpm 330\b.*320 BPM"),
        ("psf", float("nan"), None, "min_bpm=nan"),
        ("librosa", 500, None, r"min_bpm=500\b.*20-400 BPM"),
        ("essentia-degara", 30, None, r"min_bpm 30\b.*40 to 180.*psf"),
        ("essentia-degara", 75.5, None, r"min_bpm 75\.5\b.*40 to 180.*76$"),
        ("essentia-degara", 39.6, None, r"min_bpm 39\.6\b.*40 to 180.* 40$"),
        ("essentia-degara", None, 250.4, r"max_bpm 250\.4\b.*60 to 250.* 250$"),
        ("essentia-multifeature", None, 260, r"max_bpm 260\b.*60 to 250"),
        ("essentia-degara", 100, 110, r"min_bpm 100\b.*20 BPM.*max_bpm 110$"),
        ("essentia-degara", 190, None, r"min_bpm 190\b.*40 to 180"),
    ],
)
def test_tempo_range_a_method_does_not_take_is_refused(name, lo, hi, match):
    with pytest.raises(ParameterError, match=match):
        trackers.check_tempo_range(name, lo, hi)


@pytest.mark.skipif(not HAS_ESSENTIA, reason="optional essentia not installed")
def test_essentia_tempo_limits_are_essentias_own():
    es = trackers._essentia()
    for algo in (es.BeatTrackerDegara, es.BeatTrackerMultiFeature):
        params = {p["name"]: p for p in algo().getStruct()["parameters"]}
        assert params["minTempo"]["range"] == "[{},{}]".format(*trackers.ESSENTIA_TEMPO["min"])
        assert params["maxTempo"]["range"] == "[{},{}]".format(*trackers.ESSENTIA_TEMPO["max"])
        default = (params["minTempo"]["default"], params["maxTempo"]["default"])
        assert tuple(int(v) for v in default) == trackers.ESSENTIA_TEMPO["default"]


def test_tempo_range_defaults_stay_each_methods_own():
    assert trackers.check_tempo_range("psf") == {}
    assert trackers.check_tempo_range("essentia-degara", 60) == {"min_bpm": 60.0}
    assert trackers.check_tempo_range("librosa", None, 100.0) == {"max_bpm": 100.0}


def test_librosa_peer_at_another_rate(song):
    import librosa

    y, ref = song
    y44 = librosa.resample(y, orig_sr=SR, target_sr=44100)
    est = trackers.track("librosa", y44, 44100)
    assert evaluate(ref, est, min_beat_time=1.0)["F-measure"] >= 0.9


@pytest.mark.parametrize("orig, target", [(22050, 44100), (44100, 22050), (48000, 22050.5)])
def test_resample_audio_gives_librosa_resample_samples(orig, target):
    # io.resample_audio (the reader and the essentia trackers) replaces librosa.resample with
    # its default soxr_hq filter: the same samples, without importing librosa
    import librosa

    from beatsync.io import resample_audio

    y = np.random.default_rng(5).standard_normal(12345).astype(np.float32)
    np.testing.assert_array_equal(
        resample_audio(y, orig, target), librosa.resample(y, orig_sr=orig, target_sr=target)
    )


def test_unknown_method():
    with pytest.raises(ParameterError, match="'madmom'"):
        trackers.get("madmom")


def test_missing_optional_package_says_how_to_install(monkeypatch):
    fake = dataclasses.replace(trackers.TRACKERS["essentia-degara"], requires="no_such_package_xyz")
    monkeypatch.setitem(trackers.TRACKERS, "essentia-degara", fake)
    assert trackers.available()["essentia-degara"] is False
    assert trackers.available()["psf"] is True
    with pytest.raises(ParameterError, match=r"pip install 'beatsync\[peers\]'"):
        trackers.get("essentia-degara")


@pytest.mark.parametrize(
    "y, sr, match",
    [
        (np.zeros(SR * 5, dtype=np.float32), SR, r"peak below 1e-07"),
        # a DC offset: ours made up one beat at the end, essentia's sixteen
        (np.full(SR * 10, 0.5, dtype=np.float32), SR, r"constant at 0\.5"),
        (np.array([], dtype=np.float32), SR, "zero samples"),
        # librosa returned one beat for 0.5 s, essentia's none
        (np.random.default_rng(0).standard_normal(SR // 2), SR, r"0\.500 s"),
        (np.full(SR * 5, np.nan, dtype=np.float32), SR, "110250 NaN"),
        (np.ones(SR * 5, dtype=np.float32), 0, "sr=0"),
    ],
)
def test_bad_audio_refused_for_every_method(y, sr, match):
    for name in ("psf", "librosa"):
        with pytest.raises(ParameterError, match=match):
            trackers.track(name, y, sr)


def test_prepare_checks_the_name_and_compiles_only_for_librosa(monkeypatch):
    with pytest.raises(ParameterError, match="'madmom'"):
        trackers.prepare("madmom")
    calls = []
    librosa = pytest.importorskip("librosa")
    monkeypatch.setattr(librosa.beat, "beat_track", lambda **kw: calls.append(kw))
    trackers.prepare("psf")
    assert calls == []
    trackers.prepare("librosa")
    assert len(calls) == 1 and calls[0]["y"].dtype == np.float32
