"""Tests of beatsync.sync.landing: the motion beats a viewer sees land on the beats."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from beatsync.errors import BeatsyncWarning
from beatsync.sync import synchronize
from beatsync.sync.landing import _within, dip_floor, release_floor
from beatsync.sync.warp import integrate_warp


def test_dip_floor_keeps_half_of_each_dips_log_depth():
    # a speed of 1 at the landings, peaks of 1.21 and 4 amid the two intervals: the
    # held rate may not fall below m / sqrt(P) on either side, m the interval's rate
    def speed_at(t):
        t = np.asarray(t, dtype=np.float64)
        bump = np.where(t < 1.0, 0.21, 3.0) * np.sin(np.pi * t) ** 2
        return 1.0 + bump

    used = np.array([0.0, 1.0, 2.0])
    targets = np.array([0.0, 0.8, 2.0])  # rates 0.8 and 1.2
    floor = dip_floor(speed_at, used, targets)
    np.testing.assert_allclose(floor, [0.8 / 1.1, max(0.8 / 1.1, 1.2 / 2.0), 1.2 / 2.0], rtol=1e-3)


def test_integrate_warp_holds_at_least_the_floor_at_every_boundary():
    s = np.array([0.0, 1.0, 1.5, 2.5])
    b = np.array([0.0, 1.2, 1.6, 2.5])
    floor = np.array([0.0, 1.5, 0.0, 0.0])
    w = integrate_warp(s, b, hold=0.1, floor=floor)
    at = np.searchsorted(w.src, s[1])
    assert w.rate[at] >= 1.5 - 1e-9
    assert abs(w.rate[at] - 1.5) < 1e-6  # the blend alone holds less than that there
    np.testing.assert_allclose(w.to_target(s), b, atol=1e-9)  # still lands every beat


def test_integrate_warp_holds_where_the_two_periods_meet():
    # a short fast period between two slow ones: held at the geometric mean of the two
    # rates at each of its ends (eq. 9's blend, reaching the further period, held 0.995, and
    # the period's middle played at x1.49 for a mean of x1.18; now x1.42)
    s = np.array([0.0, 1.0, 1.5, 2.5])
    rates = np.array([1.1, 0.85, 1.1])
    b = np.concatenate([[0.0], np.cumsum(np.diff(s) * rates)])
    w = integrate_warp(s, b, hold=0.1)
    for x in s[1:3]:
        assert w.rate[np.searchsorted(w.src, x)] == pytest.approx(np.sqrt(1.1 * 0.85))
    inside = (w.src > s[1]) & (w.src < s[2])
    assert 1.0 / w.rate[inside].min() < 1.45
    np.testing.assert_allclose(w.to_target(s), b, atol=1e-9)


def test_release_floor_gives_the_band_priority_over_a_dips_depth():
    # a short fast interval (x1.18) between two slow ones (x0.91), its ends held at the
    # slow rate: it races to x1.82 in its middle; released to its own rate there, it
    # plays as without a floor (x1.42, the held geometric mean's own bump)
    s = np.array([0.0, 1.0, 1.5, 2.5])
    b = np.array([0.0, 1.1, 1.525, 2.625])
    floor = np.array([0.0, 1.1, 1.1, 0.0])
    w = integrate_warp(s, b, hold=0.1, floor=floor)
    lower = release_floor(w, s, b, floor, np.full(3, 1.25))
    np.testing.assert_allclose(lower, [0.0, 0.85, 0.85, 0.0])

    def fastest(warp):
        return 1.0 / warp.rate[(warp.src > s[1]) & (warp.src < s[2])].min()

    released = integrate_warp(s, b, hold=0.1, floor=lower)
    assert fastest(w) > 1.8
    assert fastest(released) == pytest.approx(fastest(integrate_warp(s, b, hold=0.1)))
    assert fastest(released) < 1.45
    assert release_floor(w, s, b, floor, np.full(3, 2.0)) is None  # nothing races


def test_seen_landings_of_a_window_aim_at_the_whole_outputs_frames():
    # a window of the output from an odd frame on: a beat exactly half-way between two
    # frames is aimed at the frame the whole output aims at (np.rint rounds half frames
    # to the even one; shifting the times by an odd number of frames moved them)
    from beatsync.sync.quality import seen_landings

    fps = 25.0
    t = np.arange(200) / fps
    speed = 1.5 + np.cos(2 * np.pi * (t - 2.02) / 1.6)  # minima at 2.82 s and 4.42 s
    pos = np.zeros((t.size, 2, 3))
    pos[:, :, 0] = np.cumsum(speed)[:, None] / fps
    targets = np.array([2.82, 4.42])  # half-way between frames 70 and 71, 110 and 111
    whole, _ = seen_landings(pos, fps, targets)
    first = 31  # odd
    part, _ = seen_landings(pos[first:], fps, targets, first)
    np.testing.assert_allclose(part, whole, atol=1e-9)
    shifted, _ = seen_landings(pos[first:], fps, targets - first / fps)
    assert not np.allclose(shifted, whole, atol=1e-9)  # the times shifted instead


def test_within_shortens_a_move_that_leaves_the_band():
    targets = np.array([0.0, 1.0, 2.0])
    kept = np.array([0.0, 1.0, 2.0])
    moved = np.array([0.0, 1.3, 2.0])  # speeds 1.3 and 0.7
    lo, hi = np.full(2, 0.85), np.full(2, 1.18)
    pins = _within(moved, kept, kept, targets, lo, hi)
    speed = np.diff(pins) / np.diff(targets)
    assert np.all((speed >= lo - 1e-12) & (speed <= hi + 1e-12))
    assert 1.0 < pins[1] < 1.3  # moved as far as the band lets it


def test_within_falls_back_until_every_interval_is_in_its_band():
    # shortening alone cannot mend these moves: every interval ends inside its band
    targets = np.array([0.0, 0.597, 0.936, 1.389, 1.878, 2.229])
    planned = np.array([0.0, 0.54, 0.86, 1.298, 1.747, 2.087])
    moved = np.array([-0.03, 0.559, 0.999, 1.4, 1.77, 1.979])
    lo, hi = np.full(5, 0.848), np.full(5, 1.18)
    speed = np.diff(_within(moved, planned, planned, targets, lo, hi)) / np.diff(targets)
    assert np.all((speed >= lo - 1e-12) & (speed <= hi + 1e-12))


def _seen_score(res) -> float:
    """The landings' music-side Gaussian (sigma 0.05 s) on the output's motion beats."""
    from beatsync.evaluate.alignment import nearest_distance
    from beatsync.motion_beats import kinematic_beats

    d = nearest_distance(np.asarray(res.report["target_beats_s"]), kinematic_beats(res.motion))
    return float(np.mean(np.exp(-(d * d) / (2 * 0.05**2))))


def _off_band(res) -> int:
    fps = res.motion.fps
    t = np.arange(1, res.warp_src_times.size) / fps
    live = (t > res.warp.tgt[0]) & (t <= res.warp.tgt[-1])
    speed = np.diff(res.warp_src_times)[live] * fps
    return int(np.count_nonzero((speed < 0.8) | (speed > 1.25)))


@pytest.mark.parametrize(
    "name, bpm, bar, fill",
    [("DANCE_C_4", 84.0, 3, "loop"), ("DANCE_W_10", 90.0, 3, "loop"), ("salsa", 125.0, 4, "loop"),
     ("DANCE_R_3", 90.0, 3, "stop")],
)  # fmt: skip
def test_moved_landings_never_leave_the_plan_worse(name, bpm, bar, fill, monkeypatch):
    # against the plan's own landings (no rounds, no refinement): the landings score at
    # least as well and no more output plays outside 0.8-1.25, the run-on after the last
    # landing included (a real dancer, a BVH dancer)
    from beatsync import datasets
    from beatsync.sync import landing

    dancer = datasets.load_salsa() if name == "salsa" else datasets.load_dance_pair(name).motion
    beats = np.arange(0.31, 30.0 if fill == "loop" else 40.0, 60.0 / bpm)
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        for rounds, steps in ((0, 0), (landing.SEEN_ROUNDS, landing.REFINE_STEPS)):
            monkeypatch.setattr(landing, "SEEN_ROUNDS", rounds)
            monkeypatch.setattr(landing, "REFINE_STEPS", steps)
            runs[rounds] = synchronize(
                dancer, None, beats, mode="beats", fill=fill, beats_per_bar=bar, out_fps=25.0
            )
    plan, moved = runs[0], runs[landing.SEEN_ROUNDS]
    assert _seen_score(moved) >= _seen_score(plan) - 0.01  # view and output differ a little
    assert _off_band(moved) <= _off_band(plan)


def test_refined_pins_show_more_landings_on_their_frames(monkeypatch):
    # the waltz dancer DANCE_W_5 on the cha-cha dancer's song (tracked, 125 BPM): three
    # early landings on shallow dips stay a frame off after the rounds, as moving one
    # alone pushes its neighbour's minimum off; moved one pin at a time and measured
    # around it, more show on their frames, with no more output outside the band
    from beatsync import datasets, io
    from beatsync.beats import track_beats
    from beatsync.sync import landing

    y, sr = io.read_audio(datasets.path("motion/dance_with_melody/DANCE_C_4/audio.ogg"))
    beats = np.asarray(track_beats(y, sr).beats)
    dancer = datasets.load_dance_pair("DANCE_W_5").motion
    reports = {}
    for steps in (0, landing.REFINE_STEPS):
        monkeypatch.setattr(landing, "REFINE_STEPS", steps)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BeatsyncWarning)
            res = synchronize(dancer, None, beats, mode="beats", fill="loop", song_end=y.size / sr)
        reports[steps] = (res.report["landings_seen"]["on_their_frame"], _off_band(res))
    (seen0, off0), (seen1, off1) = reports[0], reports[landing.REFINE_STEPS]
    assert seen1 >= seen0 + 2
    assert off1 <= off0


@pytest.fixture(scope="module")
def waltz_on_a_cha_cha():
    """The real waltz dancer DANCE_W_10 (24 s) looped onto 40 s at a cha-cha's tempo
    (125 BPM), beats a quarter frame off the output's 25 fps grid."""
    from beatsync import datasets

    dancer = datasets.load_dance_pair("DANCE_W_10").motion
    beats = np.arange(0.31, 40.0, 60.0 / 125.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BeatsyncWarning)
        res = synchronize(dancer, None, beats, mode="beats", fill="loop", beats_per_bar=4)
    return dancer, res


def test_real_waltz_shows_its_landings_within_half_a_frame(waltz_on_a_cha_cha):
    # the output's own motion beats (as kinematic_beats finds them) on their beats: the
    # nearest output frame; 50 % of them without landing what the output shows
    from beatsync.evaluate.alignment import nearest_distance
    from beatsync.motion_beats import kinematic_beats

    _, res = waltz_on_a_cha_cha
    landed = np.asarray(res.report["target_beats_s"])[1:-1]  # the ends: no minimum
    d = nearest_distance(landed, kinematic_beats(res.motion))
    assert np.mean(d <= 0.5 / res.motion.fps + 1e-9) >= 0.85


def test_real_waltz_landings_keep_the_speed_band_and_the_dancers_peak(waltz_on_a_cha_cha):
    dancer, res = waltz_on_a_cha_cha
    fps = res.motion.fps
    t = np.arange(res.warp_src_times.size) / fps
    live = (t[1:] > res.warp.tgt[0]) & (t[1:] <= res.warp.tgt[-1])
    speed = np.diff(res.warp_src_times)[live] * fps
    assert np.mean((speed >= 0.8) & (speed <= 1.25)) >= 0.95
    own = np.linalg.norm(np.diff(dancer.positions(), axis=0), axis=-1).max() * dancer.fps
    out = np.linalg.norm(np.diff(res.motion.positions(), axis=0), axis=-1).max() * fps
    assert out <= 1.10 * own
