"""Tests of beatsync.graph: construction, searches, synthesis, quality proxies."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.evaluate.composition import foot_sliding, intensity_correlation, transition_jumps
from beatsync.graph import (
    aligned_distance_matrix,
    aligned_pair_distance,
    beat_warp,
    build_graph,
    conventional_search,
    dp_search,
    path_cost,
    random_walk,
    synthesize,
    transition_weight,
)
from beatsync.graph.compose import compose
from beatsync.motion import Motion
from beatsync.motion_beats import beat_interval_intensity, kinematic_beats, motion_positions
from beatsync.rotations import euler_to_rotation
from beatsync.study.paper_b import composition_proxies
from beatsync.synth.library import dance_skeleton, synthetic_dance, synthetic_library


@pytest.fixture(scope="module")
def library():
    return synthetic_library(3, duration=8.0, seed=1)


@pytest.fixture(scope="module")
def graph(library):
    clips, beats = library
    return build_graph(clips, beats=beats)


# ----------------------------------------------------------------- construction


def test_synthetic_beats_are_kinematic_beats():
    m, beats = synthetic_dance(duration=6.0, bpm=100.0, seed=3)
    kb = kinematic_beats(m, smooth=0.0)
    # every detected beat is a true beat (the held lead-in/out are plateaus)
    np.testing.assert_allclose(kb, beats[1:-1], atol=1e-9)


def test_graph_nodes_and_forward_edges(library, graph):
    clips, beats = library
    assert graph.n_nodes == sum(b.size for b in beats)
    assert graph.n_intervals == graph.n_nodes - len(clips)
    # node times are the given beats, clip by clip
    np.testing.assert_allclose(graph.node_time(), np.concatenate(beats), atol=1e-9)
    last = np.cumsum([b.size for b in beats]) - 1
    assert np.all(graph.next_node[last] == -1)
    ok = graph.next_node >= 0
    assert np.all(graph.next_node[ok] == np.flatnonzero(ok) + 1)
    assert np.all(np.isnan(graph.intensity[~ok]))
    z = graph.z_intensity[ok]
    np.testing.assert_allclose([z.mean(), z.std()], [0.0, 1.0], atol=1e-9)


def test_intensity_follows_amplitude():
    # same move at two loudness levels: the louder clip has the larger intensity
    m_lo, b_lo = synthetic_dance(duration=5, seed=0, level_range=(0.3, 0.3), n_moves=1)
    m_hi, b_hi = synthetic_dance(duration=5, seed=0, level_range=(0.9, 0.9), n_moves=1)
    g = build_graph([m_lo, m_hi], beats=[b_lo, b_hi])
    lo = np.nanmean(g.intensity[g.node_clip == 0])
    hi = np.nanmean(g.intensity[g.node_clip == 1])
    assert hi > 4 * lo


def test_identical_clips_are_connected_at_zero_distance():
    m, b = synthetic_dance(duration=5, seed=2)
    g = build_graph([m, m.rename("copy")], beats=[b, b])
    n = b.size
    pairs = set(zip(g.trans_src.tolist(), g.trans_dst.tolist(), strict=True))
    for i in range(n):
        assert (i, i + n) in pairs and (i + n, i) in pairs  # two-way
    same = (g.trans_src % n) == (g.trans_dst % n)
    np.testing.assert_allclose(g.trans_rd[same], 0.0, atol=1e-6)  # stable distance formula
    assert np.all(g.trans_weight[same] == 2.0)  # eq. 2 as written: at least 2


def test_weight_rules():
    rd = np.array([0.5, 2.0, 2.5])
    np.testing.assert_allclose(transition_weight(rd, "paper"), [2.0, 2.0, 2.5])
    np.testing.assert_allclose(transition_weight(rd, "rd"), rd)
    with pytest.raises(ParameterError):
        transition_weight(rd, "max")


def test_aligned_distance_invariant_to_floor_rigid_motion(rng):
    a = rng.normal(size=(1, 40, 3))
    rot = Rotation.from_euler("y", 73, degrees=True)
    b = rot.apply(a[0]) + np.array([3.0, 0.0, -2.0])
    d = aligned_distance_matrix(a, b[None])
    assert d[0, 0] < 1e-6  # sqrt of a difference of sums: ~1e-8 round-off
    c = b + np.array([0.0, 0.1, 0.0])  # vertical offsets are not aligned away
    np.testing.assert_allclose(aligned_distance_matrix(a, c[None])[0, 0], 0.1, rtol=1e-9)


@pytest.mark.parametrize("height", [0.0, 100.0, 1e4])
def test_identical_clouds_at_zero_distance_far_from_the_floor(rng, height):
    # the closed form subtracts sums of squares of the heights: far from the floor the
    # old formula returned 1.8e-6 (100 units) and 1.6e-4 (1e4 units) for identical clouds
    a = rng.normal(size=(3, 300, 3)) * 0.3
    a[:, :, 1] += height
    assert np.diag(aligned_distance_matrix(a, a)).max() < 1e-9 * max(1.0, height)
    assert aligned_pair_distance(a, a).max() < 1e-9 * max(1.0, height)


def test_rd_is_scale_free():
    clips1 = [synthetic_dance(duration=6, seed=s, scale=1.0)[0] for s in (0, 1)]
    clips2 = [synthetic_dance(duration=6, seed=s, scale=100.0)[0] for s in (0, 1)]
    beats = [synthetic_dance(duration=6, seed=s)[1] for s in (0, 1)]
    g1 = build_graph(clips1, beats=beats)
    g2 = build_graph(clips2, beats=beats)
    assert g1.n_transitions == g2.n_transitions
    np.testing.assert_allclose(g1.trans_rd, g2.trans_rd, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(g1.z_intensity, g2.z_intensity, rtol=1e-6)


# ----------------------------------------------------------------- bad inputs


def test_empty_library():
    with pytest.raises(ParameterError, match="empty"):
        build_graph([])


def test_different_skeletons_named(library):
    clips, _ = library
    other = dance_skeleton()
    joints = list(other.joints)
    joints[1] = type(joints[1])("torso", 0, joints[1].offset, joints[1].channels)
    sk = type(other)(tuple(joints))
    m = Motion(clips[0].values, clips[0].fps, sk.channel_names(), sk, "odd_clip")
    with pytest.raises(ParameterError, match="odd_clip"):
        build_graph([clips[0], m])


def test_given_beats_after_last_frame_refused(library):
    clips, beats = library
    m = clips[0]
    last = (m.n_frames - 1) / m.fps
    # Motion.duration (n / fps) is one frame after the last frame: refused, not clipped
    bad = np.concatenate([beats[0][:-1], [m.duration]])
    with pytest.raises(ParameterError, match=f"end at {m.duration:g} s"):
        build_graph([m], beats=[bad], require_transitions=False)
    ok = np.concatenate([beats[0][:-1], [last]])
    g = build_graph([m], beats=[ok], require_transitions=False)
    assert g.node_frame[-1] == m.n_frames - 1


def test_given_beats_on_one_frame_merge_with_warning(library):
    clips, beats = library
    m = clips[0]
    b = beats[0]
    close = np.sort(np.concatenate([b, [b[2] + 0.2 / m.fps]]))  # rounds to b[2]'s frame
    with pytest.warns(BeatsyncWarning, match="round to the same frame"):
        g = build_graph([m], beats=[close], require_transitions=False)
    assert g.n_nodes == b.size
    np.testing.assert_allclose(g.node_time(), b, atol=1e-9)


def test_check_th_is_the_one_threshold_check():
    from beatsync.graph import check_th

    assert check_th("2.5") == 2.5
    with pytest.raises(ParameterError, match="--th=0"):
        check_th(0.0, name="--th")


@pytest.mark.parametrize("th", [0.0, -1.0, float("nan"), "abc"])
def test_bad_threshold(library, th):
    with pytest.raises(ParameterError, match="TH"):
        build_graph(library[0], beats=library[1], th=th)


def test_no_transitions_suggests_threshold():
    m1, b1 = synthetic_dance(duration=5, seed=0, vocabulary_seed=0, n_moves=1)
    with pytest.raises(ParameterError, match="TH=1e-06"):
        build_graph([m1], beats=[b1], th=1e-6)


# ----------------------------------------------------------------- searches


def _all_paths(graph, k_n):
    src, dst, _ = graph.successors()
    succ = {}
    for a, b in zip(src.tolist(), dst.tolist(), strict=True):
        succ.setdefault(a, []).append(b)
    paths = [[u] for u in np.flatnonzero(graph.is_interval).tolist()]
    for _ in range(k_n - 1):
        paths = [p + [v] for p in paths for v in succ.get(p[-1], [])]
    return paths


@pytest.fixture(scope="module")
def tiny_graph():
    clips, beats = synthetic_library(2, duration=2.6, seed=4, bpm_range=(100, 110))
    g = build_graph(clips, beats=beats, th=3.0)
    assert 0 < g.n_transitions and g.n_intervals <= 10
    return g


@pytest.mark.parametrize("lam", [0.0, 0.3, 1.0, 5.0])
@pytest.mark.parametrize("rule", ["paper", "rd"])
def test_dp_is_optimal_against_brute_force(tiny_graph, lam, rule):
    g = tiny_graph.with_rule(rule)
    rng = np.random.default_rng(7)
    k_n = 5
    music = rng.normal(size=k_n)
    best = min(path_cost(g, p, music, lam=lam)[0] for p in _all_paths(g, k_n))
    res = dp_search(g, music, lam=lam)
    np.testing.assert_allclose(res.cost, best, rtol=1e-12, atol=1e-12)


def test_dp_with_tempo_term_is_optimal(tiny_graph):
    rng = np.random.default_rng(8)
    k_n = 4
    music = rng.normal(size=k_n)
    dur = rng.uniform(0.4, 0.8, size=k_n)
    kw = {"lam": 1.0, "tempo_weight": 2.0, "music_durations": dur}
    best = min(path_cost(tiny_graph, p, music, **kw)[0] for p in _all_paths(tiny_graph, k_n))
    assert dp_search(tiny_graph, music, **kw).cost == pytest.approx(best, abs=1e-12)


def test_dp_follows_music_intensity(graph):
    # music intensity = the intensity of a path that exists: the DP cost must be ~0
    start = int(np.flatnonzero(graph.is_interval)[0])
    path = [start]
    for _ in range(4):
        path.append(int(graph.next_node[path[-1]]))
    music = graph.z_intensity[path]
    res = dp_search(graph, music)
    assert res.intensity_cost == pytest.approx(0.0, abs=1e-12)


def test_conventional_and_random_are_feasible(graph):
    rng = np.random.default_rng(3)
    k_n = 20
    music = rng.normal(size=k_n)
    dur = np.full(k_n, 0.55)
    conv = conventional_search(graph, music, dur, segment_beats=4, max_candidates=500)
    dp = dp_search(graph, music)
    assert conv.path.size == k_n
    assert conv.cost >= dp.cost - 1e-9  # the DP is the global optimum
    rw1 = random_walk(graph, k_n, seed=5)
    rw2 = random_walk(graph, k_n, seed=5)
    np.testing.assert_array_equal(rw1.path, rw2.path)
    path_cost(graph, rw1.path, music)  # raises if a step is not an edge
    # the control optimises nothing: it reports no costs, but its transitions
    assert np.isnan([rw1.cost, rw1.intensity_cost, rw1.transition_cost]).all()
    assert rw1.transitions.shape == rw1.path.shape


def test_search_bad_inputs(graph):
    with pytest.raises(ParameterError, match="music intensity"):
        dp_search(graph, np.empty(0))
    with pytest.raises(ParameterError):
        dp_search(graph, [0.0, np.nan])
    with pytest.raises(ParameterError):
        dp_search(graph, [0.0, 1.0], lam=-1)
    with pytest.raises(ParameterError):
        conventional_search(graph, [0.0, 1.0], [0.5])


# ----------------------------------------------------------------- synthesis


def test_beat_warp_lands_exactly():
    beats = np.array([0.5, 1.1, 1.6, 2.3])
    s0 = np.array([2.0, 7.25, 3.0])
    s1 = np.array([2.7, 7.9, 3.45])
    k, s = beat_warp(beats, s0, s1, beats[:-1])
    np.testing.assert_array_equal(k, [0, 1, 2])
    np.testing.assert_array_equal(s, s0)
    _, s_end = beat_warp(beats, s0, s1, beats[1:] - 1e-12)
    np.testing.assert_allclose(s_end, s1, atol=1e-9)


@pytest.mark.parametrize("warp", ["linear", "pchip"])
def test_motion_beats_land_on_music_beats(graph, warp):
    fps = graph.clips[0].fps
    k_n = 12
    music_beats = 0.5 + np.cumsum(np.concatenate([[0], np.full(k_n, 0.5)]))
    music_beats = np.rint(music_beats * fps) / fps  # on output frames
    res = dp_search(graph, np.random.default_rng(0).normal(size=k_n))
    syn = synthesize(graph, res.path, music_beats, warp=warp)
    np.testing.assert_array_equal(syn.beat_source_times[:-1], graph.node_time()[res.path])
    frames = np.rint(music_beats * fps).astype(int)
    # at every beat the source time is a beat frame of the library
    src_at_beats = syn.source_time[frames[:-1]]
    np.testing.assert_allclose(src_at_beats, graph.node_time()[res.path], atol=1e-9)
    # non-root channels at non-transition beats equal the source beat frame exactly
    clip0 = graph.clips[0]
    body = [i for i, c in enumerate(clip0.channels) if not c.startswith("hip_")]
    for k in range(k_n):
        if res.transitions[k]:
            continue
        node = res.path[k]
        src = graph.clips[graph.node_clip[node]].values[graph.node_frame[node]]
        got = syn.motion.values[frames[k]]
        d = (got[body] - src[body] + 180.0) % 360.0 - 180.0
        np.testing.assert_allclose(d, 0.0, atol=1e-6)


def _max_angle_step(motion, joint_cols, order):
    r = euler_to_rotation(motion.values[:, joint_cols], order)
    return (r[1:] * r[:-1].inv()).magnitude()


def test_transition_blending_is_continuous():
    # two different clips, forced transitions by a path that alternates clips
    clips, beats = synthetic_library(2, duration=6.0, seed=11, bpm_range=(100, 100))
    g = build_graph(clips, beats=beats, th=50.0, weight_rule="rd")
    src, dst, _ = g.successors()
    trans = g.next_node[src] != dst
    cross = trans & (g.node_clip[src] != g.node_clip[dst])
    u, v = int(src[cross][0]), int(dst[cross][0])
    path = [u, v, int(g.next_node[v])]
    assert g.is_interval[path].all()
    fps = clips[0].fps
    music = np.array([0.5, 1.1, 1.7, 2.3])
    t_trans = music[1]
    jf = int(round(t_trans * fps))
    steps = {}
    for blend in (0.0, 1.0 / 3.0):
        m = synthesize(g, path, music, blend=blend, warp="linear").motion
        root = m.values[:, :3]
        jumps = np.linalg.norm(np.diff(root, axis=0), axis=1)
        ang = np.max(
            [_max_angle_step(m, list(idx), order) for _, idx, order in m.rotation_triples()],
            axis=0,
        )
        steps[blend] = (jumps, ang)
    jumps, ang = steps[1.0 / 3.0]
    typical_ang = np.median(ang)
    # with blending, the step at the transition is of ordinary size
    assert ang[jf - 1 : jf + 2].max() < 4 * max(typical_ang, 1e-3)
    assert jumps[jf - 1 : jf + 2].max() < 4 * max(np.median(jumps), 1e-4) + 1e-6
    # without blending the same transition jumps (so the test can fail)
    ang0 = steps[0.0][1]
    assert ang0[jf - 1 : jf + 2].max() > ang[jf - 1 : jf + 2].max()


def test_root_alignment_no_jump_on_floor():
    m, b = synthetic_dance(duration=5, seed=0)
    vals = m.values.copy()
    vals[:, 0] += 0.4 * m.times  # walk along x
    moving = m.with_values(vals)
    turned_vals = m.values.copy()
    turned_vals[:, 2] += 5.0  # far away on z
    other = m.with_values(turned_vals).rename("far")
    g = build_graph([moving, other], beats=[b, b], th=50.0)
    # path: two intervals of clip 0, then jump to clip 1
    n0 = b.size
    path = [1, 2, n0 + 4, n0 + 5]
    music = np.array([0.5, 1.0, 1.5, 2.0, 2.5])
    out = synthesize(g, path, music, blend=0.0, warp="linear").motion
    root = out.values[:, [0, 2]]
    step = np.linalg.norm(np.diff(root, axis=0), axis=1)
    assert step.max() < 0.1  # no 5 m teleport


def test_synthesize_bad_inputs(graph):
    path = dp_search(graph, [0.0, 1.0, -1.0]).path
    with pytest.raises(ParameterError, match="path has 3 nodes for 1"):
        synthesize(graph, path, [0.5, 1.0])
    with pytest.raises(ParameterError):
        synthesize(graph, path, [0.5, 1.0, 0.9, 2.0])
    with pytest.raises(ParameterError, match="1 beat"):
        synthesize(graph, path[:0], [0.5])
    with pytest.raises(ParameterError, match="cubic"):
        synthesize(graph, path, [0.5, 1.0, 1.5, 2.0], warp="cubic")


# ----------------------------------------------------------------- compose + quality


def test_quality_known_answer_exact_composition():
    # one clip, music beats = the clip's own beats, music level = its own intensities:
    # the DP must play the clip as captured (no transition, identity warp), so the
    # composed motion's beats land exactly on the music beats and its intensity
    # follows the level exactly
    m, b = synthetic_dance(duration=8.0, seed=4)
    g = build_graph([m], beats=[b], require_transitions=False)
    inten = beat_interval_intensity(m, b)
    music = b[1:-1]
    comp = compose(g, music, inten[1:-1], end_time=7.9)
    np.testing.assert_array_equal(comp.search.path, np.arange(1, b.size - 2))
    assert comp.n_transitions == 0
    np.testing.assert_allclose(comp.motion.values, m.values[: comp.motion.n_frames], atol=1e-9)
    q = composition_proxies(comp, beat_smooth=0.0)
    assert q["alignment_motion"] == pytest.approx(1.0, abs=1e-9)
    assert q["alignment_music"] == pytest.approx(1.0, abs=1e-9)
    assert q["intensity_r"] == pytest.approx(1.0, abs=1e-9)
    assert q["n_transitions"] == 0 and np.isnan(q["transition_jump_max"])
    # the same dance against music beats half a beat off scores near zero
    off = dataclasses.replace(comp, music_beats=music[:-1] + 0.3)
    q_off = composition_proxies(off, beat_smooth=0.0)
    assert q_off["alignment_motion"] < 0.01 and q_off["alignment_music"] < 0.01


def test_dp_beats_random_walk_on_intensity_correlation(graph):
    rng = np.random.default_rng(2)
    beats = 0.5 + 0.55 * np.arange(15)
    level = rng.uniform(-30, -5, size=14)
    r_dp = composition_proxies(compose(graph, beats, level))["intensity_r"]
    r_rand = [
        composition_proxies(compose(graph, beats, level, method="random", seed=s))["intensity_r"]
        for s in range(5)
    ]
    assert r_dp > 0.5
    assert max(r_rand) < r_dp
    assert np.mean(r_rand) < r_dp - 0.3


def test_compose_and_quality(graph):
    rng = np.random.default_rng(2)
    beats = 0.5 + 0.55 * np.arange(15)
    level = rng.uniform(-30, -5, size=14)
    comp = compose(graph, beats, level)
    assert comp.motion.skeleton is graph.clips[0].skeleton
    assert comp.motion.n_frames == int(np.floor(beats[-1] * comp.motion.fps)) + 1
    q = composition_proxies(comp)
    assert 0.0 <= q["alignment_motion"] <= 1.0 and 0.0 <= q["alignment_music"] <= 1.0
    assert -1.0 <= q["intensity_r"] <= 1.0
    assert q["foot_sliding"] >= 0
    with pytest.raises(ParameterError, match="1 beat"):
        compose(graph, [0.5], [])
    with pytest.raises(ParameterError, match="music_level"):
        compose(graph, beats, level[:-1])
    with pytest.raises(ParameterError, match="blend=None is not a number"):
        compose(graph, beats, level, blend=None)
    with pytest.raises(ParameterError, match=r"unknown option\(s\) \['segment_beat'\]"):
        compose(graph, beats, level, method="conventional", segment_beat=4)


def test_transition_jumps_and_foot_sliding_known():
    m, _ = synthetic_dance(duration=4, seed=0)
    assert transition_jumps(motion_positions(m), [], fps=m.fps).size == 0
    # upper body dancing, legs and hip still: the feet do not slide
    vals = m.values.copy()
    legs = [
        i
        for i, c in enumerate(m.channels)
        if c.split("_")[0] in ("hip", "lThigh", "rThigh", "lShin", "rShin", "lFoot", "rFoot")
    ]
    vals[:, legs] = m.values[0, legs]
    m = m.with_values(vals)
    feet = ["lFoot", "rFoot"]
    assert foot_sliding(motion_positions(m, joints=feet), fps=m.fps) < 1e-9
    vals = m.values.copy()
    vals[:, 0] += 1.0 * m.times  # whole body glides at 1 m/s
    glide = motion_positions(m.with_values(vals), joints=feet)
    assert foot_sliding(glide, fps=m.fps) == pytest.approx(1.0, rel=0.05)


def test_brute_force_enumeration_sane(tiny_graph):
    # the helper enumerates exactly the feasible paths
    for p in itertools.islice(_all_paths(tiny_graph, 3), 20):
        path_cost(tiny_graph, p, np.zeros(3))


def test_root_euler_curves_stay_continuous_after_heading_alignment():
    m, b = synthetic_dance(duration=5, seed=0)
    vals = m.values.copy()
    yrot = m.channel_index("hip_Yrotation")
    vals[:, yrot] += 170.0  # the other clip faces the opposite way
    turned = m.with_values(vals).rename("turned")
    g = build_graph([m, turned], beats=[b, b], th=50.0)
    n0 = b.size
    path = [1, 2, n0 + 3, n0 + 4, 5, 6]
    music = 0.5 + 0.5 * np.arange(7)
    out = synthesize(g, path, music, warp="linear").motion
    root_rot = [out.channel_index(f"hip_{a}rotation") for a in "ZXY"]
    steps = np.abs(np.diff(out.values[:, root_rot], axis=0))
    assert steps.max() < 20.0  # degrees per frame: no 180/360 flips in the file
    # and the dancer keeps facing the same way across the transition
    r = euler_to_rotation(out.values[:, root_rot], "ZXY")
    assert (r[1:] * r[:-1].inv()).magnitude().max() < np.radians(20)


def test_intensity_correlation_known_answers():
    m, b = synthetic_dance(duration=8, seed=0)
    inten = beat_interval_intensity(m, b)
    assert intensity_correlation(inten, inten * 3 - 1) == pytest.approx(1.0)
    assert intensity_correlation(inten, -inten) == pytest.approx(-1.0)
    with pytest.warns(BeatsyncWarning, match="fewer than two"):
        assert np.isnan(intensity_correlation(inten[:1], inten[:1]))


def test_with_threshold_equals_a_build_at_that_threshold(library):
    clips, beats = library
    wide = build_graph(clips, beats=beats, th=10.0)
    g3 = build_graph(clips, beats=beats, th=3.0)
    cut = wide.with_threshold(3.0)
    assert cut.th == 3.0 and cut.n_transitions == g3.n_transitions
    np.testing.assert_array_equal(cut.trans_src, g3.trans_src)
    np.testing.assert_allclose(cut.trans_weight, g3.trans_weight)
    np.testing.assert_array_equal(cut.successors()[1], g3.successors()[1])
    with pytest.raises(ParameterError, match="TH=5 "):
        g3.with_threshold(5.0)
