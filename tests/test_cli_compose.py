"""End-to-end tests of ``beatsync compose``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from beatsync import io
from beatsync.cli import main
from beatsync.motion import Joint, Motion, Skeleton
from beatsync.synth.audio import drum_song
from beatsync.synth.library import synthetic_dance


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.setenv("BEATSYNC_CACHE_DIR", str(tmp_path / "cache"))
    lib = tmp_path / "lib"
    lib.mkdir()
    for seed in (0, 1):
        m, _ = synthetic_dance(duration=6.0, bpm=110.0, seed=seed)
        io.write_bvh(lib / f"clip{seed}.bvh", m)
    song = drum_song(6.0, bpm=110.0, sr=22050, seed=1)
    io.write_audio(tmp_path / "song.wav", song.y, song.sr)
    io.write_beats(tmp_path / "song.beats", song.beats)
    return tmp_path


def _outputs(d):
    return sorted(p.name for p in d.iterdir() if p.suffix in (".bvh", ".json", ".mp4"))


def test_compose_end_to_end_with_beats(workdir, capsys):
    out = workdir / "dance.bvh"
    rep = workdir / "report.json"
    argv = [
        "compose",
        str(workdir / "song.wav"),
        "--library",
        str(workdir / "lib" / "clip0.bvh"),
        str(workdir / "lib" / "clip1.bvh"),
        "--beats",
        str(workdir / "song.beats"),
        "-o",
        str(out),
        "--report",
        str(rep),
    ]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "transition" in text and "search (dp)" in text
    m = io.read_bvh(out)
    src = io.read_bvh(workdir / "lib" / "clip0.bvh")
    assert m.channels == src.channels
    report = json.loads(rep.read_text())
    beats = io.read_beats(workdir / "song.beats")
    assert report["n_music_beats"] == beats.size
    assert report["graph_cached"] is False
    # one graph node per music beat interval, every one an interval start
    path = np.asarray(report["path"])
    assert path.shape == (beats.size - 1,)
    assert report["graph"]["n_transitions"] > 0
    # two 6 s clips cannot cover the song without jumping: the path uses transitions,
    # exactly where consecutive path nodes are not consecutive beats of one clip
    assert report["n_transitions"] == int(np.sum(np.diff(path) != 1)) > 0
    assert len(report["transition_times_s"]) == report["n_transitions"]
    assert report["search_time_s"] > 0 and report["graph_build_time_s"] > 0
    assert m.n_frames == int(np.floor(6.0 * m.fps)) + 1  # lasts as long as the song
    assert report["n_frames"] == m.n_frames
    assert report["duration_s"] == pytest.approx(6.0)  # frame j at j / fps: the song's end
    cache = list((workdir / "cache").glob("graph-*.npz"))
    assert len(cache) == 1
    # second run: the graph comes from the cache, the result is the same
    out2 = workdir / "dance2.bvh"
    argv2 = [a if a != str(out) else str(out2) for a in argv if a not in ("--report", str(rep))]
    assert main([*argv2, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["graph_cached"] is True
    np.testing.assert_allclose(io.read_bvh(out2).values, m.values, atol=1e-4)
    # audio after --library is understood, folders are libraries
    out3 = workdir / "dance3.bvh"
    assert (
        main(
            [
                "compose",
                "--library",
                str(workdir / "lib"),
                str(workdir / "song.wav"),
                "--bpm",
                "110",
                "-o",
                str(out3),
                "--json",
            ]
        )
        == 0
    )
    res3 = json.loads(capsys.readouterr().out)
    assert res3["tempo_bpm"] == pytest.approx(110, rel=0.05)
    assert out3.is_file()


def test_compose_warns_when_the_beats_given_stop_long_before_the_song(workdir, capsys):
    # the dance then holds its last pose: the beats of part of the song, or of another one
    short = workdir / "short.beats"
    io.write_beats(short, io.read_beats(workdir / "song.beats")[:4])
    argv = ["compose", str(workdir / "song.wav"), "--library", str(workdir / "lib"),
            "--beats", str(short), "-o", str(workdir / "d.bvh"), "--json"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr()
    assert "warning: the beats of" in out.err and "holds its last pose" in out.err
    assert any("holds its last pose" in w for w in json.loads(out.out)["warnings"])
    argv[argv.index(str(short))] = str(workdir / "song.beats")  # the whole song's: quiet
    assert main(argv) == 0 and "warning" not in capsys.readouterr().err


def test_cache_key_changes_with_content_and_params(workdir):
    from beatsync.graph.cache import graph_cache_key

    files = sorted((workdir / "lib").glob("*.bvh"))
    k1 = graph_cache_key(files, {"th": 3.0})
    assert graph_cache_key(files, {"th": 2.0}) != k1
    assert graph_cache_key(files[::-1], {"th": 3.0}) != k1
    m, _ = synthetic_dance(duration=6.0, bpm=110.0, seed=5)
    io.write_bvh(files[0], m)
    assert graph_cache_key(files, {"th": 3.0}) != k1


def test_cache_key_changes_with_graph_code(workdir, monkeypatch, tmp_path):
    # an editable install keeps __version__ when build_graph changes: the key must not
    from beatsync import motion_beats
    from beatsync.graph import build
    from beatsync.graph import cache as cmd

    files = sorted((workdir / "lib").glob("*.bvh"))
    k1 = cmd.graph_cache_key(files, {"th": 3.0})
    for module in (build, motion_beats):
        edited = tmp_path / f"edited_{module.__name__.rsplit('.', 1)[-1]}.py"
        edited.write_bytes(Path(module.__file__).read_bytes() + b"\n# changed\n")
        with monkeypatch.context() as mp:
            mp.setattr(module, "__file__", str(edited))
            assert cmd.graph_cache_key(files, {"th": 3.0}) != k1
    assert cmd.graph_cache_key(files, {"th": 3.0}) == k1


def test_stale_cache_entry_is_not_served(workdir, monkeypatch, capsys):
    from beatsync.graph import cache as cmd

    argv = [
        "compose",
        str(workdir / "song.wav"),
        "--library",
        str(workdir / "lib"),
        "--beats",
        str(workdir / "song.beats"),
        "-o",
        str(workdir / "a.bvh"),
        "--json",
    ]
    assert main(argv) == 0
    first = json.loads(capsys.readouterr().out)
    assert Path(first["graph_cache_file"]).parent == workdir / "cache"
    # the graph code changed (simulated): the old entry must not be used
    monkeypatch.setattr(cmd, "graph_source_hash", lambda: "0" * 64)
    assert main(argv) == 0
    second = json.loads(capsys.readouterr().out)
    assert second["graph_cached"] is False
    assert second["graph_cache_file"] != first["graph_cache_file"]
    assert len(list((workdir / "cache").glob("graph-*.npz"))) == 2
    # --no-cache neither reads nor writes
    assert main([*argv, "--no-cache"]) == 0
    third = json.loads(capsys.readouterr().out)
    assert third["graph_cached"] is False and third["graph_cache_file"] is None
    assert len(list((workdir / "cache").glob("graph-*.npz"))) == 2


def test_help_names_the_cache(capsys):
    with pytest.raises(SystemExit):
        main(["compose", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "BEATSYNC_CACHE_DIR" in out and "--no-cache" in out and "~/.cache/beatsync" in out


def _odd_clip(path):
    m, _ = synthetic_dance(duration=6.0, bpm=110.0, seed=2)
    joints = list(m.skeleton.joints)
    j = joints[1]
    joints[1] = Joint("torso", j.parent, j.offset, j.channels, j.is_end_site)
    sk = Skeleton(tuple(joints))
    io.write_bvh(path, Motion(m.values, m.fps, sk.channel_names(), sk, "odd"))


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("th0", "--th"),
        ("th_tiny", "TH=1e-09"),
        ("skeletons", "'torso'"),
        ("empty_folder", "no .bvh"),
        ("silent", "silent"),
        ("one_beat", "1 beat(s)"),
        ("missing_clip", "nope.bvh"),
        ("tempo_neg", "--tempo-weight"),
        ("not_bvh_out", "dance.csv"),
        ("range_with_beats", "--min-bpm"),
        ("range_reversed", "--min-bpm 150"),
        ("song_folder", "is not a file"),
        ("empty_beats", "is empty"),
    ],
)
def test_bad_inputs_write_nothing(workdir, capsys, case, message):
    lib = [str(workdir / "lib" / "clip0.bvh"), str(workdir / "lib" / "clip1.bvh")]
    song = str(workdir / "song.wav")
    extra: list[str] = ["--beats", str(workdir / "song.beats")]
    if case == "th0":
        extra += ["--th", "0"]
    elif case == "th_tiny":
        extra += ["--th", "1e-9"]
    elif case == "skeletons":
        _odd_clip(workdir / "odd.bvh")
        lib.append(str(workdir / "odd.bvh"))
    elif case == "empty_folder":
        (workdir / "empty").mkdir()
        lib = [str(workdir / "empty")]
    elif case == "silent":
        io.write_audio(workdir / "silence.wav", np.zeros(22050 * 3, dtype=np.float32), 22050)
        song = str(workdir / "silence.wav")
        extra = []
    elif case == "one_beat":
        io.write_beats(workdir / "one.beats", np.array([0.5]))
        extra = ["--beats", str(workdir / "one.beats")]
    elif case == "missing_clip":
        lib.append(str(workdir / "nope.bvh"))
    elif case == "tempo_neg":
        extra += ["--tempo-weight", "-1"]
    elif case == "range_with_beats":
        extra += ["--min-bpm", "60"]
    elif case == "range_reversed":
        extra = ["--min-bpm", "150", "--max-bpm", "100"]
    elif case == "song_folder":
        (workdir / "a_song").mkdir()
        song = str(workdir / "a_song")
    elif case == "empty_beats":
        (workdir / "empty.beats").write_text("")
        extra = ["--beats", str(workdir / "empty.beats")]
    before = _outputs(workdir)
    out = workdir / ("dance.csv" if case == "not_bvh_out" else "dance.bvh")
    argv = [
        "compose",
        song,
        "--library",
        *lib,
        "-o",
        str(out),
        "--report",
        str(workdir / "r.json"),
        *extra,
    ]
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err
    assert _outputs(workdir) == before
    assert not out.exists()


@pytest.mark.parametrize("method", ["conventional", "random"])
def test_compose_other_methods(workdir, capsys, method):
    out = workdir / f"{method}.bvh"
    argv = [
        "compose",
        str(workdir / "song.wav"),
        "--library",
        str(workdir / "lib"),
        "--beats",
        str(workdir / "song.beats"),
        "--method",
        method,
        "-o",
        str(out),
        "--json",
    ]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == method
    assert io.read_bvh(out).n_frames == res["n_frames"]
