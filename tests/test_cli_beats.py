"""End-to-end tests of ``beatsync beats``."""

import json

import numpy as np
import pytest

from beatsync import io
from beatsync.cli import main
from beatsync.evaluate.beats import evaluate
from beatsync.synth.audio import beat_times, click_track

SR = 22050


@pytest.fixture
def song(tmp_path):
    ref = beat_times(120, duration=10.0, start=0.3)
    path = tmp_path / "song.wav"
    io.write_audio(path, click_track(ref, sr=SR, duration=10.0), SR)
    return path, ref


def test_prints_beats(song, capsys):
    path, ref = song
    assert main(["beats", str(path)]) == 0
    est = np.array([float(x) for x in capsys.readouterr().out.split()])
    assert evaluate(ref, est, min_beat_time=0.0)["F-measure"] >= 0.95


def test_json_out_and_click(song, tmp_path, capsys):
    path, ref = song
    out = tmp_path / "song.beats"
    click = tmp_path / "click.wav"
    rc = main(["beats", str(path), "--json", "--out", str(out), "--click", str(click)])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["tempo_bpm"] == pytest.approx(120, rel=0.02)
    assert res["n_beats"] == len(res["beats"])
    np.testing.assert_allclose(io.read_beats(out), res["beats"], atol=1e-6)
    y, sr = io.read_audio(click)
    assert sr == SR and y.size == 10 * SR


def test_tempo_range_help_states_the_trackers_defaults(capsys):
    # the option help is written without importing the tracker (start-up stays light)
    from beatsync.beats.tracker import DEFAULT_MAX_BPM, DEFAULT_MIN_BPM

    for command in ("beats", "sync", "compose", "batch"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert f"(default {DEFAULT_MIN_BPM:g})" in text
        assert f"(default {DEFAULT_MAX_BPM:g})" in text


def test_librosa_and_bpm_options(song, capsys):
    path, ref = song
    assert main(["beats", str(path), "--method", "librosa", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == "librosa"
    assert evaluate(ref, res["beats"], min_beat_time=0.0)["F-measure"] >= 0.9
    assert main(["beats", str(path), "--bpm", "60", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert np.median(np.diff(res["beats"])) == pytest.approx(1.0, rel=0.02)
    # every reference beat at 120 BPM is tapped, every other one at 60 BPM
    assert evaluate(ref[::2], res["beats"], min_beat_time=0.0)["F-measure"] >= 0.9 or (
        evaluate(ref[1::2], res["beats"], min_beat_time=0.0)["F-measure"] >= 0.9
    )


def _bad_cases(tmp_path):
    silent = tmp_path / "silent.wav"
    io.write_audio(silent, np.zeros(SR, dtype=np.float32), SR)
    empty = tmp_path / "empty.wav"
    empty.write_bytes(b"")
    text = tmp_path / "notaudio.wav"
    text.write_text("hello")
    short = tmp_path / "short.wav"  # 0.5 s of clicks: shorter than 1.5 s
    io.write_audio(
        short, click_track(beat_times(120, duration=0.5, start=0.1), sr=SR, duration=0.5), SR
    )
    return {
        "short": ["beats", str(short)],
        "missing": ["beats", str(tmp_path / "nope.wav")],
        "empty": ["beats", str(empty)],
        "notaudio": ["beats", str(text)],
        "silent": ["beats", str(silent)],
        "range": ["beats", "{song}", "--min-bpm", "150", "--max-bpm", "100"],
        "range_with_bpm": ["beats", "{song}", "--bpm", "120", "--max-bpm", "100"],
        "bpm_low": ["beats", "{song}", "--bpm", "2"],
        "bpm_high": ["beats", "{song}", "--bpm", "900"],
        "overwrite": ["beats", "{song}", "--click", "{song}"],
        "no_folder": ["beats", "{song}", "--out", str(tmp_path / "no" / "x.beats")],
    }


@pytest.mark.parametrize(
    "case",
    [
        "short",
        "missing",
        "empty",
        "notaudio",
        "silent",
        "range",
        "range_with_bpm",
        "bpm_low",
        "bpm_high",
        "overwrite",
        "no_folder",
    ],
)
def test_bad_input_exit_2_nothing_written(case, song, tmp_path, capsys):
    path, _ = song
    argv = [a.replace("{song}", str(path)) for a in _bad_cases(tmp_path)[case]]
    before = sorted(p.name for p in tmp_path.iterdir())
    size = path.stat().st_size
    out = tmp_path / "out.beats"
    click = tmp_path / "out_click.wav"
    if "--out" not in argv and "--click" not in argv:
        argv += ["--out", str(out), "--click", str(click)]
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert err.startswith("beatsync beats: error:")
    if case == "short":
        assert "0.500 s" in err and "1.5 s" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert path.stat().st_size == size


def test_noise_warns_on_stderr(tmp_path, capsys):
    path = tmp_path / "noise.wav"
    y = np.random.default_rng(0).standard_normal(30 * SR).astype(np.float32) * 0.3
    io.write_audio(path, y, SR)
    assert main(["beats", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    assert "beatsync beats: warning: no clear pulse" in captured.err
    # the way out is named: a known tempo
    assert "give it with bpm= (--bpm)" in captured.err
    assert json.loads(captured.out)["warnings"]
