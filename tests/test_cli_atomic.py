"""Commands that write several files write all of them or none.

A later output failing (disk full, ffmpeg failing), Ctrl-C or SIGTERM leaves every
output path as it was and no temporary file or folder behind.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.cli import main
from beatsync.errors import ParameterError
from beatsync.synth.audio import beat_times, click_track

SR = 22050
SRC = str(Path(__file__).resolve().parents[1] / "src")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """An exactly periodic 8 s salsa clip (one real 1 s step tiled) and a 10 s song."""
    d = tmp_path_factory.mktemp("atomic")
    real = datasets.load_salsa("60_01")
    step = real.values[60:120].copy()
    step[:, :3] = step[0, :3]
    clip = io.write_bvh(d / "salsa.bvh", real.with_values(np.tile(step, (8, 1))).rename("salsa"))
    beats = beat_times(120, duration=10.0, start=0.5)
    song = io.write_audio(d / "song.wav", click_track(beats, sr=SR, duration=10.0), SR)
    return {"clip": clip, "song": song}


def _listing(d: Path) -> list[str]:
    return sorted(str(p.relative_to(d)) for p in d.rglob("*"))


def _disk_full(*args, **kwargs):
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize(
    "argv, failing",
    [
        (["beats", "{song}", "--out", "{o}/a.beats", "--click", "{o}/b.wav"], "write_audio"),
        (["sync", "{clip}", "{song}", "-o", "{o}/a.bvh", "--report", "{o}/r.json"], "write_json"),
        (["segment", "{clip}", "--out", "{o}/a.csv"], "write_csv"),
    ],
    ids=["beats --click", "sync --report", "segment --out"],
)
def test_a_later_output_failing_leaves_nothing_behind(
    argv, failing, inputs, tmp_path, capsys, monkeypatch
):
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.beats").write_text("an earlier result\n")  # replaced only on success
    before = {p: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(io, failing, _disk_full)
    argv = [a.format(o=out, **inputs) for a in argv]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 4, err
    assert "No space left on device" in err and "no output was written" in err
    assert "Traceback" not in err
    assert {p: p.read_bytes() for p in out.iterdir()} == before  # no new file, none changed


@pytest.mark.slow
def test_compose_video_failing_leaves_no_motion(inputs, tmp_path, capsys, monkeypatch):
    from beatsync import render

    def ffmpeg_fails(*args, **kwargs):
        raise ParameterError("ffmpeg failed (exit 1) writing the video")

    monkeypatch.setattr(render, "write_video", ffmpeg_fails)
    out = tmp_path / "out"
    out.mkdir()
    argv = ["compose", str(inputs["song"]), "--library", str(inputs["clip"]), "--no-cache",
            "-o", str(out / "dance.bvh"), "--video", str(out / "dance.mp4")]  # fmt: skip
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 3 and "ffmpeg failed" in err, err
    assert _listing(out) == []


def test_without_ffmpeg_the_gif_and_wav_take_the_videos_place(inputs, tmp_path, monkeypatch):
    from beatsync import render

    def gif_and_wav(motion, path, **kwargs):  # what write_video writes without ffmpeg
        path.with_suffix(".wav").write_bytes(b"RIFF")
        path.with_suffix(".gif").write_bytes(b"GIF89a")
        return path.with_suffix(".gif")

    monkeypatch.setattr(render, "write_video", gif_and_wav)
    out = tmp_path / "out"
    out.mkdir()
    argv = ["sync", str(inputs["clip"]), str(inputs["song"]), "-o", str(out / "d.bvh"),
            "--report", str(out / "r.json"), "--video", str(out / "d.mp4"), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert _listing(out) == ["d.bvh", "d.gif", "d.wav", "r.json"]
    assert json.loads((out / "r.json").read_text())["outputs"]["video"] == str(out / "d.gif")


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_during_video_leaves_no_temporary_folder(inputs, tmp_path, sig):
    out = tmp_path / "out"
    out.mkdir()
    env = {**os.environ, "PYTHONPATH": SRC}
    argv = ["sync", str(inputs["clip"]), str(inputs["song"]), "-o", str(out / "d.bvh"),
            "--report", str(out / "r.json"), "--video", str(out / "d.mp4"),
            "--video-fps", "60"]  # fmt: skip
    proc = subprocess.Popen(
        [sys.executable, "-m", "beatsync.cli", *argv], stderr=subprocess.PIPE, text=True, env=env
    )
    deadline = time.monotonic() + 120
    while not any(".beatsync-video-" in p for p in _listing(out)):  # the video is being made
        assert proc.poll() is None and time.monotonic() < deadline, proc.stderr.read()
        time.sleep(0.02)
    proc.send_signal(sig)
    err = proc.communicate(timeout=60)[1]
    assert proc.returncode == 128 + sig, err
    assert err.rstrip().endswith(f"interrupted by {sig.name}; no output was written"), err
    assert _listing(out) == []


@pytest.mark.slow
def test_batch_summary_failing_leaves_no_clip(inputs, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    tables = []

    def summary_fails(path, table, **kwargs):
        tables.append(table)
        _disk_full()

    monkeypatch.setattr(io, "write_csv", summary_fails)
    argv = ["batch", "--clips", str(inputs["clip"]), "--songs", str(inputs["song"]),
            "--out-dir", str(out), "--workers", "1"]  # fmt: skip
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 4 and "No space left on device" in err, err
    assert list(tables[0]["status"]) == ["ok"]  # the clip was synchronised...
    assert _listing(out) == []  # ...staged, then removed with the staging folder


@pytest.mark.slow
@pytest.mark.parametrize("ffmpeg", [True, False], ids=["mp4", "no ffmpeg: gif + wav"])
def test_outputs_land_at_their_names(ffmpeg, inputs, tmp_path, capsys, monkeypatch):
    import json

    from beatsync import render

    if not ffmpeg:
        monkeypatch.setattr(render, "find_ffmpeg", lambda: None)
    out = tmp_path / "out"
    out.mkdir()
    argv = ["sync", str(inputs["clip"]), str(inputs["song"]), "-o", str(out / "d.bvh"),
            "--report", str(out / "r.json"), "--video", str(out / "d.mp4"),
            "--video-fps", "10", "--json"]  # fmt: skip
    code = main(argv)
    cap = capsys.readouterr()
    assert code == 0, cap.err
    res = json.loads(cap.out)
    video = out / ("d.mp4" if ffmpeg else "d.gif")
    assert res["outputs"] == {
        "video": str(video),
        "motion": str(out / "d.bvh"),
        "report": str(out / "r.json"),
    }
    assert json.loads((out / "r.json").read_text())["outputs"]["video"] == str(video)
    expected = ["d.bvh", "d.mp4", "r.json"] if ffmpeg else ["d.bvh", "d.gif", "d.wav", "r.json"]
    assert _listing(out) == expected  # no staging folder left
