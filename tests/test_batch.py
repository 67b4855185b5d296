"""The Dask study runner: every clip x song, errors recorded per pair."""

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.batch import sync_grid
from beatsync.cli import main
from beatsync.errors import ParameterError


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    import librosa

    d = tmp_path_factory.mktemp("batch")
    salsa = datasets.load_salsa("60_01")
    io.write_bvh(d / "salsa.bvh", salsa.rename("salsa"))
    io.write_bvh(d / "pirouette.bvh", datasets.load_walk("005_02"))
    sr = 22050
    songs = []
    for bpm in (100, 125):
        beats = np.arange(0.5, 30.0, 60.0 / bpm)
        y = librosa.clicks(times=beats, sr=sr, length=30 * sr)
        songs.append(io.write_audio(d / f"click{bpm}.wav", y, sr))
    return d, [d / "salsa.bvh", d / "pirouette.bvh"], songs


def test_grid_syncs_periodic_clip_and_records_errors(inputs, tmp_path):
    _, clips, songs = inputs
    table = sync_grid(clips, songs, tmp_path, processes=False, n_workers=2, fps=60.0)
    assert len(table) == 4
    ok = table[table["status"] == "ok"]
    assert sorted(ok["clip"]) == ["salsa", "salsa"]
    for _, row in ok.iterrows():
        back = io.read_bvh(row["output"])
        assert back.n_frames == row["output_frames"]
        assert row["max_abs_residual_ms"] <= 1000.0 / 60.0
    bad = table[table["clip"] == "pirouette"]
    assert (bad["status"] == "error").all()
    assert bad["error"].str.contains("periodic").all()


def test_grid_bad_arguments(inputs, tmp_path):
    _, clips, songs = inputs
    with pytest.raises(ParameterError, match="does not exist"):
        sync_grid([tmp_path / "none.bvh"], songs, tmp_path)
    with pytest.raises(ParameterError, match="output folder"):
        sync_grid(clips, songs, tmp_path / "missing")
    with pytest.raises(ParameterError, match="at least one"):
        sync_grid([], songs, tmp_path)


def test_batch_cli_writes_summary(inputs, tmp_path, capsys):
    _, clips, songs = inputs
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
            "--workers",
            "1",
            "--json",
        ]
    )
    assert code == 0
    assert (tmp_path / "summary.csv").is_file()
    assert (tmp_path / "salsa__click100.bvh").is_file()


def test_batch_refuses_to_overwrite_inputs(inputs, tmp_path):
    _, clips, songs = inputs
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
    d, clips, songs = inputs
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    twins = [tmp_path / "a" / "song.wav", tmp_path / "b" / "song.wav"]
    for t in twins:
        t.write_bytes(songs[0].read_bytes())
    with pytest.raises(ParameterError, match="song file names must differ"):
        sync_grid(clips[:1], twins, tmp_path)
