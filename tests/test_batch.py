"""The Dask study runner: every clip x song, errors recorded per pair."""

import json
import time

import numpy as np
import pandas as pd
import pytest

from beatsync import datasets, io
from beatsync.cli import main
from beatsync.errors import NotPeriodicError, ParameterError
from beatsync.sync_grid import prepare_clip, sync_grid
from beatsync.synth.audio import beat_times, click_track

SR = 22050


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("batch")
    # 12 s of salsa made exactly periodic: one 1 s step of 60_01 repeated (root held),
    # so segmentation is fast and certain; the skeleton and the step are real
    real = datasets.load_salsa("60_01")
    step = real.values[60:120].copy()
    step[:, :3] = step[0, :3]
    io.write_bvh(d / "salsa.bvh", real.with_values(np.tile(step, (12, 1))).rename("salsa"))
    io.write_bvh(d / "pirouette.bvh", datasets.load_walk("005_02"))  # 9 s, not periodic
    songs = []
    for bpm in (100, 125, 80):  # at 80 BPM the salsa's 1 s steps play x1.33: a warning
        beats = beat_times(bpm, duration=14.0, start=0.5)
        songs.append(
            io.write_audio(d / f"click{bpm}.wav", click_track(beats, sr=SR, duration=14.0), SR)
        )
    return d, [d / "salsa.bvh", d / "pirouette.bvh"], songs[:2], songs[2]


def test_grid_syncs_periodic_clip_and_records_errors(inputs, tmp_path):
    _, clips, songs, _ = inputs
    table = sync_grid(clips, songs, tmp_path, processes=False, n_workers=2, fps=60.0,
                      mode="periods")  # fmt: skip
    assert len(table) == 4
    ok = table[table["status"] == "ok"]
    assert sorted(ok["clip"]) == ["salsa", "salsa"]
    for _, row in ok.iterrows():
        back = io.read_bvh(row["output"])
        assert back.n_frames == row["output_frames"]
        assert (back.n_frames - 1) / 60.0 >= 14.0 - 1e-9  # danced to the song's end
        assert row["max_abs_residual_ms"] <= 1000.0 / 60.0
    bad = table[table["clip"] == "pirouette"]
    assert (bad["status"] == "error").all()
    assert bad["error"].str.contains("periodic").all()
    assert bad["error"].str.contains("--mode beats").all()  # what syncs a free dance


def test_grid_mode_auto_uses_the_motion_beats_of_a_clip_that_is_not_periodic(inputs, tmp_path):
    _, clips, songs, _ = inputs
    table = sync_grid(clips, songs[:1], tmp_path, processes=False, n_workers=2, fps=60.0,
                      mode="auto")  # fmt: skip
    assert (table["status"] == "ok").all()
    row = table.set_index("clip")
    assert row.loc["salsa", "mode"] == "periods" and row.loc["salsa", "note"] == ""
    assert row.loc["pirouette", "mode"] == "beats"
    assert "not periodic" in row.loc["pirouette", "note"]
    assert (
        io.read_bvh(row.loc["pirouette", "output"]).n_frames
        == row.loc["pirouette", "output_frames"]
    )


@pytest.mark.parametrize("mode", ["periods", "auto"])
def test_a_bad_setting_is_the_clips_error_not_a_free_dance(inputs, mode):
    # neither the hint that --mode beats syncs it nor mode auto's fallback to the motion
    # beats: those are for a dance that is not periodic
    _, clips, _, _ = inputs
    with pytest.raises(ParameterError, match="alpha") as err:
        prepare_clip(str(clips[0]), fps=60.0, alpha=0.7, mode=mode)
    assert not isinstance(err.value, NotPeriodicError)
    assert "--mode beats" not in str(err.value)


@pytest.mark.parametrize(
    "kwargs,match",
    [({"period_range": (1.25, 0.25)}, "period_range"), ({"alpha": 10}, "alpha"),
     ({"fps": 44100.0}, "fps")],
)  # fmt: skip
def test_grid_refuses_a_bad_shared_setting_before_any_work(inputs, tmp_path, kwargs, match):
    _, clips, songs, _ = inputs
    with pytest.raises(ParameterError, match=match):
        sync_grid(clips, songs, tmp_path, processes=False, n_workers=1, mode="auto", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_grid_tempo_range_reaches_every_song(inputs, tmp_path):
    # click tracks at 100 and 125 BPM, searched at 40-70 BPM: every other click
    _, clips, songs, _ = inputs
    table = sync_grid(clips[:1], songs, tmp_path, processes=False, n_workers=1, fps=60.0,
                      min_bpm=40, max_bpm=70)  # fmt: skip
    assert (table["status"] == "ok").all()
    np.testing.assert_allclose(sorted(table["tempo_bpm"]), [50.0, 62.5], rtol=0.03)


def test_grid_bad_arguments(inputs, tmp_path):
    _, clips, songs, _ = inputs
    with pytest.raises(ParameterError, match="none.bvh"):
        sync_grid([tmp_path / "none.bvh"], songs, tmp_path)
    with pytest.raises(ParameterError, match="missing"):
        sync_grid(clips, songs, tmp_path / "missing")
    with pytest.raises(ParameterError, match="one clip"):
        sync_grid([], songs, tmp_path)
    with pytest.raises(ParameterError, match="mode='bars'"):
        sync_grid(clips, songs, tmp_path, mode="bars")


def test_batch_cli_writes_summary(inputs, scheduler, tmp_path, capsys):
    _, clips, songs, _ = inputs
    code = main(
        [
            "batch",
            "--clips",
            str(clips[0]),
            "--songs",
            str(songs[0]),
            "--out-dir",
            str(tmp_path),
            "--fps",
            "60",
            "--scheduler",
            scheduler,
            "--json",
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert (tmp_path / "summary.csv").is_file()
    assert (tmp_path / "salsa__click100.bvh").is_file()


def test_batch_refuses_to_overwrite_inputs(inputs, tmp_path):
    _, clips, songs, _ = inputs
    before = songs[0].read_bytes()
    code = main(
        [
            "batch",
            "--clips",
            str(clips[0]),
            "--songs",
            str(songs[0]),
            "--out-dir",
            str(tmp_path),
            "--summary",
            str(songs[0]),
        ]
    )
    assert code == 3
    assert songs[0].read_bytes() == before


def test_batch_refuses_duplicate_song_names(inputs, tmp_path):
    d, clips, songs, _ = inputs
    twins = [tmp_path / "a" / "take" / "song.wav", tmp_path / "b" / "take" / "song.wav"]
    for t in twins:  # the same file name in folders of the same name: nothing tells them apart
        t.parent.mkdir(parents=True)
        t.write_bytes(songs[0].read_bytes())
    with pytest.raises(ParameterError, match=r"\['take'\]"):
        sync_grid(clips[:1], twins, tmp_path)


def test_batch_defaults_are_those_of_sync():
    import inspect

    from beatsync.cli import build_parser

    parser = build_parser()
    batch = parser.parse_args(["batch", "--clips", "a.bvh", "--songs", "s.wav", "--out-dir", "o"])
    sync = parser.parse_args(["sync", "a.bvh", "s.wav", "-o", "o.bvh"])
    assert batch.mode == sync.mode == "auto"
    assert inspect.signature(sync_grid).parameters["mode"].default == "auto"


def _takes(tmp_path):
    """Two real dancers laid out one folder per take (DANCE_C_4/skeletons.json, ...) and
    a 10 s song."""
    clips = []
    for take in ("DANCE_C_4", "DANCE_R_3"):
        (tmp_path / take).mkdir()
        clips.append(tmp_path / take / "skeletons.json")
        src = datasets.path(f"motion/dance_with_melody/{take}/skeletons.json")
        clips[-1].write_bytes(src.read_bytes())
    song = io.write_audio(
        tmp_path / "song.wav",
        click_track(beat_times(100, duration=10.0, start=0.5), sr=SR, duration=10.0), SR,
    )  # fmt: skip
    out = tmp_path / "out"
    out.mkdir()
    return clips, song, out


def test_grid_names_one_folder_per_take_by_its_folder(tmp_path):
    clips, song, out = _takes(tmp_path)
    table = sync_grid(clips, [song], out, processes=False, n_workers=1, fps=25.0)
    assert sorted(table["clip"]) == ["DANCE_C_4", "DANCE_R_3"]
    assert (table["status"] == "ok").all(), table["error"].tolist()
    assert (table["mode"] == "beats").all()  # defaults of sync: auto falls back to motion beats
    for take in ("DANCE_C_4", "DANCE_R_3"):
        assert (out / f"{take}__song.json").is_file()


def test_batch_cli_takes_one_folder_per_take(tmp_path, scheduler, capsys):
    clips, song, out = _takes(tmp_path)
    argv = ["batch", "--clips", *map(str, clips), "--songs", str(song), "--out-dir", str(out),
            "--fps", "25", "--scheduler", scheduler]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.glob("*.json")) == [
        "DANCE_C_4__song.json", "DANCE_R_3__song.json"
    ]  # fmt: skip


def _batch_args(inputs, out, *extra):
    _, clips, songs, _ = inputs
    return [
        "batch",
        "--clips",
        str(clips[0]),
        "--songs",
        str(songs[0]),
        "--out-dir",
        str(out),
        *extra,
    ]


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--workers", "-1"], "--workers=-1"),
        (["--workers", "0"], "--workers=0"),
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "--workers 2"),
        (["--scheduler", "tcp://127.0.0.1:9"], "127.0.0.1:9'"),
        (["--scheduler", "nonsense"], "'nonsense'"),
        # the tempo options are checked before the cluster starts
        (["--bpm", "100", "--max-bpm", "80"], "--max-bpm.*--bpm"),
        (["--min-bpm", "90", "--max-bpm", "60"], "--min-bpm 90"),
    ],
)
def test_batch_bad_cluster_options_fail_fast(inputs, tmp_path, monkeypatch, extra, match):
    """Once: --workers -1 hung forever; an unreachable scheduler waited 30 s, then a traceback."""
    from beatsync import cluster
    from beatsync.cli import build_parser

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    args = build_parser().parse_args(_batch_args(inputs, tmp_path, *extra))
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=match):
        args.func(args)
    assert time.perf_counter() - t0 < 10.0
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_batch_cli_bad_cluster_option_exit_code(inputs, tmp_path, capsys):
    code = main(_batch_args(inputs, tmp_path, "--workers", "-1"))
    assert code == 3  # a well-formed number that cannot be used: bad input
    assert "--workers=-1 must be a whole number of workers >= 1" in capsys.readouterr().err


def test_batch_writes_all_or_nothing(inputs, scheduler, tmp_path, monkeypatch, capsys):
    """A failure after the pairs were synchronised (here: writing the summary) leaves
    the output folder as it was: no pair's BVH behind, no staging folder."""
    from beatsync.io import _files

    (tmp_path / "keep.txt").write_text("before")

    def fail(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(_files, "write_csv", fail)
    monkeypatch.setattr(io, "write_csv", fail)
    code = main(_batch_args(inputs, tmp_path, "--fps", "60", "--scheduler", scheduler))
    assert code == 4, capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]


def test_grid_writes_joint_positions_back_in_the_inputs_layout(inputs, tmp_path):
    # a real dancer (Dance-with-Melody JSON, cm, y up) and the same dancer as an
    # (n_frames, n_joints, 3) .npy: each pair is written as the clip came in, as
    # `beatsync sync` keeps it, not as a CSV table of metres, z up
    _, _, songs, _ = inputs
    src = datasets.path("motion/dance_with_melody/DANCE_W_5/skeletons.json")
    clips = tmp_path / "clips"
    clips.mkdir()
    (clips / "dancer.json").write_bytes(src.read_bytes())
    dancer = io.read_motion(clips / "dancer.json", fps=25.0)
    io.write_motion(clips / "dancer_array.npy", dancer)
    out = tmp_path / "out"
    out.mkdir()
    table = sync_grid([clips / "dancer.json", clips / "dancer_array.npy"], songs[:1], out,
                      processes=False, n_workers=1, fps=25.0, mode="beats")  # fmt: skip
    assert (table["status"] == "ok").all(), table["error"].tolist()
    rows = table.set_index("clip")
    assert rows.loc["dancer", "output"].endswith("dancer__click100.json")
    assert rows.loc["dancer_array", "output"].endswith("dancer_array__click100.npy")
    for name in ("dancer", "dancer_array"):
        back = io.read_motion(rows.loc[name, "output"], fps=25.0)
        assert back.n_frames == rows.loc[name, "output_frames"] != dancer.n_frames
        assert back.channels == dancer.channels
        info = back.position_info
        assert (info.units, info.up) == (dancer.position_info.units, dancer.position_info.up)
    layout = json.loads((out / "dancer__click100.json").read_text())
    assert {"skeletons", "center"} <= set(layout)  # the dataset's own keys


@pytest.mark.parametrize("cli", [True, False])
def test_batch_refuses_a_positions_output_that_is_an_input(inputs, tmp_path, cli):
    # dancer x click100 would be written as dancer__click100.json: here an input clip
    _, _, songs, _ = inputs
    src = datasets.path("motion/dance_with_melody/DANCE_W_5/skeletons.json")
    clips = [tmp_path / "dancer.json", tmp_path / "dancer__click100.json"]
    for c in clips:
        c.write_bytes(src.read_bytes())
    before = clips[1].read_bytes()
    if cli:
        argv = ["batch", "--clips", *map(str, clips), "--songs", str(songs[0]),
                "--out-dir", str(tmp_path), "--fps", "25", "--mode", "beats"]  # fmt: skip
        assert main(argv) == 3
    else:
        with pytest.raises(ParameterError, match="dancer__click100.json"):
            sync_grid(clips, songs[:1], tmp_path, processes=False, n_workers=1, fps=25.0)
    assert clips[1].read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(c.name for c in clips)


def test_batch_text_gives_a_line_per_pair_and_its_note_or_error(inputs, scheduler, tmp_path,
                                                                 capsys):  # fmt: skip
    # as one table, the notes of real dancers made lines of several hundred characters
    _, clips, songs, _ = inputs
    argv = ["batch", "--clips", *map(str, clips), "--songs", str(songs[0]), "--out-dir",
            str(tmp_path), "--fps", "60", "--scheduler", scheduler,
            "--mode", "periods"]  # fmt: skip
    assert main(argv) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("salsa x click100: periods, ")
    assert "frames, largest residual" in lines[0]
    assert lines[0].endswith(str(tmp_path / "salsa__click100.bvh"))
    assert lines[1].startswith("pirouette x click100: error: ") and "--mode beats" in lines[1]
    assert lines[2] == f"1/2 pairs synchronised; {tmp_path / 'summary.csv'}"
    assert len(lines) == 3


def test_batch_refuses_a_summary_named_like_a_pairs_output(inputs, tmp_path, capsys):
    # it was written over the synchronised pair, and the command exited 0
    _, clips, songs, _ = inputs
    pair = str(tmp_path / "salsa__click100.csv")  # the name a table's pair would take
    argv = ["batch", "--clips", str(clips[0]), "--songs", str(songs[0]), "--out-dir",
            str(tmp_path), "--fps", "60", "--summary", pair]  # fmt: skip
    assert main(argv) == 3
    assert "give the summary another name" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_batch_refuses_a_summary_that_is_not_csv(inputs, tmp_path, capsys):
    _, clips, songs, _ = inputs
    argv = ["batch", "--clips", str(clips[0]), "--songs", str(songs[0]), "--out-dir",
            str(tmp_path), "--fps", "60", "--summary", str(tmp_path / "sum.mp4")]  # fmt: skip
    assert main(argv) == 3
    assert "must end in .csv" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_batch_keeps_each_pairs_warnings_with_it(inputs, scheduler, tmp_path, capsys):
    # they were printed raw by the worker (file, line and class) and lost from the summary
    _, clips, _, slow = inputs
    argv = ["batch", "--clips", str(clips[0]), "--songs", str(slow), "--out-dir",
            str(tmp_path), "--fps", "60", "--scheduler", scheduler,
            "--mode", "periods"]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "beatsync batch: warning: salsa x click80: the dance plays within x0.8-x1.25" in err
    assert "BeatsyncWarning" not in err and ".py:" not in err
    row = pd.read_csv(tmp_path / "summary.csv").iloc[0]
    assert "a song at about 60 BPM" in row["warnings"] and row["mean_period_s"] > 0


def test_outputs_adopt_never_takes_another_options_file(tmp_path):
    from beatsync.commands._common import Outputs

    with pytest.raises(ParameterError, match="a.csv"):
        with Outputs(inputs=[]) as outs:
            folder = outs.add_folder(tmp_path, option="--out-dir")
            outs.add(folder / "a.csv", option="--summary")
            staged = outs.staging_folder(folder) / "a.csv"
            staged.write_text("pair")
            outs.adopt(staged, option="--out-dir")
    assert list(tmp_path.iterdir()) == []  # rolled back


def test_batch_variable_picks_the_recording_of_a_mat_file(inputs, tmp_path, capsys):
    # the toolbox's demo file holds several recordings: batch named --variable without having it
    _, _, songs, _ = inputs
    mat = datasets.path("motion/mocaptoolbox/mcdemodata.mat")
    argv = ["batch", "--clips", str(mat), "--songs", str(songs[0]), "--out-dir", str(tmp_path),
            "--variable", "dance2", "--mode", "beats", "--workers", "1", "--json"]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    row = json.loads(capsys.readouterr().out)["rows"][0]
    assert row["status"] == "ok" and row["output"].endswith("mcdemodata__click100.csv")
