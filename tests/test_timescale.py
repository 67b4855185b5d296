"""Tempo-matched composition: motion tempo, tempo groups, multiplicity, the scale bound."""

from __future__ import annotations

import itertools
import json
import warnings

import numpy as np
import pytest

from beatsync import io
from beatsync.cli import main
from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.graph import build_graph, conventional_search, dp_search, path_cost, random_walk
from beatsync.graph.compose import compose
from beatsync.graph.timescale import (
    check_scale_bound,
    choose_multiplicity,
    clip_tempi,
    tempo_groups,
)
from beatsync.motion_beats import kinematic_beats, motion_tempo
from beatsync.study.paper_b import composition_proxies
from beatsync.synth.audio import drum_song
from beatsync.synth.library import synthetic_dance

# ----------------------------------------------------------------- motion tempo


@pytest.mark.parametrize("bpm", [70.0, 100.0, 135.0])
def test_motion_tempo_of_clips_with_known_beats(bpm):
    m, beats = synthetic_dance(duration=12.0, bpm=bpm, seed=1)
    # the exact beats, their kinematic beats, and the beats with every third one missed
    assert motion_tempo(beats) == pytest.approx(bpm, rel=0.01)
    assert motion_tempo(kinematic_beats(m, smooth=0.0)) == pytest.approx(bpm, rel=0.02)
    assert motion_tempo(np.delete(beats, np.arange(2, beats.size, 3))) == pytest.approx(
        bpm, rel=0.01
    )


def test_motion_tempo_with_jitter_and_bad_input(rng):
    beats = np.cumsum(0.5 * (1 + rng.uniform(-0.04, 0.04, size=40)))
    assert motion_tempo(beats) == pytest.approx(120.0, rel=0.03)
    with pytest.raises(ParameterError, match="1 motion beat"):
        motion_tempo([1.0])
    with pytest.raises(ParameterError, match="tolerance"):
        motion_tempo(beats, tolerance=0.0)
    with pytest.raises(ParameterError, match="reversed"):
        motion_tempo(beats, min_bpm=200, max_bpm=100)


def test_clip_tempi_and_groups():
    clips, beats = [], []
    for i, bpm in enumerate((60.0, 66.0, 120.0)):
        m, b = synthetic_dance(duration=8.0, bpm=bpm, seed=i, name=f"c{i}")
        clips.append(m)
        beats.append(b)
    g = build_graph(clips, beats=beats, th=50.0)
    tempi = clip_tempi(g)
    np.testing.assert_allclose(tempi, [60.0, 66.0, 120.0], rtol=0.02)
    np.testing.assert_array_equal(tempo_groups(tempi, width=1.25 / 0.8), [0, 0, 1])
    assert choose_multiplicity(60.0, 120.0, (0.8, 1.25)) == (2.0,)
    assert choose_multiplicity(70.0, 120.0, (0.8, 1.25)) == (1.0, 2.0)
    assert choose_multiplicity(140.0, 70.0, (0.8, 1.25)) == (0.5, 1.0)


@pytest.mark.parametrize(
    ("bound", "match"),
    [((1.2, 0.9), "reversed"), ((1.1, 1.3), "contain 1"), ((0.8,), "two numbers"), ("x", "two")],
)
def test_bad_scale_bound(bound, match):
    with pytest.raises(ParameterError, match=match):
        check_scale_bound(bound)


# ----------------------------------------------------------------- the bound in the searches


@pytest.fixture(scope="module")
def two_tempo_graph():
    """A slow loud clip (60 BPM) and a clip at the music's tempo (100 BPM), quieter."""
    slow, bs = synthetic_dance(duration=10.0, bpm=60.0, seed=1, level_range=(0.9, 1.0))
    fit, bf = synthetic_dance(duration=10.0, bpm=100.0, seed=2, level_range=(0.2, 0.5))
    return build_graph([slow.rename("slow"), fit.rename("fit")], beats=[bs, bf], th=50.0)


def _music(graph, k_n=12):
    # loud music everywhere: the slow clip's loud intervals match it best
    z = np.full(k_n, float(np.nanmax(graph.z_intensity)))
    return z, np.full(k_n, 0.6)


def test_unbounded_optimum_violates_the_bound(two_tempo_graph):
    g = two_tempo_graph
    z, md = _music(g)
    res = dp_search(g, z, music_durations=md)
    assert np.any(res.scales < 0.8)  # the slow clip's 1 s intervals squeezed into 0.6 s
    # a rhythm match too wide to filter anything: the baseline picks by intensity
    loose = {"rhythm_threshold": 0.0, "rhythm_sigma": 10.0, "segment_beats": 2}
    conv = conventional_search(g, z, md, max_candidates=10000, **loose)
    assert np.any(conv.scales < 0.8)
    walks = [random_walk(g, z.size, seed=s, music_durations=md) for s in range(5)]
    assert any(np.any(w.scales < 0.8) for w in walks)


@pytest.mark.parametrize("method", ["dp", "conventional", "random"])
def test_every_search_respects_the_bound(two_tempo_graph, method):
    g = two_tempo_graph
    z, md = _music(g)
    kw = {"music_durations": md, "scale_bound": (0.8, 1.25)}
    if method == "dp":
        res = dp_search(g, z, **kw)
        unbounded = dp_search(g, z, music_durations=md)
        assert res.cost > unbounded.cost  # the bound costs something here
    elif method == "conventional":
        loose = {"rhythm_threshold": 0.0, "rhythm_sigma": 10.0, "segment_beats": 2}
        res = conventional_search(g, z, md, max_candidates=500, scale_bound=(0.8, 1.25), **loose)
    else:
        res = random_walk(g, z.size, seed=3, **kw)
    assert np.all((res.scales >= 0.8 - 1e-9) & (res.scales <= 1.25 + 1e-9))
    assert res.boundaries[-1] == z.size
    # path_cost accepts the path under the bound
    path_cost(g, res.path, z, boundaries=res.boundaries, **kw)


def test_path_cost_refuses_out_of_bound_intervals(two_tempo_graph):
    g = two_tempo_graph
    z, md = _music(g)
    res = dp_search(g, z, music_durations=md)
    with pytest.raises(ParameterError, match=r"0\.8-1\.25"):
        path_cost(g, res.path, z, music_durations=md, scale_bound=(0.8, 1.25))


def _all_bounded_paths(graph, g_n, steps):
    src, dst, _ = graph.successors()
    succ = {}
    for a, b in zip(src.tolist(), dst.tolist(), strict=True):
        succ.setdefault(a, []).append(b)
    out = []

    def rec(path, bnd):
        if bnd[-1] == g_n:
            out.append((list(path), list(bnd)))
            return
        nxt = np.flatnonzero(graph.is_interval).tolist() if not path else succ.get(path[-1], [])
        for v, s in itertools.product(nxt, steps):
            if bnd[-1] + s <= g_n:
                rec([*path, v], [*bnd, bnd[-1] + s])

    rec([], [0])
    return out


def test_bounded_dp_with_steps_is_optimal_against_brute_force():
    clips, beats = [], []
    for i, bpm in enumerate((60.0, 110.0)):
        m, b = synthetic_dance(duration=3.2, bpm=bpm, seed=i + 4)
        clips.append(m)
        beats.append(b)
    g = build_graph(clips, beats=beats, th=50.0)
    rng = np.random.default_rng(5)
    g_n = 5
    z = rng.normal(size=g_n)
    md = rng.uniform(0.45, 0.6, size=g_n)
    kw = {"music_durations": md, "scale_bound": (0.8, 1.25), "lam": 0.5}
    best = np.inf
    for p, b in _all_bounded_paths(g, g_n, (1, 2)):
        try:
            best = min(best, path_cost(g, p, z, boundaries=b, **kw)[0])
        except ParameterError:
            continue  # out of the bound
    assert np.isfinite(best)
    res = dp_search(g, z, steps=(1, 2), **kw)
    assert res.cost == pytest.approx(best, abs=1e-9)


# ----------------------------------------------------------------- multiplicity, no path


def _library(bpm, n=2, duration=12.0):
    clips, beats = [], []
    for i in range(n):
        m, b = synthetic_dance(duration=duration, bpm=bpm, seed=i, name=f"lib{i}")
        clips.append(m)
        beats.append(b)
    return build_graph(clips, beats=beats)


def test_library_at_half_the_music_tempo_covers_two_beats():
    g = _library(60.0)
    song = drum_song(10.0, bpm=120.0, sr=22050, seed=0)
    level = np.linspace(-20, -10, song.beats.size - 1)
    comp = compose(g, song.beats, level)
    assert comp.tempo.multiplicity == (2.0,)
    np.testing.assert_array_equal(np.diff(comp.search.boundaries), 2)
    np.testing.assert_allclose(comp.search.scales, 1.0, atol=0.03)
    # every motion beat lands on a music beat (every other one)
    assert set(np.round(comp.anchors, 9)) <= set(np.round(song.beats, 9))
    q = composition_proxies(comp, beat_smooth=0.0)
    assert q["alignment_motion"] > 0.9
    assert comp.plausibility["root_speed_ratio"] < 1.1
    # paper B as written squeezes each 1 s interval into a 0.5 s beat
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", BeatsyncWarning)
        fast = compose(g, song.beats, level, scale_bound=None)
    np.testing.assert_allclose(fast.search.scales, 0.5, atol=0.03)
    assert fast.plausibility["rotation_speed_ratio"] > 1.5
    assert any("faster than its library" in str(w.message) for w in caught)


def test_library_at_double_the_music_tempo_fills_a_beat_with_two_intervals():
    g = _library(120.0)
    song = drum_song(10.0, bpm=60.0, sr=22050, seed=0)
    level = np.linspace(-20, -10, song.beats.size - 1)
    comp = compose(g, song.beats, level)
    assert comp.tempo.subdivision == 2 and 0.5 in comp.tempo.multiplicity
    assert np.all((comp.search.scales >= 0.8) & (comp.search.scales <= 1.25))
    assert comp.report()["multiplicity_used"].get("0.5", 0) > 0


def test_no_path_error_names_both_tempi_and_the_bound():
    g = _library(100.0)
    song = drum_song(8.0, bpm=200.0, sr=22050, seed=0)
    level = np.zeros(song.beats.size - 1)
    with pytest.raises(ParameterError, match=r"100 BPM.*200 BPM"):
        compose(g, song.beats, level, multiplicity=[1])
    md = np.diff(song.beats)
    for method in ("conventional", "random"):
        with pytest.raises(ParameterError, match=r"0\.8-1\.25.*100 BPM.*200 BPM"):
            compose(g, song.beats, level, multiplicity=[1], method=method)
    with pytest.raises(ParameterError, match="scale-bound"):
        dp_search(g, np.zeros(md.size), music_durations=md, scale_bound=(0.8, 1.25))
    # relaxing the bound as suggested composes
    with pytest.warns(BeatsyncWarning, match="faster than its library"):
        comp = compose(g, song.beats, level, multiplicity=[1], scale_bound=(0.4, 1.25))
    assert comp.search.scales.min() >= 0.4


def test_tempo_groups_choose_the_clips():
    slow, bs = synthetic_dance(duration=10.0, bpm=60.0, seed=1)
    fast, bf = synthetic_dance(duration=10.0, bpm=100.0, seed=2)
    g = build_graph([slow.rename("slow"), fast.rename("fast")], beats=[bs, bf], th=50.0)
    song = drum_song(10.0, bpm=100.0, sr=22050, seed=0)
    level = np.linspace(-20, -10, song.beats.size - 1)
    comp = compose(g, song.beats, level, multiplicity=[1])
    rows = {r["clip"]: r for r in comp.tempo.clip_table}
    assert rows["fast"]["eligible"] and not rows["slow"]["eligible"]
    assert "outside the bound" in rows["slow"]["reason"] and "60 BPM" in rows["slow"]["reason"]
    assert set(g.node_clip[comp.search.path]) == {1}
    whole = compose(g, song.beats, level, multiplicity=[1], tempo_select=False)
    assert all(r["eligible"] for r in whole.tempo.clip_table)


# ----------------------------------------------------------------- CLI


@pytest.fixture
def slow_lib(tmp_path, monkeypatch):
    monkeypatch.setenv("BEATSYNC_CACHE_DIR", str(tmp_path / "cache"))
    lib = tmp_path / "lib"
    lib.mkdir()
    for seed in (0, 1):
        m, _ = synthetic_dance(duration=10.0, bpm=60.0, seed=seed)
        io.write_bvh(lib / f"clip{seed}.bvh", m)
    song = drum_song(8.0, bpm=120.0, sr=22050, seed=1)
    io.write_audio(tmp_path / "song.wav", song.y, song.sr)
    io.write_beats(tmp_path / "song.beats", song.beats)
    return tmp_path


def _argv(d, *extra):
    return [
        "compose",
        str(d / "song.wav"),
        "--library",
        str(d / "lib"),
        "--beats",
        str(d / "song.beats"),
        "-o",
        str(d / "dance.bvh"),
        "--json",
        *extra,
    ]


def test_cli_tempo_matched_end_to_end(slow_lib, capsys):
    assert main(_argv(slow_lib)) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["tempo"]["multiplicity"] == [2.0]
    assert res["multiplicity_used"] == {"2": res["multiplicity_used"]["2"]}
    assert all(r["eligible"] and "BPM" in r["reason"] for r in res["tempo"]["clips"])
    p = res["plausibility"]
    assert 0.8 <= p["scale_min"] and p["scale_max"] <= 1.25 and p["scale_outside_bound"] == 0
    assert p["root_speed_ratio"] < 1.25 and p["rotation_speed_ratio"] < 1.25
    assert res["warnings"] == []
    assert io.read_bvh(slow_lib / "dance.bvh").n_frames == res["n_frames"]
    # paper B as written: squeezed, and the command says so
    assert main(_argv(slow_lib, "--no-scale-bound")) == 0
    captured = capsys.readouterr()
    res = json.loads(captured.out)
    assert res["plausibility"]["scale_max"] < 0.6
    assert "faster than its library" in captured.err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--scale-bound", "1.2", "0.9"], "reversed"),
        (["--scale-bound", "1.1", "1.3"], "contain 1"),
        (["--multiplicity", "5"], "multiplicity"),
        (["--multiplicity", "1"], "relax the bound"),
    ],
)
def test_cli_bad_bounds_write_nothing(slow_lib, capsys, extra, message):
    assert main(_argv(slow_lib, *extra)) == 3
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (slow_lib / "dance.bvh").exists()


@pytest.mark.parametrize("multiplicity", ["bogus", "Auto", [5.0]])
def test_plan_tempo_refuses_a_bad_multiplicity(two_tempo_graph, multiplicity):
    from beatsync.graph.timescale import plan_tempo

    with pytest.raises(ParameterError, match="multiplicity"):
        plan_tempo(two_tempo_graph, np.arange(0.0, 10.0, 0.5), multiplicity=multiplicity)
