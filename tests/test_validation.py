import re
import warnings

import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.validation import (
    MAX_BPM,
    MIN_BPM,
    as_float,
    as_float_array,
    as_int,
    check_audio,
    check_bpm,
    check_choice,
    check_finite,
    check_fps,
    check_motion_fps,
    check_positive,
    check_range,
    check_sample_rate,
    check_times,
    frames_to_time,
    time_to_frames,
)


def test_frames_seconds_round_trip():
    frames = np.array([0, 1, 59, 60, 6000])
    t = frames_to_time(frames, fps=60.0)
    assert t[3] == 1.0
    np.testing.assert_array_equal(time_to_frames(t, fps=60.0), frames)


def test_fractional_frames():
    assert time_to_frames([0.5], fps=25, round_to_int=False)[0] == pytest.approx(12.5)


@pytest.mark.parametrize("fps", [0, -25, np.nan, np.inf, "x", None])
def test_bad_fps(fps):
    with pytest.raises(ParameterError, match=re.escape(f"fps={fps!r}")):
        check_fps(fps)


@pytest.mark.parametrize(
    "times, match",
    [
        ([1.0, 0.5], r"#1 \(0\.5 s\) <= time #0 \(1\.0 s\)"),
        ([0.0, 0.0], r"#1 \(0\.0 s\)"),
        ([[0.0, 1.0]], r"shape \(1, 2\)"),
        ([-1.0, 2.0], "-1.0"),
        ([0.1, np.nan], r"index \(1,\)"),
    ],
)
def test_bad_times(times, match):
    with pytest.raises(ParameterError, match=match):
        check_times(times)


@pytest.mark.parametrize(
    "times, match",
    [
        (np.array([2.5, 1.25]), r"time #1 \(1\.25 s\) <= time #0 \(2\.5 s\)"),
        (np.array([-0.5, 1.0]), r"negative time -0\.5;"),
    ],
)
def test_bad_times_message_shows_plain_numbers(times, match):
    # numpy scalars in the message read as plain seconds, not as np.float64(...)
    with pytest.raises(ParameterError, match=match) as info:
        check_times(times, name="beat times")
    assert "np.float64" not in str(info.value)


@pytest.mark.parametrize("fps", [1e5, 44100])
def test_implausibly_high_motion_fps_is_refused(fps):
    # --out-fps 100000 made sync resample a 28 s dance to 2.8 million frames (10 GB)
    with pytest.raises(ParameterError, match=rf"out_fps={fps!r} Hz .*2000 Hz"):
        check_motion_fps(fps, name="out_fps")
    assert check_motion_fps(2000) == 2000.0
    assert check_fps(fps) == fps  # audio sample rates stay valid for check_fps


def test_times_that_look_like_frames():
    with pytest.raises(ParameterError, match="900 s.*frame indices"):
        check_times([30.0, 60.0, 900.0], duration=10.0)


def test_empty_times_policy():
    assert check_times([]).size == 0
    with pytest.raises(ParameterError, match="times is empty"):
        check_times([], allow_empty=False)


def test_range():
    assert check_range(0.25, 1.25, name="period_range", unit="s") == (0.25, 1.25)
    with pytest.raises(ParameterError, match=r"\(1\.25, 0\.25\)"):
        check_range(1.25, 0.25, name="period_range", unit="s")


# --------------------------------------------------------------- one validation layer


@pytest.mark.parametrize(
    "value, match",
    [
        ("abc", r"delta='abc'.*text"),
        ("0.5", r"delta='0\.5'.*text"),
        (None, r"delta=None.*not a number"),
        (True, r"delta=True.*bool"),
        (np.array([0.5, 0.6]), r"delta=array\(\[0\.5, 0\.6\]\)"),
        ([0.5], r"delta=\[0\.5\].*list"),
        (np.nan, r"delta=nan.*finite"),
        (np.inf, "delta=inf"),
        (1e999, "delta=inf"),
    ],
)
def test_as_float_refuses(value, match):
    with pytest.raises(ParameterError, match=match):
        as_float(value, name="delta", unit="s")


def test_as_float_accepts_numbers_and_numpy_scalars():
    assert as_float("0.5", name="d", unit="s", text=True) == 0.5
    with pytest.raises(ParameterError, match="d='abc'"):
        as_float("abc", name="d", unit="s", text=True)
    assert as_float(np.float32(2), name="d", unit="s") == 2.0
    assert as_float(np.array(3.0), name="d", unit="s") == 3.0
    assert np.isnan(as_float(np.nan, name="d", unit="s", allow_nonfinite=True))


@pytest.mark.parametrize(
    "value, match", [(2.5, "n_periods=2.5"), (1, "n_periods=1 .*>= 2"), ("x", "n_periods='x'")]
)
def test_as_int_refuses(value, match):
    with pytest.raises(ParameterError, match=match):
        as_int(value, name="n_periods", minimum=2)


def test_as_int_accepts_integral_floats():
    assert as_int(3.0, name="n", minimum=2) == 3


@pytest.mark.parametrize(
    "value, match",
    [
        (0, r"win_s=0 .*> 0 \[s\]"),
        (-1, "win_s=-1"),
        (np.nan, "win_s=nan"),
        ("x", "win_s='x'"),
        (False, "win_s=False"),
    ],
)
def test_check_positive_refuses(value, match):
    with pytest.raises(ParameterError, match=match):
        check_positive(value, name="win_s", unit="s")


@pytest.mark.parametrize(
    "sr, match",
    [
        (0, "sr=0"),
        (-22050, "sr=-22050"),
        (np.nan, "sr=nan"),
        ("fast", "sr='fast'"),
        (44.1, r"sr=44\.1 .*sr=44100"),
        (None, "sr=None"),
    ],
)
def test_check_sample_rate_refuses(sr, match):
    with pytest.raises(ParameterError, match=match):
        check_sample_rate(sr)


def test_check_sample_rate_accepts():
    assert check_sample_rate(22050) == 22050.0
    assert check_sample_rate(np.int64(8000)) == 8000.0


@pytest.mark.parametrize(
    "bpm, match",
    [
        (0.5, r"bpm=0\.5 .*beat period"),
        (2.0, "bpm=2.0 .*beats per second"),
        (1000, "bpm=1000 .*sub-beats"),
        (0, "bpm=0 .*positive"),
        (-5, "bpm=-5 .*positive"),
        (np.nan, "bpm=nan"),
        (np.inf, "bpm=inf"),
        ("inf", "bpm='inf'"),
        ("x", "bpm='x'"),
    ],
)
def test_check_bpm_refuses(bpm, match):
    with pytest.raises(ParameterError, match=match):
        check_bpm(bpm)


def test_check_bpm_one_range():
    assert (MIN_BPM, MAX_BPM) == (20.0, 400.0)
    assert check_bpm(20) == 20.0 and check_bpm(400) == 400.0


def test_check_audio_keeps_float32_without_copy():
    y = np.linspace(-0.5, 0.5, 2205, dtype=np.float32)
    out, sr = check_audio(y, 22050)
    assert out is y and out.dtype == np.float32 and sr == 22050.0
    out64, _ = check_audio(y.astype(np.float64), 22050)
    assert out64.dtype == np.float64
    outi, _ = check_audio(np.arange(2205, dtype=np.int16), 22050)
    assert outi.dtype == np.float64


_Y = np.full(2205, 0.1, dtype=np.float32)


@pytest.mark.parametrize(
    "y, sr, kwargs, match",
    [
        (np.stack([_Y, _Y]), 22050, {}, r"shape \(2, 2205\).*mean\(axis=0\)"),
        (_Y[:0], 22050, {}, "zero samples"),
        (
            np.where(np.arange(2205) == 7, np.nan, _Y),
            22050,
            {},
            "1 NaN or infinite sample.*sample 7",
        ),
        (_Y, 0, {}, r"sr=0 "),
        (_Y + 1j, 22050, {}, "complex"),
        (["a"] * 5, 22050, {}, "strings"),
        (_Y, 22050, {"min_duration": 1.0}, r"0\.100 s .*2205 samples"),
        (_Y * 0, 22050, {"silence_peak": 1e-7}, "silent .*1e-07"),
        (_Y, 22050, {"silence_peak": 1e-7}, r"constant at 0\.1 "),
        (_Y - 0.3, 22050, {"silence_peak": 1e-7}, r"constant at -0\.2"),
    ],
)
def test_check_audio_refuses(y, sr, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        check_audio(y, sr, **kwargs)


def test_check_audio_finite_and_level_checks_at_the_edges():
    # finite samples whose sum overflows are not taken for infinite ones
    loud = np.full(2205, 3e38, dtype=np.float32)
    loud[::2] *= -1
    loud[:4] = 3e38
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.isfinite(loud.sum())
    assert check_audio(loud, 22050, silence_peak=1e-7)[0] is loud
    # an infinite sample among finite ones whose sum would be finite
    for bad in (np.inf, -np.inf, np.nan):
        y = _Y.copy()
        y[100] = bad
        with pytest.raises(ParameterError, match="1 NaN or infinite sample.*sample 100"):
            check_audio(y, 22050)
    # the peak and the spread are the largest magnitudes either side
    neg = np.full(2205, -0.5, dtype=np.float32)
    neg[10] = -0.5 - 2e-7
    assert check_audio(neg, 22050, silence_peak=1e-7)[0] is neg
    with pytest.raises(ParameterError, match=r"constant at -0\.5"):
        check_audio(np.full(2205, -0.5, dtype=np.float32), 22050, silence_peak=1e-7)


def test_check_audio_near_the_float64_maximum_warns_nothing():
    # the float64 mean of samples near 1.8e308 overflows: the level is taken relative
    # to the peak instead (an overflow warning and "constant at nan" before)
    huge = np.full(2205, 1.7e308)
    huge[::2] *= -1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_audio(huge, 22050, silence_peak=1e-7)[0] is huge
        with pytest.raises(ParameterError, match=r"constant at 1\.7e\+308"):
            check_audio(np.full(2205, 1.7e308), 22050, silence_peak=1e-7)


@pytest.mark.parametrize(
    "values, match",
    [
        ([[1.0, 2.0], [3.0]], "values .*ragged"),
        (np.array([1 + 2j]), "complex"),
        (np.array(["1.0"]), "strings"),
        (np.array([b"1"]), "bytes"),
        (np.array([True, False]), "booleans"),
        (np.array(["2020-01-01"], dtype="datetime64[D]"), "dates"),
        (np.zeros(2, dtype=[("a", "f8"), ("b", "f8")]), "records"),
        ([1.0, None], "None"),
    ],
)
def test_as_float_array_refuses_non_numeric(values, match):
    with pytest.raises(ParameterError, match=match):
        as_float_array(values, name="values")


def test_check_finite_dtype_none_keeps_float32():
    x = np.zeros(3, dtype=np.float32)
    assert check_finite(x, name="x", dtype=None) is x
    assert check_finite(x, name="x").dtype == np.float64


def test_check_times_refuses_strings_as_parameter_error():
    with pytest.raises(ParameterError, match="strings"):
        check_times(["a", "b"])


def test_check_helpers_accept_numbers_written_as_text():
    assert check_positive("2.5", name="th", unit="rd") == 2.5
    assert check_fps("60", name="fps") == 60.0
    assert check_bpm("120") == 120.0


@pytest.mark.parametrize(
    "pair, match",
    [
        (0.5, r"period_range=0\.5 .*two numbers"),
        ((0.5, 1.0, 2.0), r"period_range=\(0\.5, 1\.0, 2\.0\)"),
        ("ab", "period_range='ab'"),
        ((2.0, 0.5), r"period_range=\(2\.0, 0\.5\)"),
        ((0.0, 1.0), r"period_range=\(0\.0, 1\.0\)"),
    ],
)
def test_check_interval_refuses(pair, match):
    from beatsync.validation import check_interval

    with pytest.raises(ParameterError, match=match):
        check_interval(pair, name="period_range", unit="s")


def test_check_interval_accepts_arrays_and_lists():
    from beatsync.validation import check_interval

    assert check_interval(np.array([0.5, 2.0]), name="r", unit="s") == (0.5, 2.0)
    assert check_interval([1, 3], name="r", unit="s") == (1.0, 3.0)


def test_check_choice_names_the_value_and_the_options():
    assert check_choice("loop", ("stop", "loop"), name="fill") == "loop"
    with pytest.raises(ParameterError, match=r"fill='Loop' must be one of 'stop', 'loop'"):
        check_choice("Loop", ("stop", "loop"), name="fill")
    # not text (an array, a number): refused the same way, not numpy's truth-value error
    for bad in (np.array(["loop"]), 1, None):
        with pytest.raises(ParameterError, match=r"fill=.* must be one of"):
            check_choice(bad, ("stop", "loop"), name="fill")
