import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.units import check_fps, check_range, check_times, frames_to_time, time_to_frames


def test_frames_seconds_round_trip():
    frames = np.array([0, 1, 59, 60, 6000])
    t = frames_to_time(frames, fps=60.0)
    assert t[3] == 1.0
    np.testing.assert_array_equal(time_to_frames(t, fps=60.0), frames)


def test_fractional_frames():
    assert time_to_frames([0.5], fps=25, round_to_int=False)[0] == pytest.approx(12.5)


@pytest.mark.parametrize("fps", [0, -25, np.nan, np.inf, "x", None])
def test_bad_fps(fps):
    with pytest.raises(ParameterError, match="fps"):
        check_fps(fps)


@pytest.mark.parametrize(
    "times, match",
    [
        ([1.0, 0.5], "strictly increasing"),
        ([0.0, 0.0], "strictly increasing"),
        ([[0.0, 1.0]], "1-D"),
        ([-1.0, 2.0], "negative"),
        ([0.1, np.nan], "NaN"),
    ],
)
def test_bad_times(times, match):
    with pytest.raises(ParameterError, match=match):
        check_times(times)


def test_times_that_look_like_frames():
    with pytest.raises(ParameterError, match="frame indices"):
        check_times([30.0, 60.0, 900.0], duration=10.0)


def test_empty_times_policy():
    assert check_times([]).size == 0
    with pytest.raises(ParameterError, match="empty"):
        check_times([], allow_empty=False)


def test_range():
    assert check_range(0.25, 1.25, name="period_range", unit="s") == (0.25, 1.25)
    with pytest.raises(ParameterError, match="reversed"):
        check_range(1.25, 0.25, name="period_range", unit="s")
