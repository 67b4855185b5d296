"""Tests of beatsync.sync: the beat-synchronous time warp and resampling."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.motion import Joint, Motion, Skeleton
from beatsync.motion_beats import kinematic_beats
from beatsync.sync import SyncResult, beats_per_period, blended_rate, synchronize, time_warp

FPS = 30.0


def _skeleton() -> Skeleton:
    pos_rot = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    return Skeleton(
        (
            Joint("hip", -1, np.zeros(3), pos_rot),
            Joint("knee", 0, np.array([0.0, -0.4, 0.0]), ("Zrotation", "Xrotation", "Yrotation")),
            Joint("knee_end", 1, np.array([0.0, -0.4, 0.0]), (), True),
        )
    )


def _periodic_motion(period: float = 1.0, duration: float = 6.0, fps: float = FPS) -> Motion:
    t = np.arange(int(round(duration * fps))) / fps
    ph = 2 * np.pi * t / period
    vals = np.zeros((t.size, 9))
    vals[:, 0] = 0.3 * t  # walking forward [m]
    vals[:, 1] = 0.9 + 0.02 * np.cos(ph)
    vals[:, 3] = 10 * np.sin(ph)
    vals[:, 4] = 5 * np.sin(ph)
    vals[:, 7] = 40 * (1 - np.cos(ph))  # knee flexion
    return Motion(vals, fps, _skeleton().channel_names(), _skeleton(), "synthetic")


# ---------------------------------------------------------------- rule and rate


@pytest.mark.parametrize(
    "period, beat, expected",
    [(1.0, 0.5, 2), (1.0, 1.0, 1), (0.3, 0.5, 1), (3.0, 0.5, 6), (1.1, 0.5, 2)],
)
def test_beats_per_period_rule(period, beat, expected):
    beats = np.arange(20) * beat
    assert beats_per_period(period, beats) == expected


def test_beats_per_period_override():
    assert beats_per_period(1.0, np.arange(10) * 0.5, override=4) == 4


def test_blended_rate_constant_and_between():
    c = np.array([0.5, 1.5, 2.5])
    assert np.allclose(blended_rate(np.linspace(0, 3, 7), c, np.ones(3), delta=1.0), 1.0)
    r = blended_rate(np.array([0.5, 1.0, 1.5]), c[:2], np.array([1.0, 2.0]), delta=0.5)
    assert r[0] < 1.5 < r[2] and np.isclose(r[1], 1.5)


# ---------------------------------------------------------------- warp


def test_time_warp_lands_boundaries_exactly():
    rng = np.random.default_rng(1)
    s = np.cumsum(np.r_[0.2, rng.uniform(0.7, 1.3, 25)])
    b = 0.1 + np.cumsum(np.r_[0.0, rng.uniform(0.4, 0.6, 25)])
    w = time_warp(s, b, start=0.0, end=s[-1] + 0.5)
    assert np.allclose(w.to_target(s), b, atol=1e-9)
    assert np.all(np.diff(w.tgt) > 0) and np.all(w.rate > 0)
    # continuous rate: no jumps much larger than the within-period variation
    assert np.abs(np.diff(w.rate)).max() < 0.05
    # inverse
    assert np.allclose(w.to_source(b), s, atol=1e-9)


def test_warp_holds_its_rate_around_every_boundary():
    from beatsync.sync.warp import integrate_warp

    rng = np.random.default_rng(2)
    s = np.cumsum(np.r_[0.2, rng.uniform(0.7, 1.3, 12)])
    b = 0.1 + np.cumsum(np.r_[0.0, rng.uniform(0.6, 1.4, 12)])
    w = integrate_warp(s, b, hold=0.1)
    assert np.allclose(w.to_target(s), b, atol=1e-9)  # still lands every boundary
    for x in s[1:-1]:  # constant within 0.1 s on both sides of each inner boundary
        near = np.abs(w.src - x) <= 0.1 - 1e-9
        assert near.sum() >= 20 and np.ptp(w.rate[near]) < 1e-9
    # without a hold the rate changes there
    free = integrate_warp(s, b)
    near = np.abs(free.src - s[5]) <= 0.1
    assert np.ptp(free.rate[near]) > 1e-3


def test_time_warp_identity_when_tempi_match():
    s = np.arange(0.0, 5.01, 1.0)
    w = time_warp(s, s + 0.25)
    t = np.linspace(0, 5, 101)
    assert np.allclose(w.to_target(t), t + 0.25)
    assert np.allclose(w.rate, 1.0)


# ---------------------------------------------------------------- synchronize


def test_identity_when_tempi_match():
    m = _periodic_motion()
    bounds = np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.0, 8.0, 0.5)  # 2 beats per 1 s period, first beat on boundary 0
    res = synchronize(m, bounds, beats)
    assert isinstance(res, SyncResult)
    assert res.report["beats_per_period"] == 2
    assert res.motion.n_frames == m.n_frames
    assert np.allclose(res.warp_src_times, m.times, atol=1e-9)
    assert np.allclose(res.motion.values, m.values, atol=1e-6)


def test_exact_boundary_placement_other_tempo():
    m = _periodic_motion(period=1.0, duration=10.0)
    rng = np.random.default_rng(7)
    bounds = np.cumsum(np.r_[0.3, rng.uniform(0.9, 1.1, 8)])
    beats = 0.2 + np.cumsum(np.r_[0.0, rng.uniform(0.36, 0.40, 40)])  # about 158 BPM
    res = synchronize(m, bounds, beats, out_fps=60.0)
    rep = res.report
    assert rep["periods_used"] == 8 and rep["beats_per_period"] == 3
    frame_ms = 1000 / 60
    assert np.all(np.abs(rep["residual_ms"]) < 0.05 * frame_ms)
    assert np.all(np.abs(rep["residual_nearest_frame_ms"]) <= 0.5 * frame_ms + 1e-6)
    assert rep["max_abs_residual_frames"] <= 0.5 + 0.05
    assert np.all(np.diff(res.warp_src_times) >= 0)
    assert res.motion.fps == 60.0
    # the pose at each boundary is shown on its beat: the knee angle at the beat's frame
    # matches the source's angle at the boundary
    k = m.channel_index("knee_Xrotation")
    frames = np.rint(rep["target_beats_s"] * 60).astype(int)
    src = 40 * (1 - np.cos(2 * np.pi * bounds))
    assert np.allclose(res.motion.values[frames, k], src, atol=40 * 2 * np.pi / 60)


def test_output_length_follows_tempo():
    m = _periodic_motion(period=1.0, duration=8.0)
    bounds = np.arange(0.0, 8.0, 1.0)
    beats = np.arange(0.0, 20.0, 0.4)  # 1 s periods -> 2 beats of 0.4 s: rate 0.8
    res = synchronize(m, bounds, beats)
    assert res.report["beats_per_period"] == 2
    assert np.allclose(res.report["rate_range"], 0.8)
    expected = int(np.floor(0.8 * (m.n_frames - 1))) + 1
    assert abs(res.motion.n_frames - expected) <= 1


def test_music_shorter_than_dance_truncates_periods():
    m = _periodic_motion(period=1.0, duration=8.0)
    bounds = np.arange(0.0, 8.0, 1.0)
    beats = np.arange(0.0, 3.1, 0.5)  # 7 beats -> 3 periods of 2 beats
    res = synchronize(m, bounds, beats)
    assert res.report["periods_used"] == 3
    assert res.motion.n_frames == int(round(3.0 * FPS)) + 1


def test_first_beat_offset_holds_lead_in():
    m = _periodic_motion()
    bounds = np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.0, 12.0, 0.5)
    res = synchronize(m, bounds, beats, first_beat=4)  # boundary 0 on 2.0 s
    assert res.report["lead_in_hold_frames"] == int(2.0 * FPS)
    assert res.report["first_boundary_frame"] == int(2.0 * FPS)
    assert res.report["max_abs_residual_frames"] <= 0.5 + 1e-9
    assert np.allclose(res.motion.values[: int(2.0 * FPS)], m.values[0], atol=1e-6)


@pytest.mark.parametrize("n_frames", [750, 638, 417])
def test_every_boundary_within_half_a_frame_at_25_hz(n_frames):
    # the paper's clip sizes: the last boundary too must have a frame near its beat
    from beatsync.synth.motion import periodic_motion

    s = periodic_motion(n_frames=n_frames, fps=25.0, n_periods=n_frames // 25, seed=2)
    beats = 0.4 + np.arange(200) * 60 / 132
    rep = synchronize(s.motion, s.boundaries, beats).report
    assert rep["max_abs_residual_frames"] <= 0.5 + 0.01
    assert np.all(np.abs(rep["residual_ms"]) < 1.0)


def test_phase_offset_shifts_targets():
    m = _periodic_motion()
    bounds = np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.2, 12.0, 0.5)
    res = synchronize(m, bounds, beats, phase_offset=-0.1)
    assert np.allclose(res.report["target_beats_s"], beats[: 2 * 5 + 1 : 2] - 0.1)
    assert res.report["max_abs_residual_frames"] <= 0.5 + 1e-6
    with pytest.raises(ParameterError, match="phase_offset=-0.300"):
        synchronize(m, bounds, beats, phase_offset=-0.3)


def test_slerp_across_wrap():
    # a root yaw that crosses +-180 deg between frames: 178 -> -178 (i.e. 182)
    n = 8
    vals = np.zeros((n, 9))
    vals[:, 5] = np.where(np.arange(n) % 2 == 0, 178.0, -178.0)
    m = Motion(vals, FPS, _skeleton().channel_names(), _skeleton())
    bounds = np.array([0.0, 2 / FPS, 4 / FPS, 6 / FPS])
    res = synchronize(m, bounds, bounds, out_fps=2 * FPS, beats_per_period=1)
    mid = res.motion.values[1::2, 5][:3]  # half-way between 178 and -178
    assert np.allclose(np.abs(mid), 180.0, atol=1e-6)  # linear Euler would give 0


def test_bvh_round_trip(tmp_path):
    m = _periodic_motion()
    res = synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0.1, 9.0, 0.45))
    out = io.write_bvh(tmp_path / "out.bvh", res.motion)
    back = io.read_bvh(out)
    assert back.fps == res.motion.fps
    assert back.channels == res.motion.channels
    assert back.skeleton.same_structure(m.skeleton)
    assert np.array_equal(back.values, res.motion.values)


def test_warns_on_extreme_speed_change():
    m = _periodic_motion()
    with pytest.warns(BeatsyncWarning, match="speed"):
        synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0.0, 40, 2.5))


def test_no_warning_in_normal_case():
    m = _periodic_motion()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0.0, 12, 0.55))


@pytest.mark.parametrize(
    "bounds, beats, kwargs, match",
    [
        (np.array([1.0]), np.arange(0, 10, 0.5), {}, "periodic"),
        (np.array([]), np.arange(0, 10, 0.5), {}, "periodic"),
        (np.arange(0, 180, 30.0), np.arange(0, 10, 0.5), {}, "duration"),  # frames
        (np.array([2.0, 1.0, 3.0]), np.arange(0, 10, 0.5), {}, "increasing"),
        (np.arange(0.0, 5.5, 1.0), np.array([1.0]), {}, "beat"),
        (np.arange(0.0, 5.5, 1.0), np.array([]), {}, "beat"),
        (np.arange(0.0, 5.5, 1.0), np.array([0.0, 0.5]), {}, "too short"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"out_fps": 0}, "out_fps"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"first_beat": 99}, "first_beat"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"first_beat": -1}, "first_beat"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"beats_per_period": 0}, "beats"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"beats_per_period": "two"}, "beats"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"beats_per_period": 1.5}, "beats"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"first_beat": "x"}, "first_beat"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"phase_offset": "x"}, "phase"),
        # an offset of a beat or more (50 ms given as 50 s made a 1000 s dance for a 28 s song)
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"phase_offset": 50}, "one beat"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"phase_offset": 0.5}, "first_beat"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"delta": -1.0}, "delta"),
        (np.arange(0.0, 5.5, 1.0), np.array([0.0, np.nan, 1.0]), {}, "NaN"),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"mode": "bars"}, "mode="),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"land": "feet"}, "land="),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"fill": "repeat"}, "fill="),
        (np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), {"beats_per_bar": 0}, "beats_per_bar"),
        (
            np.arange(0.0, 5.5, 1.0),
            np.arange(0, 10, 0.5),
            {"dance_beats_per_period": 2.5},
            "dance_beats_per_period",
        ),
        (
            np.arange(0.0, 5.5, 1.0),
            np.arange(0, 10, 0.5),
            {"land": "accents", "phase_offset": 0.1},
            "accents.*phase_offset",
        ),
        (
            np.arange(0.0, 5.5, 1.0),
            np.arange(0, 10, 0.5),
            {"period_range": (1.0, 0.5)},
            "period_range",
        ),
    ],
)
def test_bad_inputs_raise(bounds, beats, kwargs, match):
    m = _periodic_motion()
    with pytest.raises(ParameterError, match=match):
        synchronize(m, bounds, beats, **kwargs)


def test_time_warp_bad_inputs():
    with pytest.raises(ParameterError, match=r"targets has shape \(2,\)"):
        time_warp([0.0, 1.0, 2.0], [0.0, 1.0])
    with pytest.raises(ParameterError, match="got 1"):
        time_warp([0.0], [0.0])


# ---------------------------------------------------------------- accents


def test_accent_lag():
    from beatsync.sync import accent_lag

    music = np.arange(0.5, 20.0, 0.5)
    assert np.isclose(accent_lag(music + 0.1, music), 0.1)
    assert np.isclose(accent_lag(music[1:] - 0.1, music), -0.1)
    with pytest.raises(ParameterError, match="no motion beat"):
        accent_lag([30.0], music)
    with pytest.raises(ParameterError, match="at least 2 music beats"):
        accent_lag([1.0], [0.5])


def _bounce(fps: float = 60.0, seconds: float = 12.0, period: float = 1.1) -> Motion:
    skel = Skeleton(
        (
            Joint("hip", -1, np.zeros(3), ("Xposition", "Yposition", "Zposition")),
            Joint("end", 0, np.array([0.0, 0.5, 0.0]), (), True),
        )
    )
    t = np.arange(int(seconds * fps)) / fps
    v = np.zeros((t.size, 3))
    v[:, 1] = np.cos(2 * np.pi * (t / period - 0.3))  # speed minima at phase 0.3 and 0.8
    return Motion(v, fps, skel.channel_names(), skel, "bounce")


def test_land_accents_puts_motion_beats_on_the_beats():

    m = _bounce()
    bounds = np.arange(0.0, 11.9, 1.1)
    beats = 0.5 + np.arange(40) * 0.5
    plain = synchronize(m, bounds, beats)
    acc = synchronize(m, bounds, beats, land="accents")
    assert acc.report["land"] == "accents" and plain.report["land"] == "boundaries"
    # boundaries on beats: the accents sit at phase 0.3 of a 2-beat period, off the beat
    d_plain = np.abs(np.subtract.outer(kinematic_beats(plain.motion), beats)).min(axis=1)
    d_acc = np.abs(np.subtract.outer(kinematic_beats(acc.motion), beats)).min(axis=1)
    assert np.median(d_plain) > 0.08
    assert np.median(d_acc) < 1.5 / 60
    assert acc.report["phase_offset_s"] == pytest.approx(-acc.report["accent_lag_s"])


def test_land_accents_needs_positions():
    m = _periodic_motion().select(["hip_Zrotation", "knee_Xrotation"])
    with pytest.raises(ParameterError, match="accents.*positions"):
        synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0, 10, 0.5), land="accents")


# ---------------------------------------------------------------- position-only motion


def _arm_positions(fps: float = 25.0, seconds: float = 12.0, beat_times=None) -> Motion:
    """A 3-joint arm (shoulder, elbow, wrist; bones 0.3 m) swinging, positions only.

    The elbow swings by +-60 deg and the forearm by a further +-60 deg; the speed has
    a minimum at every turn. ``beat_times``: the turns, else every 0.6 s.
    """
    t = np.arange(int(round(seconds * fps))) / fps
    turns = np.arange(0.3, seconds, 0.6) if beat_times is None else np.asarray(beat_times)
    # phase goes 0 -> 1 between successive turns: angles reverse at each turn
    k = np.clip(np.searchsorted(turns, t, side="right") - 1, 0, turns.size - 2)
    u = np.clip((t - turns[k]) / (turns[k + 1] - turns[k]), 0.0, 1.0)
    sign = np.where(k % 2 == 0, 1.0, -1.0)
    a1 = np.deg2rad(60.0) * sign * np.cos(np.pi * u)
    a2 = a1 * 2.0
    sh = np.stack([np.zeros_like(t), np.zeros_like(t), 1.4 + 0.02 * np.cos(np.pi * u)], axis=1)
    el = sh + 0.3 * np.stack([np.sin(a1), np.zeros_like(t), -np.cos(a1)], axis=1)
    wr = el + 0.3 * np.stack([np.sin(a2), np.zeros_like(t), -np.cos(a2)], axis=1)
    pos = np.stack([sh, el, wr], axis=1)
    names = tuple(f"{j}_{a}" for j in ("shoulder", "elbow", "wrist") for a in "xyz")
    return Motion(pos.reshape(t.size, -1), fps, names, None, "arm")


def test_restore_bone_lengths_after_linear_resampling():
    from beatsync.sync.positions import restore_bone_lengths

    m = _arm_positions(fps=10.0)  # fast turns per frame: linear blends cut the arc
    pos = m.values.reshape(m.n_frames, 3, 3)
    bones = np.array([[0, 1], [1, 2]])
    t = (np.arange(m.n_frames - 1) + 0.5) / m.fps  # half-way between source frames
    lin = 0.5 * (pos[:-1] + pos[1:])

    def worst(p):
        return np.abs(
            np.linalg.norm(p[:, bones[:, 1]] - p[:, bones[:, 0]], axis=-1) / 0.3 - 1
        ).max()

    assert worst(lin) > 0.01  # the naive resampling shortens the forearm by over 1 %
    fixed = restore_bone_lengths(lin, pos, bones, m.fps, t)
    assert worst(fixed) < 1e-9
    # directions are kept
    d_lin = lin[:, 2] - lin[:, 1]
    d_fix = fixed[:, 2] - fixed[:, 1]
    cos = (
        np.sum(d_lin * d_fix, axis=1)
        / np.linalg.norm(d_lin, axis=1)
        / np.linalg.norm(d_fix, axis=1)
    )
    assert np.all(cos > 1 - 1e-12)


# ---------------------------------------------------------------- meter


@pytest.mark.parametrize(
    "period, dance, bar, expected",
    [
        (2.1, 3, 3, 3),  # a 3-beat waltz step on a 3/4 song at 120 BPM: 4.2 beats -> 3, not 4
        (2.4, 3, None, 6),  # a 3-beat step, 4.8 beats -> 6 (a multiple of 3), never 5
        (2.4, None, 3, 6),  # a 3/4 song alone: divisors or multiples of the bar
        (2.4, None, None, 5),  # paper A's plain rule (no meter known)
        (1.0, 1, 4, 2),  # one motion beat per period constrains nothing
    ],
)
def test_beats_per_period_respects_meter(period, dance, bar, expected):
    beats = np.arange(0.0, 30.0, 0.5)
    got = beats_per_period(period, beats, dance_beats_per_period=dance, beats_per_bar=bar)
    assert got == expected


def _waltz_motion(step: float = 2.4, seconds: float = 14.4) -> Motion:
    """A position-only dance with 3 motion beats (turns) per step of ``step`` s."""
    turns = np.arange(0.0, seconds + step, step / 3)
    m = _arm_positions(fps=25.0, seconds=seconds, beat_times=turns)
    return m


def test_sync_waltz_step_on_3_4_keeps_the_step_whole():
    m = _waltz_motion()
    bounds = np.arange(0.0, 14.3, 2.4)
    beats = np.arange(0.2, 60.0, 0.5)  # 120 BPM: a step is 4.8 beats
    res = synchronize(m, bounds, beats, beats_per_bar=3, dance_beats_per_period=3)
    assert res.report["motion_beats_per_period_counted"] == 3  # the speed minima agree
    assert res.report["beats_per_period"] == 6 and res.report["meter_fit"] is True
    # the song's 3/4 alone: 4.8 beats -> 6, never 5
    assert synchronize(m, bounds, beats, beats_per_bar=3).report["beats_per_period"] == 6


def test_sync_waltz_step_on_4_4_says_the_meters_do_not_fit():
    m = _waltz_motion()
    bounds = np.arange(0.0, 14.3, 2.4)
    beats = np.arange(0.2, 60.0, 0.5)
    with pytest.warns(BeatsyncWarning, match="do not fit"):
        res = synchronize(m, bounds, beats, beats_per_bar=4, dance_beats_per_period=3)
    assert res.report["beats_per_period"] in (3, 6)  # the step stays whole, never 5 or 4
    assert res.report["meter_fit"] is False and "do not fit" in res.report["meter_note"]


# ---------------------------------------------------------------- fill


def test_fill_loop_covers_a_song_longer_than_the_clip():
    m = _periodic_motion(period=1.0, duration=6.0)
    bounds = np.arange(0.0, 5.5, 1.0)  # 5 periods
    beats = np.arange(0.3, 40.0, 0.55)  # 40 s song: 2 beats per period, 36 periods
    stop = synchronize(m, bounds, beats, fill="stop")
    loop = synchronize(m, bounds, beats, fill="loop")
    r = loop.report
    assert stop.report["repetitions"] == 1 and stop.report["output_duration_s"] < 8.0
    assert r["repetitions"] >= 7 and r["periods_used"] >= 35
    assert r["output_duration_s"] >= beats[-1] - 1.0 / FPS  # to the last beat
    assert r["max_abs_residual_frames"] <= 0.5 + 1e-6
    # blended joins: no jump bigger than the source's own largest frame-to-frame step
    src_step = np.abs(np.diff(m.values[:, 3:], axis=0)).max()
    out_step = np.abs(np.diff(loop.motion.values[:, 3:], axis=0)).max()
    assert out_step <= 1.5 * src_step


def test_fill_loop_carries_the_travel_across_joins():
    # the clip walks forward at 0.3 m/s: each pass goes on from where the last one
    # ended (it jumped 1.5 m back at every join, within the 0.2 s blend)
    m = _periodic_motion(period=1.0, duration=6.0)
    bounds = np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.3, 40.0, 0.5)  # 2 beats per period: the clip's own speed
    res = synchronize(m, bounds, beats, fill="loop")
    assert res.report["repetitions"] >= 7
    x = res.motion.values[:, 0]
    src_step = np.abs(np.diff(m.values[:, 0])).max()
    assert np.diff(x).min() > -1e-9  # never walks back (held still before the first beat)
    assert np.diff(x).max() <= 1.5 * src_step * res.report["continuous_rate_range"][1]
    # the height and the rotations are looped as they are
    assert np.abs(res.motion.values[:, 1] - 0.9).max() <= 0.02 + 1e-9


def test_fill_loop_of_a_table_says_its_passes_are_not_moved():
    # without a skeleton no channel is known to be the root's: the passes are looped as
    # they are, and a root position among the channels jumps back at every join
    m = _periodic_motion(period=1.0, duration=6.0)
    table = Motion(m.values, m.fps, m.channels, None, "table")
    bounds, beats = np.arange(0.0, 5.5, 1.0), np.arange(0.3, 20.0, 0.5)
    with pytest.warns(BeatsyncWarning, match=r"table without a skeleton is looped as it is"):
        res = synchronize(table, bounds, beats, fill="loop")
    assert res.report["repetitions"] >= 3 and np.diff(res.motion.values[:, 0]).min() < -0.05
    with warnings.catch_warnings():
        warnings.simplefilter("error", BeatsyncWarning)  # with its skeleton: carried on
        synchronize(m, bounds, beats, fill="loop")


def test_fill_loop_carries_the_travel_of_position_only_motion():
    arm = _arm_positions(fps=25.0, seconds=12.0)  # swings with turns every 0.6 s
    pos = arm.values.reshape(arm.n_frames, 3, 3).copy()
    pos[:, :, 1] += 0.4 * arm.times[:, None]  # the whole arm moves along y (z is up)
    m = arm.with_values(pos.reshape(arm.n_frames, -1))
    bounds = np.arange(0.3, 11.0, 1.2)  # one period: two swings
    beats = np.arange(0.3, 60.0, 0.6)
    res = synchronize(m, bounds, beats, fill="loop")
    assert res.report["repetitions"] >= 5
    out = res.motion.values.reshape(res.motion.n_frames, 3, 3)
    y = out[:, :, 1].mean(axis=1)
    assert np.diff(y).min() > -1e-9  # the centroid never jumps back
    src_step = np.abs(np.diff(pos[:, :, 1].mean(axis=1))).max()
    assert np.diff(y).max() <= 1.5 * src_step * res.report["continuous_rate_range"][1]
    assert np.allclose(out[:, :, 0].mean(axis=1).max(), pos[:, :, 0].mean(axis=1).max(), atol=0.05)


@pytest.mark.parametrize("clip", ["007_01", "007_12"])
def test_fill_loop_of_a_real_walk_too_short_for_its_blend_window_walks_on(clip):
    # two CMU walks of two steps, with no loop that has half a blend window of clip on
    # both sides: each pass must still start where the previous one ended (007_01 slid
    # 2 m back at every join), and the shrunk blend must stay inside the clip (007_12's
    # first frame is a T-pose: its joins peaked at 8875 against the walk's own 710)
    walk = datasets.load_walk(clip)
    res = synchronize(walk, None, np.arange(0.3, 20.0, 0.6), mode="periods", fill="loop")
    r = res.report
    assert r["repetitions"] >= 5
    play = r["playback_speed"]["instantaneous"]["max"]
    pos = walk.positions()[1:]  # after the T-pose
    own = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max() * walk.fps
    assert max(j["peak_joint_speed"] for j in r["joins"]) <= 1.05 * own * play
    root, src = res.motion.values[:, [0, 2]], walk.values[1:, [0, 2]]  # on the floor (y up)
    step = np.linalg.norm(np.diff(root, axis=0), axis=1) * res.motion.fps
    step = step[res.motion.times[1:] > 1.0]  # the clip's own start (T-pose) played once
    own_step = np.linalg.norm(np.diff(src, axis=0), axis=1) * walk.fps
    assert step.max() <= 1.05 * own_step.max() * play
    assert np.linalg.norm(root[-1] - root[0]) > 5.0 * np.linalg.norm(src[-1] - src[0])


@pytest.mark.parametrize("mode", ["periods", "beats"])
def test_a_reference_pose_the_walk_opens_on_is_not_the_dancers_peak(mode):
    # 007_12's first frame is a T-pose that snaps into the walk at 17 000 units/s, the
    # walk's own steps peak at 710: the report compares the output with the walk
    walk = datasets.load_walk("007_12")
    beats = np.arange(0.3, 20.0, 0.712)
    kin = synchronize(walk, None, beats, mode=mode, fill="loop", song_end=20.3).report["kinematics"]
    assert kin["input"]["peak_joint_speed"] < 1.2 * kin["input"]["p99_joint_speed"]


def test_peak_headroom_leaves_out_the_reference_pose():
    # the fastest playback of each interval that keeps the joints within the walk's own
    # peak: against the T-pose's snap, every interval could play 20 times faster
    from beatsync.motion_beats import kinematic_beats
    from beatsync.sync.core import _opening_snap
    from beatsync.sync.placement import peak_headroom

    walk = datasets.load_walk("007_12")
    events = kinematic_beats(walk)
    skip = _opening_snap(walk.positions())
    assert skip >= 1
    assert peak_headroom(walk, events).min() > 10.0
    room = peak_headroom(walk, events, skip=skip)
    assert 1.0 <= room.min() and room.max() < 2.0


def test_a_walk_on_a_real_song_does_not_race_between_its_landings():
    # CMU walk 005_02 in beats mode on the cha-cha dancer's song (125 BPM, tracked): one-beat
    # intervals between two-beat ones. Held at the slow neighbours' rate at both ends, one
    # raced to x1.58 in its middle, its joints to x1.34 the walk's own peak
    from beatsync.beats import track_beats

    y, sr = io.read_audio(datasets.path("motion/dance_with_melody/DANCE_C_4/audio.ogg"))
    beats = np.asarray(track_beats(y, sr).beats)
    walk = datasets.load_walk("005_02")
    r = synchronize(walk, None, beats, mode="beats", fill="loop", song_end=y.size / sr).report
    assert r["playback_speed"]["instantaneous"]["max"] < 1.45
    assert r["kinematics"]["ratio"]["peak_joint_speed"] < 1.25


@pytest.mark.parametrize("mode", ["periods", "beats"])
def test_loop_reports_the_passes_it_plays(mode):
    # the looped timeline is built with room to spare; the report counts what is played
    walk = datasets.load_walk("007_01")
    beats = np.arange(0.3, 20.0, 0.6)
    rep = synchronize(walk, None, beats, mode=mode, fill="loop", song_end=20.3).report
    assert rep["repetitions"] == len(rep["joins"]) + 1 >= 5


def test_fill_loop_of_a_clip_longer_than_the_song_is_stop_to_the_last_beat():
    m = _periodic_motion(period=1.0, duration=6.0)
    bounds = np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.3, 3.0, 0.55)  # 5 beats: 2 periods and a half
    res = synchronize(m, bounds, beats, fill="loop")
    assert res.report["repetitions"] == 1 and res.report["periods_used"] == 2
    assert res.report["output_duration_s"] >= beats[-1] - 1.0 / FPS


@pytest.mark.parametrize("mode", ["periods", "beats"])
def test_fill_loop_dances_on_to_the_songs_end(mode):
    # the song plays 1.6 s after its last beat: the dancer goes on at the final speed
    # instead of standing still (the video holds the last frame)
    m = _periodic_motion(period=1.0, duration=6.0)
    bounds = None if mode == "beats" else np.arange(0.0, 5.5, 1.0)
    beats = np.arange(0.3, 20.0, 0.5)  # last beat 19.8 s
    if mode == "beats":
        m = _arm_positions(fps=FPS, seconds=6.0)
    res = synchronize(m, bounds, beats, mode=mode, fill="loop", song_end=21.4)
    r = res.report
    assert r["output_duration_s"] >= 21.4 - 1e-9 and r["covered_s"][1] == pytest.approx(21.4)
    tail = res.warp_src_times[res.motion.times > beats[-1] + 0.1]
    assert np.diff(tail).min() > 0  # moving, not held
    stop = synchronize(m, bounds, beats, mode=mode, fill="loop")
    assert stop.report["covered_s"][1] == pytest.approx(beats[-1])
    # landed after their beats, the motion beats still end with the song, not after it
    late = synchronize(m, bounds, beats, mode=mode, fill="loop", song_end=21.4, phase_offset=0.1)
    assert late.report["output_duration_s"] <= 21.4 + 1.0 / FPS + 1e-9


def test_song_end_before_the_last_beat_or_in_milliseconds_is_refused():
    m = _periodic_motion(period=1.0, duration=6.0)
    with pytest.raises(ParameterError, match=r"song_end=9 s is before the music's last beat"):
        synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0.3, 20.0, 0.5), song_end=9)
    with pytest.raises(ParameterError, match=r"song_end=21400 s .*milliseconds given"):
        synchronize(m, np.arange(0.0, 5.5, 1.0), np.arange(0.3, 20.0, 0.5), song_end=21400)


def test_beats_mode_dances_through_a_long_outro():
    # 40 s of song after its last beat (a beatless outro): the loop reaches it too
    m = _arm_positions(fps=FPS, seconds=6.0)
    beats = np.arange(0.3, 20.0, 0.5)
    res = synchronize(m, None, beats, mode="beats", fill="loop", song_end=60.0)
    assert res.report["covered_s"][1] == pytest.approx(60.0)


# ---------------------------------------------------------------- modes


def test_mode_beats_lands_the_dancers_own_beats():

    rng = np.random.default_rng(3)
    turns = np.cumsum(rng.uniform(0.45, 0.8, 30))  # an irregular dance: no period
    m = _arm_positions(fps=25.0, seconds=15.0, beat_times=np.r_[0.0, turns])
    beats = np.arange(0.5, 30.0, 0.5)
    res = synchronize(m, None, beats, mode="beats")
    r = res.report
    assert r["mode"] == "beats" and r["beats_per_period"] >= 1
    assert r["max_abs_residual_frames"] <= 0.5 + 1e-6
    mb = kinematic_beats(res.motion)
    inside = mb[(mb > beats[0]) & (mb < r["covered_s"][1] - 0.5)]
    # intervals of 0.45-0.8 s on 0.5 s beats: within the speed band some land on half beats
    grid = np.sort(np.r_[beats, (beats[1:] + beats[:-1]) / 2])
    d = np.abs(np.subtract.outer(inside, grid)).min(axis=1)
    assert np.median(d) <= 1.0 / 25 + 1e-9  # the dancer's beats now sit on the music's
    assert r["playback_speed"]["per_interval"]["in_band"] == 1.0


@pytest.fixture(scope="module")
def waltz_dancer() -> Motion:
    """12 s of a real waltz dancer (Dance-with-Melody, joint positions, 25 fps)."""
    return datasets.load_dance_pair("DANCE_W_5").motion.slice_frames(0, 300)


def test_mode_auto_falls_back_to_beats_and_says_so(waltz_dancer):
    # paper A's period range (0.25-1.25 s) holds no cycle of this waltz: not periodic
    beats = np.arange(0.5, 30.0, 0.5)
    with pytest.warns(BeatsyncWarning, match="fell back"):
        res = synchronize(
            waltz_dancer, None, beats, mode="auto", fill="loop", period_range=(0.25, 1.25)
        )
    r = res.report
    assert r["mode"] == "beats" and "refused" in r["mode_note"]
    assert r["output_duration_s"] >= beats[-1] - 1.0 / 25 and r["repetitions"] >= 2
    assert r["max_abs_residual_frames"] <= 0.5 + 1e-6


def test_mode_periods_refuses_a_motion_that_is_not_periodic(waltz_dancer):
    with pytest.raises(ParameterError, match="not look periodic.*mode='beats'"):
        synchronize(
            waltz_dancer, None, np.arange(0.5, 30.0, 0.5), mode="periods", period_range=(0.25, 1.25)
        )


def test_mode_periods_does_not_suggest_motion_beats_for_a_dancer_standing_still(waltz_dancer):
    # no motion at all is not a free dance: motion beats would not sync it either
    still = waltz_dancer.with_values(np.repeat(waltz_dancer.values[:1], 300, axis=0))
    for mode in ("periods", "auto"):
        with pytest.raises(ParameterError, match="over the 300 frames") as err:
            synchronize(still, None, np.arange(0.5, 30.0, 0.5), mode=mode)
        assert "mode='beats'" not in str(err.value)


def test_mode_auto_falls_back_for_a_dancer_whose_joint_angles_never_change(waltz_dancer):
    # the whole body sways, rigid: no angle to segment, but motion beats to sync
    t = np.arange(300) / 25.0
    sway = np.zeros((300, 69))
    sway[:, 0::3] = 0.2 * np.sin(2 * np.pi * 1.4 * t)[:, None]  # every joint's x
    rigid = waltz_dancer.with_values(np.repeat(waltz_dancer.values[:1], 300, axis=0) + sway)
    with pytest.warns(BeatsyncWarning, match="fell back"):
        res = synchronize(rigid, None, np.arange(0.5, 30.0, 0.5), mode="auto", fill="loop")
    assert res.report["mode"] == "beats" and "its joints move" in res.report["mode_note"]


@pytest.mark.parametrize("mode", ["periods", "beats"])
def test_real_dancer_positions_both_modes_keep_bones(waltz_dancer, mode):
    # the period range from the song (one to eight beats) holds the waltz's cycle
    beats = np.arange(0.3, 40.0, 60 / 84)  # 84 BPM, 40 s: longer than the clip
    res = synchronize(waltz_dancer, None, beats, mode=mode, fill="loop", beats_per_bar=3)
    r = res.report
    assert r["mode"] == mode and r["max_abs_residual_frames"] <= 0.5 + 1e-6
    assert r["output_duration_s"] >= beats[-1] - 1.0 / 25
    assert res.motion.is_positional
    if mode == "periods":  # a waltz bar (about 2 s) on the 3/4 song: 3 beats
        assert r["meter_fit"] is True and r["beats_per_period"] == 3
    bones = waltz_dancer.bones

    def lengths(m):
        p = m.positions()
        return np.linalg.norm(p[:, bones[:, 0]] - p[:, bones[:, 1]], axis=-1)

    src, out = lengths(waltz_dancer), lengths(res.motion)
    # each output frame's bones: within 1 % of the source's lengths near the frames shown
    assert np.all(out >= 0.99 * src.min(axis=0)) and np.all(out <= 1.01 * src.max(axis=0))
    # frame by frame (no loop): each bone as long as in the source at the time shown
    stop = synchronize(waltz_dancer, None, beats, mode=mode, fill="stop", beats_per_bar=3)
    f = np.clip(stop.warp_src_times * waltz_dancer.fps, 0, waltz_dancer.n_frames - 1)
    i0 = np.floor(f).astype(int)
    i1 = np.minimum(i0 + 1, waltz_dancer.n_frames - 1)
    u = (f - i0)[:, None]
    expected = src[i0] * (1 - u) + src[i1] * u
    assert np.abs(lengths(stop.motion) / expected - 1).max() <= 0.01


def test_mode_beats_needs_positions():
    m = _periodic_motion().select(["hip_Zrotation", "knee_Xrotation"])
    with pytest.raises(ParameterError, match="mode='beats' needs joint positions"):
        synchronize(m, None, np.arange(0, 10, 0.5), mode="beats")


def test_periodicity_refusal_in_sync_advises_only_what_sync_offers():
    # it said "Try other channels", and neither sync nor batch has a --channels option
    from beatsync.errors import NotPeriodicError
    from beatsync.motion import segmentation_view
    from beatsync.segment import segment
    from beatsync.sync.core import motion_periods

    walk = datasets.load_walk("005_02")  # a walk with a turn: not periodic
    with pytest.raises(NotPeriodicError) as segmenting:
        segment(segmentation_view(walk), period_range=(0.25, 1.25))
    assert "Try other channels" in str(segmenting.value)  # segment has channels=
    with pytest.raises(NotPeriodicError) as syncing:
        motion_periods(walk, period_range=(0.25, 1.25))
    text = str(syncing.value)
    assert "channels" not in text
    assert "Try another period_range (--period-range), or a clip with repeated movement" in text
    assert text.startswith("the motion is not periodic: the best segmentation into")


# ---------------------------------------------- a real dancer moves like the dancer


def _joint_speed(pos: np.ndarray, fps: float) -> np.ndarray:
    """Speed of every joint between consecutive frames [m/s], shape (frames - 1, joints)."""
    return np.linalg.norm(np.diff(pos, axis=0), axis=-1) * fps


@pytest.fixture(scope="module")
def rumba_on_a_waltz():
    """The real rumba dancer (24 s) re-synchronised to 40 s of a waltz's tempo (84 BPM):
    looped, at a tempo where one beat per motion beat plays the dance at x1.4-x2."""
    dancer = datasets.load_dance_pair("DANCE_R_3").motion
    beats = np.arange(0.3, 40.0, 60.0 / 84.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        res = synchronize(dancer, None, beats, mode="beats", fill="loop", beats_per_bar=3)
    return dancer, beats, res


def test_real_dancer_plays_within_the_speed_band(rumba_on_a_waltz):
    _, _, res = rumba_on_a_waltz
    fps = res.motion.fps
    t = np.arange(res.warp_src_times.size) / fps
    live = (t[1:] > res.warp.tgt[0]) & (t[1:] <= res.warp.tgt[-1])
    speed = np.diff(res.warp_src_times)[live] * fps  # source seconds per output second
    assert np.mean((speed >= 0.8) & (speed <= 1.25)) >= 0.95
    # every motion beat placed lands on a beat or half beat, within half an output frame
    assert res.report["max_abs_residual_frames"] <= 0.5 + 1e-6


def test_real_dancer_shows_its_landed_motion_beats_on_the_beat(rumba_on_a_waltz):
    # the playback speed is held around every landing, so the speed minimum there is
    # found again in the output within one output frame (86 % of them without the hold)
    from beatsync.evaluate.alignment import nearest_distance

    _, _, res = rumba_on_a_waltz
    landed = np.asarray(res.report["target_beats_s"])[1:-1]  # the ends: no minimum
    d = nearest_distance(landed, kinematic_beats(res.motion))
    assert np.mean(d <= 1.0 / res.motion.fps + 1e-9) >= 0.95


def test_real_dancer_loop_join_is_seamless(rumba_on_a_waltz):
    dancer, beats, res = rumba_on_a_waltz
    r = res.report
    assert r["output_duration_s"] >= beats[-1] - 1.0 / 25 and r["joins"]
    assert r["loop"]["blend_s"] >= 0.5
    own = _joint_speed(dancer.positions(), dancer.fps)
    out = _joint_speed(res.motion.positions(), res.motion.fps)
    assert out.max() <= 1.10 * own.max()  # joins included
    fps = res.motion.fps
    for join in r["joins"]:
        f = int(round(join["time_s"] * fps))
        near = out[max(0, f - int(fps)) : f + int(fps)]  # one second either side
        assert near.max() <= own.max()  # no faster than the dancer's own peak
        assert join["peak_joint_speed"] == pytest.approx(
            out[max(0, f - 10) : f + 10].max(), rel=0.5
        )


def test_instantaneous_speed_leaves_out_the_step_out_of_a_held_start():
    # the first pose waits for a beat 0.01 s after a frame: the step across it is
    # mostly held, not a slow playback
    m = _periodic_motion(period=1.0, duration=6.0)
    beats = np.arange(1.01, 12.0, 0.5)  # 2 beats per 1 s period: the clip's own speed
    sp = synchronize(m, np.arange(0.0, 5.5, 1.0), beats, fill="stop").report["playback_speed"]
    assert sp["held_lead_in_s"] > 0.9
    assert sp["instantaneous"]["min"] >= 0.9 * sp["per_interval"]["min"]


@pytest.mark.parametrize("out_fps", [12.5, 50.0])
def test_kinematics_compare_input_and_output_at_one_frame_rate(waltz_dancer, out_fps):
    # the dancer played at its own timing: at another frame rate its joints move as before
    own = kinematic_beats(waltz_dancer)
    rep = synchronize(waltz_dancer, own, own, mode="periods", fill="stop", out_fps=out_fps).report
    ratio = rep["kinematics"]["ratio"]
    assert ratio["p99_joint_accel"] == pytest.approx(1.0, abs=0.05)
    assert ratio["p99_joint_speed"] == pytest.approx(1.0, abs=0.05)


def test_report_tells_the_counts_speeds_and_kinematics_used(rumba_on_a_waltz):
    dancer, _, res = rumba_on_a_waltz
    r = res.report
    used = r["beats_per_motion_beat_used"]
    assert sum(used.values()) == r["periods_used"] == len(r["boundaries_s"]) - 1
    counts = np.diff(r["target_beats_s"]) / (60.0 / 84.0)
    np.testing.assert_allclose(
        sorted(float(k) for k, n in used.items() for _ in range(n)), np.sort(counts), atol=0.01
    )
    sp = r["playback_speed"]
    fps = res.motion.fps
    per = np.diff(r["boundaries_s"]) / np.diff(r["target_beats_s"])
    assert sp["per_interval"]["min"] == pytest.approx(per.min())
    assert sp["per_interval"]["max"] == pytest.approx(per.max())
    inst = np.diff(res.warp_src_times) * fps
    assert inst.max() == pytest.approx(sp["instantaneous"]["max"], rel=1e-6)
    k = r["kinematics"]
    own = _joint_speed(dancer.positions(), dancer.fps)
    assert k["input"]["peak_joint_speed"] == pytest.approx(own.max())
    assert k["input"]["p99_joint_speed"] == pytest.approx(np.percentile(own, 99))
    out = _joint_speed(res.motion.positions(), fps)
    assert k["ratio"]["p99_joint_speed"] == pytest.approx(
        np.percentile(out, 99) / k["input"]["p99_joint_speed"]
    )
    # the landings the output shows, by the scorer's own detector
    seen, targets = r["landings_seen"], np.asarray(r["target_beats_s"])
    mb = kinematic_beats(res.motion)
    near = mb[np.abs(mb[None, :] - targets[:, None]).argmin(axis=1)]
    on_frame = np.isclose(near, np.rint(targets * fps) / fps)
    assert seen["landings"] == targets.size and seen["on_their_frame"] == on_frame.sum() > 0
    assert seen["not_found"] == np.sum(np.abs(near - targets) > 0.1)
    assert seen["max_ms"] <= 100.0


def test_join_weight_is_flat_at_the_join():
    from beatsync.sync.fill import join_weight

    u = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(join_weight(u), [0.0, 0.25, 0.5, 0.75, 1.0])
    h = 1e-6  # no slope at both ends of the window and at the join (u = 1/2)
    slope = (join_weight(u[[0, 2, 4]] + h) - join_weight(u[[0, 2, 4]] - h)) / (2 * h)
    np.testing.assert_allclose(slope, 0.0, atol=1e-5)


def test_real_dancer_loop_join_keeps_its_motion_beat():
    # the real waltz dancer looped onto 40 s of 87 BPM: each join is one of its motion
    # beats (a speed minimum); the blend must not move it away from the join

    dancer = datasets.load_dance_pair("DANCE_W_5").motion
    beats = np.arange(0.3, 40.0, 60.0 / 87.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        res = synchronize(dancer, None, beats, mode="beats", fill="loop", beats_per_bar=3)
    seen = kinematic_beats(res.motion)
    joins = np.array([j["time_s"] for j in res.report["joins"]])
    assert joins.size
    assert np.abs(seen[:, None] - joins[None, :]).min(axis=0).max() <= 0.06


def test_speed_warning_names_a_tempo_that_fits():
    # 10 motion beats 0.5 s apart and a song of 2 beats 3 s apart: no count fits
    m = _arm_positions(fps=25.0, seconds=6.0, beat_times=np.arange(0.0, 6.0, 0.5))
    with pytest.warns(BeatsyncWarning, match=r"within x0.8-x1.25 .* only \d+% .* about \d+ BPM"):
        res = synchronize(m, None, np.array([0.5, 3.5, 6.5]), mode="beats")
    assert res.report["speed_warning"]


def test_dance_meter_puts_the_dance_bars_on_bar_lines():
    # the real waltz dancer, told its meter (3 motion beats a bar), on a 3/4 song
    dancer = datasets.load_dance_pair("DANCE_W_10").motion
    beats = np.arange(0.3, 40.0, 60.0 / 87.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        res = synchronize(dancer, None, beats, mode="beats", fill="loop", beats_per_bar=3,
                          dance_beats_per_period=3)  # fmt: skip
    r = res.report
    assert r["phrases_on_bars"] >= 0.9
    assert r["playback_speed"]["instantaneous"]["in_band"] >= 0.95
    bar = 3 * 60.0 / 87.0
    on_bar = np.abs(((np.asarray(r["target_beats_s"]) - beats[0]) / bar + 0.5) % 1.0 - 0.5) < 1e-6
    assert on_bar.mean() > 1.0 / 3.0 + 0.1  # more than the share of beats that are bar lines


def test_dance_meter_is_estimated_when_clear_and_the_users_wins():
    # standing in place, the knee bends and straightens once a period of 1.8 s: two
    # motion beats (the turns of the knee) per period, on a 4/4 song of 0.45 s beats
    m = _periodic_motion(period=1.8, duration=20.0, fps=25.0)
    values = m.values.copy()
    values[:, 0] = 0.0
    m = m.with_values(values)
    beats = np.arange(0.3, 30.0, 0.45)
    r = synchronize(m, None, beats, mode="beats", fill="loop", beats_per_bar=4).report
    assert r["dance_meter_rule"] == "estimated" and r["dance_beats_per_period"] == 2
    assert r["dance_meter_found"]["period_s"] == pytest.approx(1.8, rel=0.05)
    # a phrase start every 4 beats would be on a bar line by chance half the time
    assert r["phrases_on_bars"] >= 0.8
    given = synchronize(m, None, beats, mode="beats", beats_per_bar=4, dance_beats_per_period=4)
    assert given.report["dance_meter_rule"] == "given"
    assert given.report["dance_beats_per_period"] == 4


def test_dance_meter_without_a_period_in_range_is_none():
    # the arm turns every 0.6 s and its bone angles repeat at every turn: no phrase of
    # 1.5-8.5 motion beats to find
    from beatsync.sync.core import estimate_dance_meter

    m = _arm_positions(seconds=12.0)
    assert estimate_dance_meter(m, kinematic_beats(m))[0] is None
    r = synchronize(m, None, np.arange(0.3, 14.0, 0.6), mode="beats").report
    assert r["dance_meter_rule"] is None and r["dance_beats_per_period"] is None


def test_dance_meter_of_a_real_waltz_is_not_clear():
    # the waltz dancer's period is its bar (3 beats of its song, 2.14 s), but its speed
    # minima mark 1 to 3 of the bar's steps: no count of motion beats holds every bar
    from beatsync.sync.core import estimate_dance_meter

    dancer = datasets.load_dance_pair("DANCE_W_5").motion
    count, found = estimate_dance_meter(dancer, kinematic_beats(dancer))
    assert count is None and found["period_s"] == pytest.approx(3 * 0.712, rel=0.05)


def test_loop_of_a_turning_skeleton_carries_its_heading_on():
    # the real salsa step (BVH) danced while turning 120 deg over the clip: each pass of
    # the loop starts facing where the previous one ended, without a turn back at a join
    from scipy.spatial.transform import Rotation

    from beatsync.motion_beats import motion_positions
    from beatsync.rotations import euler_to_rotation, rotation_to_euler

    real = datasets.load_salsa("60_01")
    step = real.values[60:120].copy()
    step[:, :3] = step[0, :3]
    values = np.tile(step, (5, 1))
    yaw = np.linspace(0.0, np.deg2rad(120.0), values.shape[0])
    root = real.skeleton.joints[0].name
    idx, order = next((list(i), o) for j, i, o in real.rotation_triples() if j == root)
    turned = Rotation.from_euler("y", yaw[:, None]) * euler_to_rotation(values[:, idx], order)
    values[:, idx] = rotation_to_euler(turned, order, reference=values[:, idx])
    dancer = real.with_values(values)
    beats = np.arange(0.3, 16.0, 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        res = synchronize(dancer, None, beats, mode="beats", fill="loop")
    r = res.report
    assert r["joins"] and abs(r["loop"]["turn_deg"]) > 30.0
    pos = motion_positions(res.motion)
    names = [j.name for j in dancer.skeleton.joints]
    hips = pos[:, names.index("lButtock")] - pos[:, names.index("rButtock")]
    heading = np.degrees(np.unwrap(np.arctan2(hips[:, 0], hips[:, 2])))
    assert np.abs(np.diff(heading)).max() < 10.0  # no turn back at a join (a reset: 48 deg)
    # the heading goes on turning: about 24 deg per second, as in the clip
    assert abs(heading[-1] - heading[0]) > 0.8 * 24.0 * res.motion.duration
    own = np.linalg.norm(np.diff(motion_positions(dancer), axis=0), axis=-1).max()
    assert np.linalg.norm(np.diff(pos, axis=0), axis=-1).max() <= 1.10 * own


def test_mode_periods_searches_the_range_segment_bpm_searches():
    # both said "one to eight beats"; sync searched 0.9-8.5 beats and segment --bpm 1-8,
    # and on the real salsa at 99.6 BPM they found periods of 1.00 s and 2.94 s
    from beatsync.segment import period_range_from_beat

    m = _periodic_motion(period=1.0, duration=12.0)
    rep = synchronize(m, None, np.arange(0.3, 12.0, 0.5), mode="periods").report
    assert rep["period_range_s"] == pytest.approx(period_range_from_beat(0.5))
    assert rep["mean_motion_period_s"] == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize("clip, opening", [("walk", 1), ("salsa", 3)])
def test_output_never_opens_on_the_clips_reference_pose(clip, opening):
    # CMU's BVH files open on a T-pose that snaps to the first pose in 1-3 frames (joints
    # at 10-30 m/s); a lead-in that reached back to the first frame showed it, then the snap
    if clip == "walk":
        m, mode, beats = datasets.load_walk("007_12"), "periods", np.arange(0.4, 20.0, 0.6)
    else:  # a real song's beats
        m, mode = datasets.load_salsa("60_01"), "auto"
        beats = io.read_beats(datasets.path("audio/real_dev/hainsworth_001.beats"))
    res = synchronize(m, None, beats[beats < 20.0], mode=mode, fill="loop")
    own = np.linalg.norm(np.diff(m.positions(), axis=0), axis=-1).max(axis=1)
    assert np.all(own[:opening] > own[opening:].max())  # the snap, faster than the dance
    out = np.linalg.norm(np.diff(res.motion.positions(), axis=0), axis=-1).max(axis=1)
    assert out.max() * res.motion.fps < own[:opening].min() * m.fps  # no snap shown
