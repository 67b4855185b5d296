"""Tests of beatsync.motion_beats: kinematic beats and motion intensity."""

from __future__ import annotations

import numpy as np
import pytest

from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.motion import Motion
from beatsync.motion_beats import (
    beat_interval_intensity,
    interval_intensity,
    kinematic_beat_frames,
    kinematic_beats,
    kinetic_energy,
    zscore,
)

FPS = 60.0


def oscillator(freq=1.0, dur=4.0, fps=FPS, phase=0.0, amp=0.3):
    t = np.arange(0, dur, 1 / fps)
    pos = np.zeros((t.size, 3, 3))
    pos[:, 1, 0] = amp * np.sin(2 * np.pi * freq * t + phase)
    pos[:, 2, 1] = 0.5 * amp * np.sin(2 * np.pi * freq * t + phase)
    return pos


def as_markers(pos, fps=FPS):
    n, j, _ = pos.shape
    ch = tuple(f"m{i}_{a}" for i in range(j) for a in "xyz")
    return Motion(pos.reshape(n, -1), fps, ch, None, "markers")


def test_speed_beats_at_turning_points():
    # x = sin(2 pi t): speed |cos| is zero at t = 0.25 + k/2
    frames = kinematic_beat_frames(oscillator(), fps=FPS)
    expected = np.arange(0.25, 4.0, 0.5)
    np.testing.assert_allclose(frames / FPS, expected, atol=1.5 / FPS)


def test_pca_beats_at_extrema():
    frames = kinematic_beat_frames(oscillator(), fps=FPS, method="pca")
    expected = np.arange(0.25, 4.0, 0.5)
    inner = (frames / FPS > 0.5) & (frames / FPS < 3.5)
    np.testing.assert_allclose(frames[inner] / FPS, expected[1:-1], atol=1.5 / FPS)


def test_min_interval_thins_beats():
    frames = kinematic_beat_frames(oscillator(freq=2.0), fps=FPS, min_interval=0.4, smooth=0.02)
    assert np.all(np.diff(frames) >= 0.4 * FPS)


def test_kinematic_beats_on_marker_motion_returns_seconds():
    m = as_markers(oscillator())
    beats = kinematic_beats(m)
    assert beats.dtype == np.float64
    assert np.all(np.diff(beats) > 0)
    np.testing.assert_allclose(beats * FPS, np.round(beats * FPS))  # on frame times
    np.testing.assert_allclose(beats, np.arange(0.25, 4.0, 0.5), atol=1.5 / FPS)


def test_upper_case_marker_axes_are_positions_too():
    pos = oscillator()
    n, j, _ = pos.shape
    ch = tuple(f"m{i}_{a}" for i in range(j) for a in "XYZ")
    upper = Motion(pos.reshape(n, -1), FPS, ch, None, "markers")
    assert upper.is_positional and upper.joint_names == ["m0", "m1", "m2"]
    np.testing.assert_array_equal(kinematic_beats(upper), kinematic_beats(as_markers(pos)))


def test_intensity_scales_with_amplitude_squared():
    slow = interval_intensity(oscillator(amp=0.1), [15, 45, 75], fps=FPS)
    fast = interval_intensity(oscillator(amp=0.3), [15, 45, 75], fps=FPS)
    np.testing.assert_allclose(fast / slow, 9.0, rtol=1e-9)
    # known value: over half a period, mean of 0.5*v^2/3 joints with v = A w cos
    a, w = 0.3, 2 * np.pi
    expected = 0.5 * (a * w) ** 2 * (1 + 0.25) / 3 * 0.5
    np.testing.assert_allclose(fast, expected, rtol=0.01)


def test_beat_interval_intensity_motion_level():
    m = as_markers(oscillator())
    out = beat_interval_intensity(m, [0.25, 0.75, 1.25])
    assert out.shape == (2,)
    np.testing.assert_allclose(out[0], out[1], rtol=1e-6)


def test_kinetic_energy_static_is_zero():
    assert np.all(kinetic_energy(np.ones((10, 2, 3)), fps=FPS) == 0)


def test_static_motion_warns_and_returns_empty():
    with pytest.warns(BeatsyncWarning):
        frames = kinematic_beat_frames(np.ones((100, 2, 3)), fps=FPS)
    assert frames.size == 0


def test_zscore():
    z = zscore(np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(z.mean(), 0, atol=1e-12)
    np.testing.assert_allclose(z.std(), 1)
    with pytest.warns(BeatsyncWarning):
        assert np.all(zscore(np.ones(4)) == 0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"method": "fft"},
        {"smooth": -0.1},
        {"smooth": 100.0},  # milliseconds by mistake
        {"min_interval": float("nan")},
        {"fps": 0.0},
    ],
)
def test_bad_parameters(kwargs):
    kw = {"fps": FPS}
    kw.update(kwargs)
    with pytest.raises(ParameterError):
        kinematic_beat_frames(oscillator(), **kw)


@pytest.mark.parametrize(
    "beats",
    [
        [30, 60],  # frames, not seconds
        [0.5, 0.5],  # not increasing
        [0.5, 0.505],  # same frame
        [[0.1, 0.2]],  # 2-D
        [0.1, float("nan")],
    ],
)
def test_bad_beat_times(beats):
    with pytest.raises(ParameterError):
        beat_interval_intensity(as_markers(oscillator()), beats)


def test_too_short_and_nan_positions():
    with pytest.raises(ParameterError):
        kinematic_beat_frames(np.zeros((2, 1, 3)), fps=FPS)
    pos = oscillator()
    pos[5, 1, 0] = np.nan
    with pytest.raises(ParameterError):
        kinematic_beat_frames(pos, fps=FPS)


def test_unknown_joint_name():
    with pytest.raises(ParameterError, match="nose"):
        kinematic_beats(as_markers(oscillator()), joints=["nose"])


def test_salsa_beats_plausible():
    from beatsync import datasets

    m = datasets.load_salsa("60_01")
    beats = kinematic_beats(m)
    ibi = np.median(np.diff(beats))
    # partner salsa with turns: whole-body speed minima about every 0.5-1 s
    assert 0.3 <= ibi <= 1.2
    inten = beat_interval_intensity(m, beats)
    assert inten.shape == (beats.size - 1,)
    assert np.all(inten > 0)


def test_position_only_motion_uses_its_joint_positions():
    from beatsync.motion_beats import motion_positions

    t = np.arange(240) / 60.0
    pos = np.zeros((240, 3, 3))
    pos[:, 1, 2] = 1.0
    pos[:, 2, 2] = 1.5
    pos[:, 2, 0] = 0.3 * np.sin(2 * np.pi * t)  # the hand swings at 1 Hz
    channels = tuple(f"{j}_{a}" for j in ("root", "neck", "hand") for a in "xyz")
    m = Motion(pos.reshape(240, -1), 60.0, channels, None, "positions")
    assert m.is_positional
    np.testing.assert_allclose(motion_positions(m), pos)
    np.testing.assert_allclose(kinematic_beats(m), np.arange(0.25, 4.0, 0.5), atol=1.5 / 60)
    assert motion_positions(m, joints=["hand"]).shape == (240, 1, 3)
