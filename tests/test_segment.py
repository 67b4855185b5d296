"""Tests of the optimal periodic segmentation (beatsync.segment, paper A sec. 3)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from beatsync import datasets
from beatsync.errors import BeatsyncWarning, NotPeriodicError, ParameterError
from beatsync.evaluate.segmentation import boundary_errors
from beatsync.motion import Motion, marker_angles
from beatsync.segment import (
    DANCE_PERIOD_RANGE,
    SEARCH_MEMORY_BUDGET,
    Segmentation,
    estimate_period_count,
    period_range_from_beat,
    segment,
    segment_values,
    segmentation_energy,
    select_channels,
)
from beatsync.segment import core as segment_core
from beatsync.segment.channels import standardise
from beatsync.segment.costs import edge_costs, pair_costs, resample_weights
from beatsync.segment.period import estimate_period, estimation_band, period_tiers
from beatsync.segment.reference import segment_literal
from beatsync.segment.search import (
    count_fits,
    min_mean_energy,
    optimum,
    period_band,
    search_bytes,
    search_decimation,
    shortest_path,
    shortest_path_count,
)
from beatsync.study.paper_a_segmentation import (
    minima_baseline,
    synthetic_error_table,
    uniform_baseline,
)
from beatsync.synth.motion import periodic_motion


# ----------------------------------------------------------------- synthetic truth
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("method", ["given", "energy"])
def test_synthetic_boundaries_within_one_frame(seed, method):
    """Paper-scale synthetic signal (29 ch, 25 Hz, n=750) at 20 dB SNR, alpha 0.1."""
    s = periodic_motion(n_frames=750, n_channels=29, fps=25.0, n_periods=25, jitter=0.08,
                        variation=0.05, snr_db=20.0, seed=seed)  # fmt: skip
    n_periods = 25 if method == "given" else None
    seg = segment(s.motion, alpha=0.1, n_periods=n_periods)
    assert isinstance(seg, Segmentation)
    assert seg.n_periods == s.n_periods
    err = np.abs(seg.boundary_frames - s.boundary_frames)
    assert err.max() <= 1, err
    assert seg.mean_period == pytest.approx(s.period, rel=0.01)
    assert seg.period_method == method
    assert np.all(np.diff(seg.boundaries) > 0)


def test_noiseless_synthetic_is_exact():
    s = periodic_motion(n_frames=500, n_periods=16, snr_db=None, variation=0.0, seed=9)
    seg = segment_values(s.motion.values, fps=25.0, n_periods=16)
    assert np.array_equal(seg.boundary_frames, s.boundary_frames)
    assert seg.normalised_energy < 1e-3  # only linear-resampling error remains


def test_constant_channels_are_excluded():
    s = periodic_motion(n_frames=400, n_periods=12, n_constant=4, seed=2)
    seg = segment(s.motion, n_periods=12)
    assert len(seg.channels) == 25
    assert np.abs(seg.boundary_frames - s.boundary_frames).max() <= 1


def test_estimate_period_count_synthetic():
    s = periodic_motion(seed=5)
    for method in ("energy", "fft"):
        p = estimate_period_count(s.motion.values, fps=25.0, method=method)
        assert abs(p - 25) <= 1


# ------------------------------------------------------- DP optimum vs reference
def _brute_force(x, lo, hi):
    n = x.shape[1]
    best = (np.inf, None)

    def rec(fr):
        nonlocal best
        if len(fr) >= 3 and fr[-1] >= n - lo:
            e = segmentation_energy(x, np.array(fr)) / (len(fr) - 2)  # mean per pair
            if e < best[0] - 1e-12:
                best = (e, list(fr))
        for d in range(lo, hi + 1):
            if fr[-1] + d <= n - 1:
                rec(fr + [fr[-1] + d])

    for t0 in range(lo):
        rec([t0])
    return best


def _same_boundaries(a, b):
    """Same count and every boundary within one frame (near-ties may round either way)."""
    assert a.size == b.size, (a, b)
    assert np.abs(a - b).max() <= 1, (a, b)


@pytest.mark.parametrize("seed", range(12))
def test_dp_equals_literal_and_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(14, 36))
    n_ch = int(rng.integers(1, 4))
    lo = int(rng.integers(3, 6))
    hi = lo + int(rng.integers(0, 3))
    t = np.arange(n)
    raw = np.sin(2 * np.pi * t / rng.uniform(4, 8))[:, None] + 0.5 * rng.standard_normal((n, n_ch))
    x = standardise(raw)
    cost = edge_costs(x, lo, hi)
    # plain argmin E (one DP pass) against the literal loops
    f0, e0 = shortest_path(cost, n, lo, hi)
    f0_lit, e0_lit = segment_literal(x, lo, hi, 0.0)
    assert e0 == pytest.approx(e0_lit, abs=1e-9)
    assert segmentation_energy(x, f0) == pytest.approx(e0_lit, abs=1e-9)
    _same_boundaries(f0, f0_lit)
    # the objective of segment(): min E / (p - 1), vs literal and brute force
    f_fast, e_fast = min_mean_energy(lambda r: shortest_path(cost, n, lo, hi, r))
    f_lit, e_lit = segment_literal(x, lo, hi)
    m_bf, f_bf = _brute_force(x, lo, hi)
    assert e_fast / (f_fast.size - 2) == pytest.approx(e_lit / (f_lit.size - 2), abs=1e-9)
    _same_boundaries(f_fast, f_lit)
    assert e_fast / (f_fast.size - 2) == pytest.approx(m_bf, abs=1e-9)
    assert segmentation_energy(x, f_fast) == pytest.approx(e_fast, abs=1e-9)


def test_vectorised_edge_costs_match_direct_pearson(rng):
    s = periodic_motion(n_frames=300, n_channels=5, n_periods=10, seed=1)
    x = standardise(s.motion.values)
    lo, hi = 26, 33
    cost = edge_costs(x, lo, hi)
    n = x.shape[1]
    b = rng.integers(lo, n - lo, 500)
    i0 = rng.integers(0, hi - lo + 1, 500)
    i1 = rng.integers(0, hi - lo + 1, 500)
    ok = (b - lo - i0 >= 0) & (b + lo + i1 <= n - 1)
    b, i0, i1 = b[ok], i0[ok], i1[ok]
    ref = pair_costs(x, b - lo - i0, b, b + lo + i1)
    np.testing.assert_allclose(cost[b, i0, i1], ref, atol=1e-10)
    # one edge by hand: np.interp + np.corrcoef
    a0, b0, c0 = 40, 70, 101
    want = 0.0
    for ch in range(x.shape[0]):
        bb = np.interp(np.arange(31) * 31 / 30, np.arange(32), x[ch, b0 : c0 + 1])
        want += 1 - np.corrcoef(x[ch, a0 : b0 + 1], bb)[0, 1]
    assert cost[b0, 30 - lo, 31 - lo] == pytest.approx(want, abs=1e-5)


# --------------------------------------------------------------------- real data
def test_salsa_knee_period_about_one_second():
    m = datasets.load_salsa("60_01")
    seg = segment(m, channels=["rShin_Xrotation", "lShin_Xrotation"])
    assert seg.mean_period == pytest.approx(1.0, abs=0.08)
    assert seg.n_periods >= 30


def test_salsa_default_channels_period():
    seg = segment(datasets.load_salsa("60_01"))
    assert len(seg.channels) == 39
    assert 0.9 <= seg.mean_period <= 1.15


def test_dance2_knee_period_near_toolbox_value():
    """MoCap Toolbox documents a 0.51 s vertical period for dance2; the knees give ~0.53 s.

    With all 11 marker angles the energy method prefers the double (~1.1 s), the cycle
    over which left and right legs alternate (see notebook fig02)."""
    angles = marker_angles(datasets.load_mocap_toolbox("dance2"))
    knees = segment(angles, channels=["knee_L_angle", "knee_R_angle"])
    assert knees.mean_period == pytest.approx(0.51, abs=0.04)
    full = segment(angles)
    assert full.mean_period == pytest.approx(2 * knees.mean_period, rel=0.1)


@pytest.mark.parametrize("clip,period", [("007_01", 1.07), ("007_12", 0.87)])
def test_walking_gait_cycle(clip, period):
    seg = segment(datasets.load_walk(clip))
    assert seg.mean_period == pytest.approx(period, abs=0.06)
    assert seg.channels[0].startswith("CC_Base_")


@pytest.mark.parametrize("method", ["energy", "fft"])
def test_pirouette_is_not_periodic(method):
    with pytest.raises(ParameterError, match="not periodic"):
        segment(datasets.load_walk("005_02"), period_method=method)


# ---------------------------------------------------------------------- channels
def test_default_channels_cmu_names():
    m = datasets.load_salsa("60_01")
    chosen = select_channels(m.channels)
    joints = {c.rsplit("_", 1)[0] for c in chosen}
    assert joints == {"abdomen", "chest", "neck", "rShldr", "rForeArm", "lShldr", "lForeArm",
                      "rThigh", "rShin", "rFoot", "lThigh", "lShin", "lFoot"}  # fmt: skip
    assert all(c.endswith("rotation") for c in chosen)


def test_default_channels_iclone_names():
    joints_in = ("CC_Base_L_Thigh", "CC_Base_L_Calf", "CC_Base_Spine01", "CC_Base_L_CalfTwist01",
                 "CC_Base_L_Hand", "CC_Base_Hip", "CC_Base_R_Upperarm", "CC_Base_R_Forearm",
                 "CC_Base_L_Foot", "CC_Base_L_ToeBase")  # fmt: skip
    names = [f"{j}_{d}rotation" for j in joints_in for d in "XYZ"]
    names += ["RL_BoneRoot_Xposition", "CC_Base_Spine01_Xposition"]
    joints = {c.rsplit("_", 1)[0] for c in select_channels(names)}
    assert joints == {"CC_Base_L_Thigh", "CC_Base_L_Calf", "CC_Base_Spine01",
                      "CC_Base_R_Upperarm", "CC_Base_R_Forearm", "CC_Base_L_Foot"}  # fmt: skip


def test_channel_selection_modes():
    names = ["knee_L_angle", "knee_R_angle", "Head_FL_x"]
    assert select_channels(names) == ("knee_L_angle", "knee_R_angle")
    assert select_channels(names, "all") == tuple(names)
    assert select_channels(names, ["Head_FL_x"]) == ("Head_FL_x",)
    with pytest.raises(ParameterError, match="knee_X"):
        select_channels(names, ["knee_X"])
    with pytest.raises(ParameterError):
        select_channels(names, "some")
    with pytest.warns(BeatsyncWarning, match="using all channels"):
        assert select_channels(["a", "b"]) == ("a", "b")


def test_rotation_channels_are_unwrapped():
    """A knee-like rotation crossing the +-180 wrap segments like its unwrapped self."""
    s = periodic_motion(n_frames=400, n_channels=3, n_periods=12, snr_db=30, seed=3)
    vals = s.motion.values - s.motion.values.mean(axis=0) + 175.0
    wrapped = (vals + 180.0) % 360.0 - 180.0
    names = ("rShin_Xrotation", "lShin_Xrotation", "rThigh_Xrotation")
    seg_w = segment(Motion(wrapped, 25.0, names), n_periods=12)
    seg_u = segment(Motion(vals, 25.0, names), n_periods=12)
    assert np.array_equal(seg_w.boundary_frames, seg_u.boundary_frames)


# -------------------------------------------------------------------- bad input
def _vals(n=300, c=4):
    return periodic_motion(n_frames=n, n_channels=c, n_periods=10, seed=0).motion.values


def _with_nan():
    v = _vals()
    v[10, 1] = np.nan
    return v


def _with_inf():
    v = _vals()
    v[5, 0] = np.inf
    return v


@pytest.mark.parametrize(
    "values,kwargs,match",
    [
        (_with_nan(), {}, "NaN"),
        (_with_inf(), {}, "NaN or infinite"),
        (_vals(), {"fps": 0.0}, "fps"),
        (_vals(), {"fps": -25.0}, "fps"),
        (_vals(), {"fps": float("nan")}, "fps"),
        (_vals(), {"alpha": 0.0}, "alpha"),
        (_vals(), {"alpha": 0.5}, "alpha"),
        (_vals(), {"alpha": 10.0}, "alpha=10.0"),
        (_vals(), {"alpha": -0.1}, "alpha"),
        (_vals(), {"period_range": (1.25, 0.25)}, "reversed"),
        (_vals(), {"period_range": (0.0, 1.0)}, "> 0"),
        (_vals()[:12], {}, "clip of 12 frames"),
        (_vals()[:19], {}, "clip of 19 frames"),
        (_vals(), {"fps": 2500.0, "period_range": (0.25, 1.25)}, "fps=2500"),
        (_vals(), {"period_range": (0.25, 1.25, 2.0)}, "two numbers"),
        (_vals(), {"period_range": (0.25, 0.06)}, "reversed"),
        (_vals(), {"n_periods": 10, "period_method": "wavelet"}, "period_method"),
        (_vals(), {"n_periods": 1}, "n_periods"),
        (_vals(), {"n_periods": 2.5}, "n_periods"),
        (_vals(), {"n_periods": 200}, "200 periods in 300 frames"),
        (_vals(), {"period_method": "wavelet"}, "period_method"),
        (_vals(), {"period_method": "given"}, "period_method='given'"),
        (np.ones((300, 4)), {}, "constant"),
        (np.zeros((2, 300, 4)), {}, r"\(2, 300, 4\)"),
        (np.random.default_rng(0).standard_normal((300, 4)), {}, "not periodic"),
        (np.random.default_rng(1).standard_normal((300, 29)), {}, "not periodic"),
    ],
)
def test_bad_input_raises(values, kwargs, match):
    kw = {"fps": 25.0} | kwargs
    with pytest.raises(ParameterError, match=match):
        segment_values(values, **kw)


@pytest.mark.parametrize(
    "values,kwargs,not_periodic",
    [
        (np.random.default_rng(0).standard_normal((300, 4)), {}, True),  # noise
        (_vals(50), {"period_range": (1.0, 2.0)}, True),  # 2 s: too short for the range
        (_vals(), {"period_range": (0.25, 0.06)}, False),  # a mistake in the settings
        (_vals(), {"alpha": 0.7}, False),
        (np.ones((300, 4)), {}, False),  # no motion at all
    ],
)
def test_only_a_motion_not_shown_periodic_is_a_not_periodic_error(values, kwargs, not_periodic):
    # callers fall back to the dancer's motion beats on NotPeriodicError only: a bad
    # setting must not pass for a free dance
    with pytest.raises(ParameterError) as err:
        segment_values(values, **({"fps": 25.0} | kwargs))
    assert isinstance(err.value, NotPeriodicError) is not_periodic


def test_clip_shorter_than_three_own_periods_is_refused():
    """A 1 s excerpt of salsa (period ~1 s) from 10 s used to come back as 2 periods of 0.45 s."""
    m = datasets.load_salsa("60_01")
    start = int(10.0 * m.fps)
    clip = m.slice_frames(start, start + int(m.fps))  # 1 s
    # too short to tell: a NotPeriodicError, so mode "auto" falls back to motion beats
    with pytest.raises(NotPeriodicError, match=r"only 2\.\d periods"):
        segment(clip)
    # the same dance, long enough, is segmented at its period
    longer = m.slice_frames(start, start + int(16 * m.fps))
    assert 0.8 <= segment(longer).mean_period <= 1.2


def test_short_clip_of_clearly_alike_periods_is_kept():
    """2-2.5 periods of a clean 1 s cycle: one pair, clearly alike, so segmented."""
    s = periodic_motion(n_frames=251, n_periods=10, fps=25.0, snr_db=30, seed=0)
    for seconds in (2.0, 2.5):
        seg = segment_values(s.motion.values[: int(seconds * 25) + 1], fps=25.0)
        assert seg.n_periods == 2
        assert seg.normalised_energy < 0.5
        assert seg.mean_period == pytest.approx(1.0, abs=0.06)
    # a given count is the caller's word: two periods are allowed
    assert segment_values(s.motion.values[:51], fps=25.0, n_periods=2).n_periods == 2


def test_channel_name_count_mismatch():
    with pytest.raises(ParameterError, match="2 channel names for"):
        segment_values(_vals(), fps=25.0, channel_names=["a", "b"])


def test_no_warning_on_normal_input():
    s = periodic_motion(n_frames=300, n_periods=10, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        segment(s.motion)


def test_float32_edge_costs_close_to_float64():
    s = periodic_motion(n_frames=750, n_channels=29, n_periods=25, seed=6)
    x = standardise(s.motion.values)
    c64 = edge_costs(x, 26, 33)
    c32 = edge_costs(x, 26, 33, dtype=np.float32)
    ok = np.isfinite(c64)
    assert np.array_equal(ok, np.isfinite(c32))
    assert np.abs(c64[ok] - c32[ok]).max() < 1e-4
    f64, e64 = shortest_path(c64, 750, 26, 33)
    f32, e32 = shortest_path(c32, 750, 26, 33)
    assert e32 == pytest.approx(e64, rel=1e-5)
    assert segmentation_energy(x, f32) == pytest.approx(e64, rel=1e-5)
    _same_boundaries(f32, f64)


# ------------------------------------------------------ evaluation helpers (fig02)
def test_boundary_errors_and_baselines():
    ref = np.array([0, 30, 61, 90, 120])
    assert boundary_errors(ref, ref)["max"] == 0.0
    e = boundary_errors(ref + 3, ref, remove_offset=True)
    assert e["max"] == 0.0 and e["offset"] == 3.0
    e = boundary_errors(np.array([0, 32, 61, 88]), ref)
    assert e["max"] == 2.0 and e["count_error"] == -1
    t = np.arange(500)
    sine = np.cos(2 * np.pi * t / 25.0)
    mins = minima_baseline(sine, fps=25.0, period=1.0)
    assert np.allclose(np.diff(mins), 25, atol=1)
    uni = uniform_baseline(np.stack([sine, np.sin(2 * np.pi * t / 25.0)], 1), fps=25.0)
    assert abs(np.diff(uni).mean() - 25) < 0.5


def test_synthetic_error_table_small():
    table = synthetic_error_table(snr_dbs=[20.0], alphas=[0.1], seeds=[0], n_frames=300,
                                    n_channels=6, n_periods=10)  # fmt: skip
    assert set(table["method"]) == {
        "optimal, count estimated",
        "optimal, count given",
        "baseline: FFT period + uniform",
        "baseline: minima of channel 0",
    }
    opt = table[table["method"] == "optimal, count given"].iloc[0]
    assert opt["max_error_frames"] <= 1


# ------------------------------------------- fixed period count (n_periods honoured)
def _brute_force_count(x, lo, hi, count):
    """Least E over segmentations with exactly ``count`` periods (free ends)."""
    n = x.shape[1]
    best = (np.inf, None)

    def rec(fr):
        nonlocal best
        if len(fr) == count + 1:
            if fr[-1] >= n - lo:
                e = segmentation_energy(x, np.array(fr))
                if e < best[0] - 1e-12:
                    best = (e, list(fr))
            return
        for d in range(lo, hi + 1):
            if fr[-1] + d <= n - 1:
                rec(fr + [fr[-1] + d])

    for t0 in range(lo):
        rec([t0])
    return best


@pytest.mark.parametrize("seed", range(8))
def test_fixed_count_dp_equals_brute_force(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(16, 34))
    lo = int(rng.integers(3, 6))
    hi = lo + int(rng.integers(0, 3))
    t = np.arange(n)
    raw = np.sin(2 * np.pi * t / rng.uniform(4, 8))[:, None] + 0.5 * rng.standard_normal((n, 2))
    x = standardise(raw)
    cost = edge_costs(x, lo, hi)
    checked = 0
    for count in range(2, n // lo + 1):
        e_bf, f_bf = _brute_force_count(x, lo, hi, count)
        assert count_fits(n, lo, hi, count) == (f_bf is not None)
        if f_bf is None:
            with pytest.raises(RuntimeError, match=f"{count} periods of {lo}-{hi}"):
                shortest_path_count(cost, n, lo, hi, count)
            continue
        frames, energy = shortest_path_count(cost, n, lo, hi, count)
        assert frames.size == count + 1
        assert energy == pytest.approx(e_bf, abs=1e-9)
        assert segmentation_energy(x, frames) == pytest.approx(e_bf, abs=1e-9)
        checked += 1
    assert checked >= 1


def test_given_count_is_honoured_or_refused():
    """True count 10: n_periods=12 used to return 10 periods silently."""
    s = periodic_motion(n_frames=300, n_periods=10, snr_db=30, seed=1)
    assert segment_values(s.motion.values, fps=25.0, n_periods=10).n_periods == 10
    with pytest.raises(ParameterError, match="n_periods=12"):
        segment_values(s.motion.values, fps=25.0, n_periods=12)
    seg = segment_values(s.motion.values, fps=25.0, n_periods=9, alpha=0.2)
    assert seg.n_periods == 9


def test_count_that_cannot_fit_is_detected():
    assert count_fits(300, 40, 42, 7)  # 7 * 40..42 frames fit in 300
    assert not count_fits(300, 40, 42, 8)  # 8 * 40 > 299
    s = periodic_motion(n_frames=300, n_periods=10, snr_db=30, seed=1)
    cost = edge_costs(standardise(s.motion.values), 40, 42)
    assert shortest_path_count(cost, 300, 40, 42, 7)[0].size == 8
    with pytest.raises(RuntimeError, match="8 periods of 40-42 frames"):
        shortest_path_count(cost, 300, 40, 42, 8)


# ------------------------------------------------------- memory of long periods
def test_long_period_runs_within_memory():
    """A ~400-frame period needed a (lags, hi+1, band^2) kernel of ~1.9 GiB."""
    import tracemalloc

    s = periodic_motion(n_frames=2401, n_channels=3, fps=400.0, n_periods=6, snr_db=30,
                        seed=3)  # fmt: skip
    x = standardise(s.motion.values)
    tracemalloc.start()
    try:
        seg = segment_values(s.motion.values, fps=400.0, n_periods=6)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < SEARCH_MEMORY_BUDGET
    lo, hi = period_band(2400 / 6, 0.1)
    assert search_bytes(2401, lo, hi, 3, 6) > 2 * SEARCH_MEMORY_BUDGET
    assert seg.search_decimation > 1
    assert seg.n_periods == 6
    assert np.abs(seg.boundary_frames - s.boundary_frames).max() <= 3
    assert seg.energy == pytest.approx(segmentation_energy(x, seg.boundary_frames), abs=1e-9)


@pytest.mark.parametrize("n_periods", [10, None])
def test_decimated_search_finds_the_exact_optimum(n_periods):
    """A search decimated to fit a smaller memory budget finds the full-rate optimum."""
    s = periodic_motion(n_frames=1200, n_channels=4, fps=100.0, n_periods=10, snr_db=20, seed=1)
    x = standardise(s.motion.values)
    if n_periods is None:
        nominal = estimate_period(x, *estimation_band(1200, 50.0, 200.0), "energy")
    else:
        nominal = 1199 / n_periods
    lo, hi = period_band(nominal, 0.1)
    assert search_decimation(1200, lo, hi, 4, n_periods) == 1
    factor = search_decimation(1200, lo, hi, 4, n_periods, budget=24 * 2**20)
    assert factor is not None and factor >= 2
    f_exact, e_exact = optimum(x, lo, hi, n_periods, 1)
    f_coarse, e_coarse = optimum(x, lo, hi, n_periods, factor)
    # float32 sums (exact search) vs float64 refinement: energies, and +-1 frame
    assert e_coarse == pytest.approx(e_exact, rel=1e-4)
    assert segmentation_energy(x, f_coarse) == pytest.approx(e_coarse, abs=1e-9)
    _same_boundaries(f_coarse, f_exact)


def test_undecimatable_period_is_refused(monkeypatch):
    lo, hi = period_band(299 / 10, 0.1)
    assert search_decimation(300, lo, hi, 29, 10, budget=1) is None
    s = periodic_motion(n_frames=300, n_periods=10, snr_db=30, seed=1)
    monkeypatch.setattr(segment_core, "SEARCH_MEMORY_BUDGET", 1)
    with pytest.raises(ParameterError, match=r"band \d+-\d+"):
        segment_values(s.motion.values, fps=25.0, n_periods=10)


def test_resample_weights_vectorised_equals_scalar():
    d1 = np.array([7, 9, 10, 12])
    j, w = resample_weights(10, d1)
    assert j.shape == w.shape == (4, 11)
    for row, d in enumerate(d1):
        js, ws = resample_weights(10, int(d))
        np.testing.assert_array_equal(j[row], js)
        np.testing.assert_array_equal(w[row], ws)
        # resampling a ramp is exact: k * d1 / d0
        np.testing.assert_allclose(js + ws, np.arange(11) * d / 10)


# ------------------------------------------------------- period range (dance cycles)
def test_period_range_from_beat():
    assert period_range_from_beat(0.5) == pytest.approx((0.45, 4.25))  # 1-8 beats, room
    assert period_range_from_beat(0.7, beats=(3, 6)) == pytest.approx((2.1, 4.2))


@pytest.mark.parametrize(
    "beat,kw,match",
    [
        (120.0, {}, "beat_period=120.0"),  # a tempo, not a beat period
        (0.0, {}, r"beat_period=0.0 must be in \[0.15, 3\]"),
        (float("nan"), {}, "finite"),
        ("fast", {}, "not a number"),
        (0.5, {"beats": (8, 1)}, "reversed"),
        (0.5, {"beats": (0, 8)}, "> 0"),
        (0.5, {"beats": 8}, "two numbers"),
    ],
)
def test_period_range_from_beat_bad_input(beat, kw, match):
    with pytest.raises(ParameterError, match=match):
        period_range_from_beat(beat, **kw)


def test_period_tiers():
    assert period_tiers(0.25, 1.25) == [(0.25, 1.25)]
    assert period_tiers(*DANCE_PERIOD_RANGE) == [(0.25, 1.25), (1.25, 6.25)]
    assert period_tiers(0.5, 4.0) == [(0.5, 2.5), (2.5, 4.0)]


def test_long_cycle_found_in_the_dance_range():
    """A 4 s figure (like a waltz box) with no shorter repetition."""
    s = periodic_motion(n_frames=1001, n_channels=12, fps=25.0, n_periods=10, snr_db=20, seed=2)
    with pytest.raises(ParameterError, match="not periodic"):
        segment(s.motion)  # the paper's 0.25-1.25 s
    seg = segment(s.motion, period_range=DANCE_PERIOD_RANGE)
    assert seg.mean_period == pytest.approx(4.0, rel=0.03)
    assert np.abs(seg.boundary_frames - s.boundary_frames[: seg.n_periods + 1]).max() <= 2
    seg_b = segment(s.motion, period_range=period_range_from_beat(0.5))  # 1-8 beats
    assert seg_b.mean_period == pytest.approx(4.0, rel=0.03)


@pytest.mark.slow
def test_dance_range_keeps_the_step_period_of_salsa():
    """Searched at once over 0.25-6 s, salsa 61_04 came out as 9 periods of 2.9 s."""
    m = datasets.load_salsa("61_04")
    seg = segment(m, period_range=DANCE_PERIOD_RANGE)
    assert seg.mean_period == pytest.approx(segment(m).mean_period, abs=1e-9)
    assert 0.95 <= seg.mean_period <= 1.1


def test_nonperiodic_refusal_is_shown_whole_or_cut_after_a_word(monkeypatch):
    # the notebook showed "... and uniform segmentat ...": cut in the middle of a word
    from beatsync.study import paper_a_segmentation as study

    def refuse(*args, **kwargs):
        raise ParameterError("the motion is not periodic: uniform segmentations beat it")

    monkeypatch.setattr(study, "segment", refuse)
    motion = periodic_motion(n_frames=100, n_periods=5, seed=0).motion
    whole = study.nonperiodic_refusal(motion, alpha=0.1, period_range=(0.25, 1.25), max_chars=600)
    assert whole == "the motion is not periodic: uniform segmentations beat it"
    cut = study.nonperiodic_refusal(motion, alpha=0.1, period_range=(0.25, 1.25), max_chars=40)
    assert cut == "the motion is not periodic: uniform ..."
