"""Tests of the synthetic periodic joint-angle generator (beatsync.synth.motion)."""

from __future__ import annotations

import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.synth.motion import periodic_motion


def test_shape_and_ground_truth_contract():
    s = periodic_motion(n_frames=750, n_channels=29, fps=25.0, n_periods=25, seed=3)
    assert s.motion.values.shape == (750, 29)
    assert s.motion.fps == 25.0
    assert s.n_periods == 25
    assert s.boundary_frames[0] == 0 and s.boundary_frames[-1] == 749
    assert np.all(np.diff(s.boundaries) > 0)
    np.testing.assert_allclose(s.boundaries, s.boundary_frames / 25.0)
    assert s.period == pytest.approx(749 / 25 / 25.0)


@pytest.mark.parametrize("jitter", [0.0, 0.05, 0.1])
def test_period_durations_within_jitter(jitter):
    s = periodic_motion(n_frames=900, n_periods=20, jitter=jitter, seed=1)
    d = np.diff(s.boundary_frames)
    nominal = 899 / 20
    # rounding to whole frames and rescaling to span the clip add at most ~1 frame
    assert np.all(np.abs(d - nominal) <= jitter * nominal * 1.1 + 1.0)


def test_noise_level_matches_snr():
    s = periodic_motion(snr_db=10.0, seed=2)
    noise = s.motion.values - s.clean
    ratio = s.clean.var(axis=0) / noise.var(axis=0)
    assert 10 * np.log10(np.median(ratio)) == pytest.approx(10.0, abs=0.5)
    assert np.array_equal(periodic_motion(snr_db=None, seed=2).motion.values, s.clean)


def test_periods_are_warped_copies_without_variation():
    s = periodic_motion(n_frames=400, n_periods=10, variation=0.0, snr_db=None, seed=4)
    f = s.boundary_frames
    # resample two periods to a common length: identical waveforms
    grid = np.linspace(0, 1, 50)
    a = np.interp(f[3] + grid * (f[4] - f[3]), np.arange(400), s.clean[:, 0])
    b = np.interp(f[6] + grid * (f[7] - f[6]), np.arange(400), s.clean[:, 0])
    assert np.corrcoef(a, b)[0, 1] > 0.99


def test_constant_channels_and_seed():
    s = periodic_motion(n_constant=3, seed=5)
    assert int(np.sum(np.ptp(s.clean, axis=0) == 0)) == 3
    a = periodic_motion(seed=7).motion.values
    assert np.array_equal(a, periodic_motion(seed=7).motion.values)
    assert not np.array_equal(a, periodic_motion(seed=8).motion.values)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_periods": 1},
        {"n_frames": 20, "n_periods": 10},
        {"jitter": 0.6},
        {"jitter": -0.1},
        {"variation": -1.0},
        {"fps": 0.0},
        {"n_constant": 40},
    ],
)
def test_bad_parameters(kwargs):
    with pytest.raises(ParameterError):
        periodic_motion(**kwargs)


@pytest.mark.parametrize("kwargs", [{"n_moves": 0}, {"section_beats": 0}, {"n_moves": 2.5}])
def test_synthetic_dance_refuses_bad_counts_naming_them(kwargs):
    from beatsync.synth.library import synthetic_dance

    (name,) = kwargs
    with pytest.raises(ParameterError, match=name):
        synthetic_dance(duration=5, **kwargs)
