"""Tests of the beat tracker (beatsync.beats) on signals with known beats."""

import warnings

import numpy as np
import pytest

from beatsync import datasets
from beatsync.beats import (
    MIN_DURATION_S,
    BeatTrack,
    beat_tempo,
    check_audio,
    onset_strength_psf,
    phase_slope,
    track_beats,
)
from beatsync.beats.phase import band_phase_weights
from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.evaluate.beats import evaluate
from beatsync.synth.audio import (
    METERS,
    beat_times,
    click_track,
    drum_pattern,
    make_beat_test_set,
    meter_pattern,
)

SR = 22050


def _score(ref, est):
    return evaluate(ref, est, min_beat_time=0.0)


def test_phase_slope_crosses_zero_at_impulse():
    y = np.zeros(SR)
    y[11025] = 1.0
    psf, energy, fps, _ = phase_slope(y, SR)
    band = int(np.argmax(energy.sum(axis=1)))
    p = psf[band]
    t = np.arange(p.size) / fps
    ok = np.isfinite(p)
    # negative before the impulse reaches the frame centre, positive after
    assert np.all(p[ok & (t < 0.49) & (t > 0.45)] < 0)
    assert np.all(p[ok & (t > 0.51) & (t < 0.55)] > 0)
    # the phase slope equals the frame time minus the impulse time (in seconds)
    near = ok & (np.abs(t - 0.5) < 0.008)
    np.testing.assert_allclose(p[near], t[near] - 0.5, atol=2e-4)


def test_onsets_at_clicks():
    ref = np.array([0.3, 0.8, 1.3, 1.8])
    ons = onset_strength_psf(click_track(ref, sr=SR, duration=2.2), SR)
    strong = ons.onset_times[ons.onset_strengths > 0.3 * ons.onset_strengths.max()]
    for r in ref:
        assert np.min(np.abs(strong - r)) < 0.005
    assert ons.band_weights[0] > ons.band_weights[-1]  # weights 6 - c


@pytest.mark.parametrize("bpm", [60, 90, 120, 150, 180])
def test_click_track_known_answer(bpm):
    ref = beat_times(bpm, duration=15.0, start=0.37)
    bt = track_beats(click_track(ref, sr=SR, duration=15.0), SR)
    assert isinstance(bt, BeatTrack) and bt.method == "psf"
    assert bt.tempo == pytest.approx(bpm, rel=0.03)
    assert np.all(np.diff(bt.beats) > 0)
    s = _score(ref, bt.beats)
    assert s["F-measure"] >= 0.95
    # beats are snapped to the phase-slope zero crossings: a few ms at most
    err = [np.min(np.abs(bt.beats - r)) for r in ref]
    assert np.median(err) < 0.005


@pytest.mark.parametrize("bpm", [90, 120, 150])
def test_drums_known_answer(bpm):
    ref = beat_times(bpm, duration=15.0, start=0.41)
    y = drum_pattern(ref, sr=SR, duration=15.0, seed=5)
    s = _score(ref, track_beats(y, SR).beats)
    assert s["Any Metric Level Total"] >= 0.95


def test_tempo_change_is_followed():
    items = make_beat_test_set(duration=20.0, bpms=[90], kinds=["click"], groups=["change"])
    it = items[0]
    bt = track_beats(it.y, it.sr)
    assert bt.tempo_curve[0] == pytest.approx(90, rel=0.03)
    assert bt.tempo_curve[-1] == pytest.approx(120, rel=0.03)
    assert _score(it.beats, bt.beats)["F-measure"] >= 0.95
    # forcing one tempo cannot follow the change
    flat = track_beats(it.y, it.sr, time_varying=False)
    assert np.ptp(flat.tempo_curve) == 0
    assert _score(it.beats, flat.beats)["F-measure"] < 0.95


def test_known_bpm_override_and_range():
    ref = beat_times(180, duration=12.0, start=0.3)
    y = click_track(ref, sr=SR, duration=12.0)
    bt = track_beats(y, SR, bpm=90.0)  # the user asks for the half-tempo level
    assert np.all(bt.tempo_curve == 90.0)
    assert np.median(np.diff(bt.beats)) == pytest.approx(60 / 90, rel=0.02)
    assert _score(ref, bt.beats)["Any Metric Level Total"] >= 0.95
    bt2 = track_beats(y, SR, min_bpm=50, max_bpm=100)
    assert bt2.tempo == pytest.approx(90, rel=0.03)


@pytest.mark.parametrize("method", ["psf", "librosa"])
def test_a_tempo_with_a_range_is_refused(method):
    # the range was ignored, even when the tempo lay outside it (the CLI refused it)
    y = click_track(beat_times(120, duration=5.0, start=0.3), sr=SR, duration=5.0)
    with pytest.raises(ParameterError, match=r"bpm=120.*\(130, 200\)"):
        track_beats(y, SR, method=method, bpm=120, min_bpm=130, max_bpm=200)
    if method == "psf":  # (librosa's first numba compilation here crashed a fresh xdist run)
        assert track_beats(y, SR, bpm=120, min_bpm=40, max_bpm=240).beats.size


def test_frontend_parameters_accepted():
    ref = beat_times(120, duration=10.0, start=0.3)
    y = click_track(ref, sr=SR, duration=10.0)
    bt = track_beats(y, SR, win_s=0.046, hop_s=0.0116, band_edges_hz=(0, 500, 2000, 8000, 11025))
    assert _score(ref, bt.beats)["F-measure"] >= 0.95


@pytest.mark.parametrize(
    "edges, match",
    [
        # band edges for another rate: no onsets, and a warning that blamed "a steady sound"
        ((20000, 30000), r"band 1 \(20000-30000 Hz\).* 11025 Hz"),
        ((0, 100, 100.5, 4000), r"band 2 \(100-100\.5 Hz\).*FFT bin"),
    ],
)
def test_band_edges_that_hold_no_frequency_are_refused(edges, match):
    y = click_track(beat_times(120, duration=5.0, start=0.3), sr=SR, duration=5.0)
    with pytest.raises(ParameterError, match=match):
        track_beats(y, SR, band_edges_hz=edges)


def test_default_band_edges_still_track_low_rate_audio():
    # the default top band (4-22 kHz) holds nothing at 4 kHz: not the user's mistake
    from beatsync.beats.onset import onset_strength_psf

    sr = 4000
    ref = beat_times(120, duration=10.0, start=0.3)
    y = click_track(ref, sr=sr, duration=10.0)
    bt = track_beats(y, sr)
    assert bt.tempo == pytest.approx(120, rel=0.05)
    # the public helper passes the default edges on explicitly: still not refused
    assert onset_strength_psf(y, sr).envelope.size > 0


def test_librosa_method_scores_on_clean_clicks():
    ref = beat_times(120, duration=10.0, start=0.3)
    bt = track_beats(click_track(ref, sr=SR, duration=10.0), SR, method="librosa")
    assert bt.method == "librosa"
    assert _score(ref, bt.beats)["F-measure"] >= 0.9
    assert bt.tempo == pytest.approx(120, rel=0.05)


@pytest.mark.parametrize("method", ["psf", "librosa"])
@pytest.mark.parametrize("duration", [0.5, 1.0, MIN_DURATION_S - 0.01])
def test_too_short_audio_is_refused(method, duration):
    # a 0.5 s click gave "109 BPM, 1 beat" (the tempo prior), exit 0
    y = click_track(beat_times(120, duration=duration, start=0.1), sr=SR, duration=duration)
    with pytest.raises(ParameterError, match=rf"{duration:.3f} s.* 1\.5 s"):
        track_beats(y, SR, method=method)


def test_short_audio_rule_with_known_bpm():
    y = click_track(beat_times(90, duration=1.8, start=0.1), sr=SR, duration=1.8)
    # 1.8 s passes the fixed minimum but is less than two beat periods at 50 BPM (2.4 s)
    with pytest.raises(ParameterError, match=r" 2\.4 s.*bpm=50"):
        track_beats(y, SR, bpm=50.0)
    assert track_beats(y, SR, bpm=90.0).beats.size >= 2  # 1.33 s needed
    # exactly the minimum is accepted
    n = int(MIN_DURATION_S * SR)
    yy = click_track(
        beat_times(120, duration=MIN_DURATION_S, start=0.1), sr=SR, duration=MIN_DURATION_S
    )
    assert yy.size == n and track_beats(yy, SR).beats.size >= 2


def test_beat_tempo_known_answer():
    starts, bpm = beat_tempo([0.0, 0.5, 1.0, 1.75])
    np.testing.assert_allclose(starts, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(bpm, [120.0, 120.0, 80.0])
    assert beat_tempo([1.0])[1].size == 0
    with pytest.raises(ParameterError):
        beat_tempo([1.0, 0.5])


def test_check_audio_silence_threshold_and_allow_silent():
    quiet = 5e-7 * (-1.0) ** np.arange(100)  # above the silence threshold (1e-7)
    assert check_audio(quiet, SR)[0].dtype == np.float64
    with pytest.raises(ParameterError, match="5e-07"):  # a DC offset: no sound
        check_audio(np.full(100, 5e-7), SR)
    with pytest.raises(ParameterError, match="silent"):
        check_audio(np.full(100, 5e-8), SR)
    y, sr = check_audio(np.zeros(100), SR, allow_silent=True)
    assert sr == SR and not y.any()


@pytest.mark.parametrize("bpm", [120.0, 150.0])
@pytest.mark.parametrize("duration", [4.5, 5.0, 5.5])
def test_short_click_tracks_at_their_tempo(bpm, duration):
    # tapped at half the tempo (60, 75 BPM), without a warning, while the resonators'
    # spectrum was sampled coarser than their pass bands (0.17 Hz bins for a 5 s clip)
    from beatsync.beats.metrical import resonator_fft_size
    from beatsync.beats.onset import frontend_settings

    ref = beat_times(bpm, duration=duration, start=0.3)
    bt = track_beats(click_track(ref, sr=SR, duration=duration), SR)
    assert bt.tempo == pytest.approx(bpm, rel=0.03)
    assert _score(ref, bt.beats)["F-measure"] >= 0.95
    fps = frontend_settings({}, SR).fps
    assert fps / resonator_fft_size(int(duration * fps), fps, 3.0) < 0.074 / 3


def test_madmom_sample():
    # tapped at 120 BPM (6 beats) while the resonators' spectrum was sampled coarser than
    # their pass bands (metrical.resonator_fft_size)
    y, sr, ref = datasets.load_madmom_sample()
    bt = track_beats(y, sr)
    # at its own level: about 88 BPM, its 4 beats (not 8)
    assert bt.tempo == pytest.approx(88.0, rel=0.1)
    assert _score(ref, bt.beats)["F-measure"] >= 0.85


def test_madmom_sample_with_known_bpm():
    y, sr, ref = datasets.load_madmom_sample()
    assert _score(ref, track_beats(y, sr, bpm=88.0).beats)["F-measure"] == 1.0


#: Clips on the beat whose F is lower for a beat placed just outside mir_eval's 70 ms
LOWER_F = {
    # one beat 71 ms early since the resonators' spectrum is sampled finely (84.4 -> 84.7
    # BPM): F 1.0 -> 0.9, CMLt 1.0
    ("ballroom_waltz", 18.0, 7.0): 0.9,
}


@pytest.mark.slow
@pytest.mark.parametrize(
    "name, start, length",
    [
        # long excerpts that the bass band (onsets at every phase of the beat) pulled onto
        # the off-beat when the bands were weighted 5:4:3:2 (F 0.00, 0.00, 0.47, 0.68)
        ("ballroom_waltz", 10.0, 15.0),
        ("ballroom_waltz", 12.5, 15.0),
        ("ballroom_waltz", 5.0, 25.0),
        ("hainsworth_001", 0.0, 20.0),
        # short clips that its random phases still put on the off-beat when the bands had
        # equal weights (F 0.00 each)
        ("hainsworth_001", 13.0, 7.0),
        ("hainsworth_001", 10.0, 10.0),
        ("hainsworth_001", 13.0, 10.0),
        ("ballroom_waltz", 18.0, 7.0),
        ("ballroom_waltz", 20.0, 10.0),
        # clips tapped at 4/3 of the beat (about 132 BPM, a "beat" of three sixteenths,
        # F 0.21-0.31) while a beat of three tatums weighed as much as one of two or four
        ("hainsworth_001", 2.0, 5.0),
        ("hainsworth_001", 10.0, 5.0),
        ("hainsworth_001", 47.0, 7.0),
        ("hainsworth_001", 46.0, 10.0),
    ],
)
def test_real_excerpts_on_the_beat_not_the_off_beat(name, start, length):
    y, sr, ref = datasets.load_real_dev(name)
    y = y[int(start * sr) : int((start + length) * sr)]
    ref = ref[(ref >= start) & (ref < start + length)] - start
    # mir_eval's default skips the first 5 s, which a 7-10 s clip cannot spare
    s = evaluate(ref, track_beats(y, sr).beats, min_beat_time=5.0 if length > 10 else 0.0)
    assert s["F-measure"] >= LOWER_F.get((name, start, length), 0.95)
    assert s["Correct Metric Level Total"] >= 0.90


def test_a_beat_of_three_tatums_weighs_less_than_a_bar_of_three_beats():
    from dataclasses import replace

    from beatsync.beats.metrical import METER_MODEL, _level_terms, ratio_weight

    # tactus / tatum = 3 counts half; measure / tactus = 3 (a bar of three) does not
    # (the Gaussians of the neighbouring ratios overlap a little)
    assert ratio_weight(3.0, tatum=True) == pytest.approx(0.5 * ratio_weight(3.0), rel=0.02)
    for x in (1.0, 2.0, 4.0):
        assert ratio_weight(x, tatum=True) == pytest.approx(ratio_weight(x), rel=0.01)
    # the tatum weights reach the tatum term only, never the measure's
    periods = np.geomspace(0.3, 1.2, 40)
    equal = replace(METER_MODEL, tatum_ratio_weights=METER_MODEL.ratio_weights)
    _, _, g_a, g_c = _level_terms(periods.tobytes(), METER_MODEL)
    _, _, g_a_eq, g_c_eq = _level_terms(periods.tobytes(), equal)
    np.testing.assert_array_equal(g_c, g_c_eq)
    assert not np.allclose(g_a[np.isfinite(g_a)], g_a_eq[np.isfinite(g_a_eq)])


def test_band_phase_weights_favour_the_band_locked_to_the_beat():
    n = 1000  # frames at 100 fps
    cycles = np.arange(n) / 50.0  # 120 BPM
    rng = np.random.default_rng(0)
    bands = np.zeros((3, n))
    bands[0, rng.integers(0, n, 400)] = 5.0  # loud, at every phase
    bands[1, ::50] = 1.0  # quiet, on every beat
    bands[2, 25::50] = 1.0  # quiet, on every off-beat
    w = band_phase_weights(bands, cycles)
    assert w.sum() == pytest.approx(1.0)
    assert w[1] == pytest.approx(w[2]) and w[1] > 5 * w[0]
    assert np.allclose(band_phase_weights(np.zeros((4, n)), cycles), 0.25)
    # a band that slips by half a beat halfway: over the whole signal its phases cancel,
    # window by window they do not
    slip = np.zeros((2, n))
    slip[0, np.r_[0:500:50, 525:1000:50]] = 1.0
    slip[1, rng.integers(0, n, 40)] = 1.0
    assert band_phase_weights(slip, cycles)[0] < 0.3
    w = band_phase_weights(slip, cycles, [0, 500], [500, 1000])
    assert w[0] > 0.7


@pytest.mark.slow
@pytest.mark.parametrize("name, meter", [("hainsworth_001", 4), ("ballroom_waltz", 3)])
def test_real_recordings_at_the_annotated_level(name, meter):
    y, sr, ref = datasets.load_real_dev(name)
    bt = track_beats(y, sr)
    s = evaluate(ref, bt.beats, min_beat_time=5.0)  # mir_eval default: after 5 s
    assert s["F-measure"] >= 0.95
    assert s["Correct Metric Level Total"] >= 0.90
    assert bt.beats_per_bar == meter


def test_808_loop_tempo():
    y, sr = datasets.load_click_808()
    assert track_beats(y, sr).tempo == pytest.approx(120, rel=0.02)


@pytest.mark.xfail(
    strict=True,
    reason="known gap: in the bands without the tone, its positive- and negative-frequency "
    "sidelobes interfere with a phase that turns by 2f per second; seen at the frame rate "
    "(172 Hz) that ripple has the alias frequency of 880 Hz, about 18.6 Hz, and the phase "
    "slope crosses zero about 37 times a second. That onset train is periodic, so its "
    "sub-harmonics resonate as a clear pulse: 5 beats in 3 s, 27 in 10 s, and no warning "
    "(the gates measured against it: beatsync.beats.onset)",
)
@pytest.mark.parametrize("seconds, fade_s", [(3, 1.5), (10, 0.01)])
def test_steady_tone_gives_no_beats_with_warning(seconds, fade_s):
    t = np.arange(seconds * SR) / SR
    y = np.sin(2 * np.pi * 440 * t) * np.minimum(t / fade_s, 1.0)  # a fade-in, no onset
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        bt = track_beats(y, SR)
    if bt.beats.size == 0:
        assert any(issubclass(w.category, BeatsyncWarning) for w in rec)
        assert np.isnan(bt.tempo)
    else:  # never more than a spurious couple
        assert bt.beats.size <= 3


_Y = np.random.default_rng(0).standard_normal(SR)


def test_noise_warns_no_clear_pulse():
    # the warning says what it means and names the way out, a known tempo
    y = np.random.default_rng(1).standard_normal(30 * SR)
    with pytest.warns(
        BeatsyncWarning, match=r"no clear pulse.*another metrical level.*bpm= \(--bpm\)"
    ):
        track_beats(y, SR)


@pytest.mark.parametrize("seconds", [2, 3, 5, 10])
def test_short_noise_warns_no_clear_pulse(seconds):
    # one or a few tempo windows: the salience of noise is high, but no higher than
    # that of the same onsets in random order
    y = np.random.default_rng(1).standard_normal(seconds * SR)
    with pytest.warns(BeatsyncWarning, match="no clear pulse.*random order") as rec:
        track_beats(y, SR)
    # a clip shorter than the tempo window is told so
    short = any("shorter than the 8 s tempo window" in str(w.message) for w in rec)
    assert short == (seconds < 8)


def test_noise_whose_ratio_passes_warns_by_its_low_salience():
    # a 2 s white noise (seed 5 of the calibration, benchmarks/calibrate_pulse_clarity.py)
    # whose path salience is 3.32 times its null, above MIN_PULSE_CLARITY: it warns by
    # its salience (0.054, below MIN_PATH_SALIENCE)
    x = np.random.default_rng(5).standard_normal(2 * SR)
    y = (0.5 * x / np.abs(x).max()).astype(np.float32)
    with pytest.warns(
        BeatsyncWarning, match=r"no clear pulse in the audio \(pulse clarity 0\.05: below 0\.08\)"
    ):
        track_beats(y, SR)


def test_pulse_clarity_null_is_reproducible_and_low_on_clicks():
    from beatsync.beats.metrical import METER_MODEL
    from beatsync.beats.onset import compute_onsets, frontend_settings
    from beatsync.beats.tempo import analysis_windows, period_grid
    from beatsync.beats.tracker import pulse_clarity_null

    y = click_track(beat_times(120, duration=10.0, start=0.3), sr=SR, duration=10.0)
    ons = compute_onsets(y, SR, frontend_settings({}, SR))
    starts, stops, _ = analysis_windows(ons.envelope.size, ons.fps, 8.0, 1.0)
    args = (ons, starts, stops, period_grid(40, 240), METER_MODEL, 30.0)
    null = pulse_clarity_null(*args)
    assert null == pulse_clarity_null(*args)  # seeded permutations
    assert 0.0 < null < 0.5  # the clicks in random order have no clear pulse


def _no_pulse_warnings(y, sr, **kwargs):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        bt = track_beats(y, sr, **kwargs)
    return bt, [str(w.message) for w in rec if "no clear pulse" in str(w.message)]


def test_no_pulse_warning_advice_works_on_a_real_clip():
    # 2.5-17.5 s of the waltz DANCE_W_10 (soft onsets) disagree with the beats of the
    # whole 28 s excerpt (F 0.36, at the right tempo: a phase error) and warn. The way
    # out the warning names, a known tempo, puts them back on the excerpt's beats.
    pair = datasets.load_dance_pair("DANCE_W_10")
    whole = track_beats(pair.y, pair.sr)
    start, stop = 2.5, 17.5
    ref = whole.beats[(whole.beats >= start) & (whole.beats < stop)] - start
    clip = pair.y[int(start * pair.sr) : int(stop * pair.sr)]
    guessed, msgs = _no_pulse_warnings(clip, pair.sr)
    if _score(ref, guessed.beats)["F-measure"] < 0.95:
        # tracked wrong told nothing: the user is warned and told the way out
        assert any("bpm= (--bpm)" in m for m in msgs)
    known, msgs = _no_pulse_warnings(clip, pair.sr, bpm=round(whole.tempo))
    assert msgs == []
    assert _score(ref, known.beats)["F-measure"] >= 0.95  # 1.0 here


@pytest.mark.slow
@pytest.mark.parametrize("name", datasets.DANCE_PAIRS)
def test_no_pulse_warning_on_ballroom_songs(name):
    # the waltz DANCE_W_10 (soft onsets) used to warn
    pair = datasets.load_dance_pair(name)
    bt, msgs = _no_pulse_warnings(pair.y, pair.sr)
    assert msgs == []
    assert bt.beats_per_bar == (3 if pair.style == "waltz" else 4)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["hainsworth_001", "ballroom_waltz", "madmom"])
def test_no_pulse_warning_on_annotated_recordings(name):
    if name == "madmom":
        y, sr, _ = datasets.load_madmom_sample()
    else:
        y, sr, _ = datasets.load_real_dev(name)
    assert _no_pulse_warnings(y, sr)[1] == []


@pytest.mark.parametrize(
    "y, sr, kwargs",
    [
        (np.zeros(0), SR, {}),
        (np.zeros(SR), SR, {}),
        (_Y[:1000], SR, {}),  # 45 ms: too short
        (_Y[: SR // 2], SR, {}),  # 0.5 s: too short for two beat periods
        (np.r_[_Y[:100], np.nan, _Y[101:]], SR, {}),
        (_Y, 0, {}),
        (_Y, -22050, {}),
        (np.stack([_Y, _Y]), SR, {}),
        (_Y, SR, {"min_bpm": 200, "max_bpm": 100}),
        (_Y, SR, {"min_bpm": 120, "max_bpm": 120}),
        (_Y, SR, {"bpm": 2.0}),
        (_Y, SR, {"bpm": 1200.0}),
        (_Y, SR, {"bpm": float("nan")}),
        (_Y, SR, {"method": "madmom"}),
        (_Y, SR, {"hop_s": 0.1}),
        (_Y, SR, {"window_ms": 20}),
        (_Y, SR, {"method": "librosa", "win_s": 0.02}),
    ],
)
def test_bad_input_raises(y, sr, kwargs):
    with pytest.raises(ParameterError):
        track_beats(y, sr, **kwargs)


@pytest.mark.parametrize("sr", [16000, 44100, 48000])
def test_other_sample_rates(sr):
    ref = beat_times(132, duration=12.0, start=0.35)
    y = drum_pattern(ref, sr=sr, duration=12.0, seed=2)
    bt = track_beats(y, sr)
    assert _score(ref, bt.beats)["Any Metric Level Total"] >= 0.95
    # the tempo curve is refined from the beats: close to the truth, not a grid step
    assert bt.tempo == pytest.approx(132, rel=0.01) or bt.tempo == pytest.approx(66, rel=0.01)


def test_slow_tempo_drift_is_followed():
    items = make_beat_test_set(duration=30.0, bpms=[120], kinds=["click"], groups=["drift"])
    it = items[0]
    bt = track_beats(it.y, it.sr)
    assert np.ptp(bt.tempo_curve) > 6.0  # +-5 % of 120 BPM over the clip
    assert _score(it.beats, bt.beats)["F-measure"] >= 0.95


# 2/4 and 6/8 at 160 BPM were tapped at half before the drum cue (beatsync.beats.drums)
METER_CASES = [
    ("2/4", 100.0),
    ("3/4", 90.0),
    ("6/8", 70.0),
    ("3/4", 140.0),
    ("2/4", 160.0),
    ("6/8", 160.0),
]


@pytest.mark.parametrize("meter, bpm", METER_CASES)
def test_metrical_level_on_synthetic_meters(meter, bpm):
    # eighth-note subdivisions everywhere: the beat is neither the eighth nor the bar
    ref = beat_times(bpm, duration=20.0, start=0.4)
    bt = track_beats(meter_pattern(ref, meter=meter, duration=20.0, seed=3), SR)
    assert bt.tempo == pytest.approx(bpm, rel=0.03)
    assert _score(ref, bt.beats)["F-measure"] >= 0.95


@pytest.mark.parametrize(
    "meter, bpm",
    [
        ("2/4", 100.0),
        pytest.param(
            "3/4",
            90.0,
            marks=pytest.mark.xfail(strict=True, reason="known gap: meter estimated as 2"),
        ),
        ("6/8", 70.0),
        ("3/4", 140.0),
    ],
)
def test_meter_estimate_on_synthetic_meters(meter, bpm):
    ref = beat_times(bpm, duration=20.0, start=0.4)
    bt = track_beats(meter_pattern(ref, meter=meter, duration=20.0, seed=3), SR)
    assert bt.beats_per_bar == METERS[meter][0]


def test_mix_clicks_puts_a_click_on_each_beat():
    from beatsync.beats import mix_clicks

    y = np.zeros(2 * SR)
    y[0] = 1e-3  # near silence: the clicks dominate
    mix = mix_clicks(y, SR, np.array([0.5, 1.5]))
    assert mix.dtype == np.float32 and mix.size == y.size
    assert np.max(np.abs(mix)) <= 1.0
    env = np.abs(mix.astype(np.float64))
    assert env[int(0.5 * SR) : int(0.52 * SR)].max() > 0.3
    assert env[int(1.0 * SR) : int(1.4 * SR)].max() < 1e-3


def test_study_scores_and_targets_on_a_small_set():
    from beatsync.study import paper_a_beats as study

    items = make_beat_test_set(duration=8.0, bpms=[120], kinds=["click"], groups=["clean"])
    assert study.available_methods()[:2] == ["psf", "librosa"]
    scores = study.score_items(items, methods=["psf"], min_beat_time=0.0)
    assert list(scores["method"]) == ["psf"]
    assert scores.loc[0, "F"] >= 0.95 and scores.loc[0, "octave"] == "correct"
    targets = study.check_targets(scores)
    clean = targets[targets["target"].str.contains("clean")]
    assert clean["result"].tolist() == ["PASS"]
    # targets of items that are not in the scores are left out, not failed
    assert not targets["target"].str.contains("hainsworth").any()


def test_frontend_sweep_lists_the_items_of_a_small_set():
    """The sweep's mean of three real recordings moved with the 2.8 s sample alone; a
    small set now shows each item's F beside the mean."""
    from beatsync.study import paper_a_beats as study

    few = make_beat_test_set(duration=8.0, bpms=[90, 150], kinds=["click"], groups=["clean"])
    many = make_beat_test_set(duration=6.0, bpms=[60, 80, 100, 120, 140, 160], kinds=["click"],
                              groups=["clean"])  # fmt: skip
    sweep = study.frontend_sweep(
        {"few": few, "many": many}, {"win_s": [0.023], "hop_s": [0.0058]}, min_beat_time=0.0
    )
    row = sweep.set_index("set")
    assert bool(row.loc["few", "default"])
    listed = row.loc["few", "F per item"].split(", ")
    assert [x.split()[0] for x in listed] == ["click_90_clean", "click_150_clean"]
    assert np.mean([float(x.split()[1]) for x in listed]) == pytest.approx(
        row.loc["few", "F"], abs=1e-3
    )
    assert row.loc["many", "F per item"] == ""  # more than SWEEP_ITEMS_LISTED items
    # a set with no items (the notebook run without real recordings) is left out
    empty = study.frontend_sweep(
        {"real": [], "few": few}, {"win_s": [0.023], "hop_s": [0.0058]}, min_beat_time=0.0
    )
    assert empty["set"].tolist() == ["few"]


def test_study_overview_and_methods_note():
    # what the beat-tracking notebook shows before scoring, now in the package
    from beatsync.study import paper_a_beats as study

    items = make_beat_test_set(duration=6.0, bpms=[60, 90, 120, 150], kinds=["click"],
                               groups=["clean", "swing"])  # fmt: skip
    table = study.items_overview(items, per_group=2)
    assert table["item"].tolist() == [
        "click_60_clean", "click_90_clean", "click_60_swing", "click_90_swing"
    ]  # fmt: skip
    assert table.columns.tolist() == ["item", "group", "bpm", "beats", "seconds"]
    assert table["seconds"].tolist() == [6.0] * 4
    assert study.methods_note(["psf", "librosa"]).splitlines() == [
        "methods: ['psf', 'librosa']",
        "essentia is not installed here: its trackers are left out of every table below",
    ]
    assert study.methods_note(["psf", "essentia-degara"]) == "methods: ['psf', 'essentia-degara']"


@pytest.mark.parametrize(
    "grid, p_jump",
    [
        ("tracker", 1e-4),
        ("tracker", 1e-30),  # far transitions differ from the jump by ~1e-13: wider band
        ("tracker", 0.0),  # no jump: the dense decoder
        ("decreasing", 1e-4),
        ("repeated", 1e-4),
    ],
)
def test_banded_tempo_decoder_equals_the_dense_viterbi(grid, p_jump):
    # the tempo HMM decodes in the band of transitions that differ from the uniform jump;
    # the path must be the dense decoder's on any observation (noisy, with tempo changes)
    from beatsync.beats.tempo import period_grid, tempo_hmm, viterbi

    rng = np.random.default_rng(7)
    periods = period_grid(40, 240)
    if grid == "decreasing":
        periods = periods[::-1].copy()
    elif grid == "repeated":
        periods = np.repeat(periods[::3], 3)
    logp = np.log(periods)
    trans = np.exp(-0.5 * ((logp[:, None] - logp[None, :]) / 0.02) ** 2)
    trans /= trans.sum(axis=1, keepdims=True)
    with np.errstate(divide="ignore"):
        log_trans = np.log((1 - p_jump) * trans + p_jump / periods.size)
    for scale in (0.1, 1.0, 10.0, 100.0):
        for _ in range(5):
            obs = rng.normal(size=(periods.size, 40)) * scale
            obs[rng.integers(periods.size), 20:] += 5 * scale  # a tempo change halfway
            path = tempo_hmm(obs, periods, trans_sigma=0.02, p_jump=p_jump)
            np.testing.assert_array_equal(path, viterbi(obs, log_trans))
    # one window (a short clip): no transition
    obs = rng.normal(size=(periods.size, 1))
    path = tempo_hmm(obs, periods, trans_sigma=0.02, p_jump=p_jump)
    np.testing.assert_array_equal(path, [np.argmax(obs[:, 0])])


def test_front_end_blocks_equal_one_pass(monkeypatch):
    # the front end runs in blocks of frames; the flux's frame difference must carry
    # across block edges (a block's first frame compared with the previous block's last)
    from beatsync.beats import onset

    y = drum_pattern(beat_times(118, duration=6.0, start=0.2), sr=SR, duration=6.0, seed=3)
    fe = onset.frontend_settings({}, SR)
    whole = onset.compute_onsets(y.astype(np.float64), SR, fe)
    monkeypatch.setattr(onset, "BLOCK_FRAMES", 7)
    blocks = onset.compute_onsets(y.astype(np.float64), SR, fe)
    np.testing.assert_allclose(blocks.bands, whole.bands, rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(blocks.onset_times, whole.onset_times, atol=1e-9)


def _salience_by_spectrum(bands, fps, starts, stops, periods, half_time_s, max_hz):
    """The resonators' salience as its definition reads: the padded window's power
    spectrum times each comb filter's squared gain, summed over the one-sided bins."""
    from beatsync.beats.metrical import resonator_fft_size

    length = max(b - a for a, b in zip(starts, stops, strict=True))
    n_fft = resonator_fft_size(length, fps, half_time_s)
    freq = np.arange(n_fft // 2 + 1) * fps / n_fft
    alpha = 0.5 ** (periods / half_time_s)
    a = alpha[:, None]
    gain = (1 - a) ** 2 / (1 - 2 * a * np.cos(2 * np.pi * np.outer(periods, freq)) + a**2)
    gamma = (1 - alpha) ** 2 / (1 - alpha**2)
    if max_hz is not None:
        gain[:, int(np.ceil(max_hz / fps * n_fft)) + 1 :] = gamma[:, None]  # passed as is
    out = np.zeros((periods.size, len(starts)))
    for w, (a0, a1) in enumerate(zip(starts, stops, strict=True)):
        x = bands[:, a0:a1]
        seg = (x - x.mean(axis=1, keepdims=True)) * np.hanning(a1 - a0)
        power = np.abs(np.fft.rfft(seg, n=n_fft, axis=1)) ** 2
        r = (gain @ power.T / power.sum(axis=1) - gamma[:, None]) / (1 - gamma[:, None])
        r[periods > (a1 - a0) / fps / 2] = 0.0
        out[:, w] = r.sum(axis=1)
    return out


@pytest.mark.parametrize(
    "windows",
    [
        [(0, 483)],  # the madmom sample: one window of 2.8 s
        [(0, 1378), (172, 1550), (600, 1978), (1624, 3000)],  # 8 s windows, one shorter
        [(0, 5000)],  # longer than half the FFT: its autocorrelation wraps the spectrum
    ],
)
@pytest.mark.parametrize("max_hz", [None, 34.0])
def test_resonator_salience_equals_the_spectrum_sum(windows, max_hz):
    # resonator_salience sums the power spectrum against the comb gains in the lag
    # domain; it must equal the sum over the padded spectrum's bins
    from beatsync.beats.metrical import resonator_salience, resonator_saliences

    fps = 22050 / 128
    rng = np.random.default_rng(3)
    bands = np.abs(rng.standard_normal((4, max(b for _, b in windows)))) ** 3
    bands[1, ::86] += 5.0  # a pulse at 120 BPM in one band
    starts, stops = [a for a, _ in windows], [b for _, b in windows]
    periods = np.exp(np.linspace(np.log(0.08), np.log(4.0), 200))
    got = resonator_salience(bands, fps, starts, stops, periods, 3.0, max_hz)
    want = _salience_by_spectrum(bands, fps, starts, stops, periods, 3.0, max_hz)
    # the lag-domain product is taken in float32: each band's energy ratio (at most 1)
    # is off by about 1e-7, the sum over four bands here by up to 1.6e-6 (lag weights
    # off by a relative 1e-4 fail it)
    tol = 5e-6
    np.testing.assert_allclose(got, want, rtol=0, atol=tol)
    # several sets of bands at once (the null's draws): each as on its own
    sets = resonator_salience(np.stack([bands, bands[::-1]]), fps, starts, stops, periods, 3.0)
    one = resonator_salience(bands[::-1], fps, starts, stops, periods, 3.0)
    np.testing.assert_allclose(sets[..., 1], one, rtol=0, atol=tol)
    # several period grids at once (tactus, tatum, measure): each as on its own
    blocks = resonator_saliences(bands, fps, starts, stops, [periods[::2], periods[1::3]], 3.0)
    for got, grid in zip(blocks, [periods[::2], periods[1::3]], strict=True):
        want = resonator_salience(bands, fps, starts, stops, grid, 3.0)
        np.testing.assert_allclose(got, want, rtol=0, atol=tol)


def test_resonator_salience_does_not_depend_on_the_accents_scale():
    # the salience is a ratio of energies: any scale of the accent signals gives the
    # same salience, also where the float32 lag-domain product would overflow (1e18)
    # or lose its precision to underflow (1e-24) without the normalisation
    from beatsync.beats.metrical import resonator_salience

    fps = 22050 / 128
    bands = np.abs(np.random.default_rng(5).standard_normal((4, 1378))) ** 3
    bands[2, ::69] += 4.0  # a pulse at 150 BPM in one band
    periods = np.exp(np.linspace(np.log(0.1), np.log(3.0), 120))
    want = resonator_salience(bands, fps, [0], [1378], periods, 3.0)
    for scale in (1e-24, 1e-6, 1e18, 1e30):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no overflow on the way
            got = resonator_salience(bands * scale, fps, [0], [1378], periods, 3.0)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)


def test_pulse_clarity_null_draws_in_one_batch_equal_draws_one_by_one():
    from beatsync.beats import tracker
    from beatsync.beats.metrical import METER_MODEL, beat_observation
    from beatsync.beats.onset import compute_onsets, frontend_settings
    from beatsync.beats.tempo import analysis_windows, period_grid, tempo_hmm

    y, sr = datasets.load_madmom_sample()[:2]
    y, sr = tracker.check_audio(y, sr)
    ons = compute_onsets(y, sr, frontend_settings({}, sr))
    starts, stops, _ = analysis_windows(ons.envelope.size, ons.fps, 8.0, 1.0)
    periods = period_grid(40, 240)
    n = ons.bands.shape[1]
    n_draws = int(np.clip(np.ceil(tracker.NULL_AUDIO_S * ons.fps / n), 1, tracker.NULL_MAX_DRAWS))
    assert n_draws > 1
    rng = np.random.default_rng(0)
    values = []
    for _ in range(n_draws):
        acc = tracker._accents(ons.bands[:, rng.permutation(n)], ons.fps)
        log_obs, sal = beat_observation(acc, ons.fps, starts, stops, periods, METER_MODEL, 30.0)
        path = tempo_hmm(log_obs, periods, trans_sigma=tracker.TRANS_SIGMA, p_jump=tracker.P_JUMP)
        values.append(np.mean(sal[path, np.arange(path.size)]))
    null = tracker.pulse_clarity_null(ons, starts, stops, periods, METER_MODEL, 30.0)
    assert null == pytest.approx(np.mean(values), rel=1e-6)  # float32 products (see above)


def test_small_filters_equal_scipy_ndimage():
    from scipy import ndimage

    from beatsync.beats.filters import gaussian_smooth, moving_max, moving_mean

    x = np.random.default_rng(4).random((3, 2, 40))
    for sigma in (0.5, 1.72, 12.0):  # 12: the kernel is wider than the signal
        want = ndimage.gaussian_filter1d(x, sigma, axis=-1)
        np.testing.assert_allclose(gaussian_smooth(x, sigma), want, atol=1e-12)
        np.testing.assert_allclose(gaussian_smooth(x[0, 0], sigma), want[0, 0], atol=1e-12)
    # 81 and 80: edges as long as the signal; 90: longer (numpy's repeated reflections)
    for size, origin in ((5, 0), (6, 1), (7, -2), (81, 0), (80, -1), (90, 3)):
        np.testing.assert_allclose(
            moving_mean(x, size, origin),
            ndimage.uniform_filter1d(x, size, origin=origin),
            atol=1e-12,
        )
        np.testing.assert_array_equal(
            moving_max(x, size, origin), ndimage.maximum_filter1d(x, size, origin=origin)
        )


def test_small_filters_refuse_an_empty_window():
    from beatsync.beats.filters import moving_max, moving_mean

    x = np.arange(10.0)
    for fn in (moving_max, moving_mean):
        with pytest.raises(ValueError, match="size=0"):
            fn(x, 0)


def test_default_front_end_is_cached_on_the_defaults_and_the_checked_rate(monkeypatch):
    # the default front end is cached per rate: the same settings as given explicitly,
    # for any type of rate, and new settings when the defaults change
    from beatsync.beats import onset
    from beatsync.errors import ParameterError

    for sr in (16000, np.int64(16000), np.float32(16000), 16000.0):
        assert onset.frontend_settings({}, sr) == onset.frontend_settings({"win_s": 0.023}, sr)
    with pytest.raises(ParameterError, match="sr=44100"):
        onset.frontend_settings({}, 44.1)
    monkeypatch.setitem(onset.FRONTEND_DEFAULTS, "win_s", 0.046)
    assert onset.frontend_settings({}, 22050.0).win_length == 1014


def test_clips_of_other_lengths_share_the_resonator_weights():
    # the lag weights are cached per power of two of the window length: clips shorter
    # than the tempo window (each its own length) computed all three grids again
    from beatsync.beats import metrical

    ref = beat_times(120, duration=6.0, start=0.3)
    y = click_track(ref, sr=SR, duration=6.0)
    track_beats(y[: int(4.0 * SR)], SR)
    before = metrical._resonator_lag_weights.cache_info()
    for seconds in (4.2, 4.5, 5.0):  # 723-861 frames: 1024 lags cached, as for 4 s
        track_beats(y[: int(seconds * SR)], SR)
    after = metrical._resonator_lag_weights.cache_info()
    assert after.misses == before.misses and after.hits > before.hits


@pytest.mark.parametrize("sr", [22050, 44100])
def test_tracker_input_types_and_extreme_levels_give_the_same_beats(sr):
    # float32 stays float32 through the front end, every other type becomes float64;
    # a level near the float maxima is scaled down by a power of two before soxr (which
    # returned NaN from about 1e37: no beats, "no onsets found")
    ref = beat_times(120, duration=6.0, start=0.3)
    y = click_track(ref, sr=sr, duration=6.0).astype(np.float64)
    y *= 0.5 / np.abs(y).max()
    want = track_beats(y, sr).beats
    assert want.size >= 10
    np.testing.assert_array_equal(
        track_beats(y.astype(np.float16), sr).beats,
        track_beats(y.astype(np.float16).astype(np.float64), sr).beats,
    )
    y32 = y.astype(np.float32)
    np.testing.assert_array_equal(
        track_beats(y32 * np.float32(2.0**127), sr).beats, track_beats(y32, sr).beats
    )
    np.testing.assert_array_equal(track_beats(y * 2.0**1020, sr).beats, want)
