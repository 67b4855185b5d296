"""End-to-end tests of ``beatsync sync`` (via beatsync.cli.main)."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.cli import main
from beatsync.motion_beats import kinematic_beats
from beatsync.synth.audio import beat_times, click_track

SR = 22050


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("in")
    # 12 s of salsa made exactly periodic: one 1 s step of 60_01 repeated (root held),
    # so segmentation is fast and certain; the skeleton is the real one
    real = datasets.load_salsa("60_01")
    step = real.values[60:120].copy()
    step[:, :3] = step[0, :3]
    salsa = real.with_values(np.tile(step, (12, 1)))
    io.write_bvh(d / "salsa.bvh", salsa)
    beats = beat_times(115, duration=20.0, start=0.4)
    io.write_audio(d / "song.wav", click_track(beats, sr=SR, duration=20.0), SR)
    io.write_beats(d / "song.beats", beats)
    (d / "one.beats").write_text("1.0\n")
    (d / "song_ms.beats").write_text("".join(f"{1e3 * b:.1f}\n" for b in beats))
    io.write_audio(d / "short.wav", click_track(np.array([0.05]), sr=SR, duration=0.3), SR)
    io.write_audio(d / "silence.wav", np.zeros(5 * SR, dtype=np.float32), SR)
    tone = 0.3 * np.sin(2 * np.pi * 440.0 * np.arange(5 * SR) / SR)
    io.write_audio(d / "tone.wav", tone.astype(np.float32), SR)  # sound without beats
    # a table without skeleton (joint angles), and pure noise (not periodic)
    io.write_table(d / "angles.csv", salsa.select([c for c in salsa.channels if "rotation" in c]))
    rng = np.random.default_rng(0)
    noise = salsa.with_values(rng.normal(0, 30.0, salsa.values.shape))
    io.write_bvh(d / "noise.bvh", noise)
    # a real dancer (Dance-with-Melody waltz excerpt, joint positions, 25 fps), 12 s of it
    dancer = datasets.load_dance_pair("DANCE_W_5").motion
    io.write_motion(d / "dancer.json", dancer.slice_frames(0, 300))
    return d, salsa, beats


def _run(argv, capsys):
    code = main(argv)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_sync_end_to_end_with_beats_file(inputs, tmp_path, capsys):
    d, salsa, beats = inputs
    out = tmp_path / "out.bvh"
    rep = tmp_path / "report.json"
    code, stdout, err = _run(
        [
            "sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out),
            "--beats", str(d / "song.beats"), "--report", str(rep), "--json",
        ],
        capsys,
    )
    assert code == 0, err
    result = json.loads(stdout)
    r = result["report"]
    assert r["input_frames"] == 720 and r["output_frames"] > 100
    assert r["max_abs_residual_frames"] <= 1.0
    assert np.all(np.abs(r["residual_ms"]) <= 1000 / 60)
    back = io.read_bvh(out)
    assert back.skeleton.same_structure(salsa.skeleton)
    assert back.n_frames == r["output_frames"] and back.fps == 60.0
    assert json.loads(rep.read_text())["report"]["output_frames"] == r["output_frames"]
    assert result["warnings"] == []
    # target beats are beats of the file
    assert np.all(np.isin(np.round(r["target_beats_s"], 6), np.round(beats, 6)))


def test_sync_default_loops_over_the_whole_song(inputs, tmp_path, capsys):
    d, _, beats = inputs  # a 12 s dance on a 20 s song
    out = tmp_path / "out.bvh"
    code, stdout, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--json"],
        capsys,
    )
    assert code == 0, err
    r = json.loads(stdout)["report"]
    assert r["mode"] == "periods" and r["fill"] == "loop" and r["repetitions"] >= 2
    # covers the song to its end, dancing on after the last beat
    song_s = json.loads(stdout)["music_duration_s"]
    assert song_s > beats[-1] + 0.1 and r["covered_s"][1] == pytest.approx(song_s)
    assert r["max_abs_residual_frames"] <= 1.0
    # --fill stop: the paper's behaviour, the dance ends with its last period
    code, stdout, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--json", "--fill", "stop"],
        capsys,
    )
    r = json.loads(stdout)["report"]
    assert code == 0 and r["repetitions"] == 1 and r["output_duration_s"] < beats[-1] - 1.0


def test_sync_mode_beats_and_auto_fallback(inputs, tmp_path, capsys):
    d, _, beats = inputs
    out = tmp_path / "out.bvh"
    code, stdout, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--mode", "beats", "--json"],
        capsys,
    )
    assert code == 0, err
    r = json.loads(stdout)["report"]
    assert r["mode"] == "beats" and r["max_abs_residual_frames"] <= 1.0
    # not periodic: auto falls back to motion beats and says so
    code, stdout, err = _run(
        ["sync", str(d / "noise.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--json"],
        capsys,
    )
    assert code == 0, err
    result = json.loads(stdout)
    assert result["report"]["mode"] == "beats" and result["report"]["mode_requested"] == "auto"
    assert "fell back" in result["report"]["mode_note"]
    assert any("fell back" in w for w in result["warnings"]) and "fell back" in err


def test_sync_warns_when_the_beats_given_stop_long_before_the_song(inputs, tmp_path, capsys):
    d, _, beats = inputs
    short = tmp_path / "short.beats"
    io.write_beats(short, beats[:6])  # 20 s song, beats to 3 s
    argv = ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(tmp_path / "o.bvh"),
            "--beats", str(short), "--json"]  # fmt: skip
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    assert "warning: the beats of" in err and "on no beat" in err
    assert any("on no beat" in w for w in json.loads(stdout)["warnings"])
    argv[argv.index(str(short))] = str(d / "song.beats")  # the whole song's: no such warning
    code, _, err = _run(argv, capsys)
    assert code == 0 and "the beats of" not in err


def test_sync_with_bpm_and_out_fps_text_report(inputs, tmp_path, capsys):
    d, _, _ = inputs
    out = tmp_path / "out.bvh"
    code, stdout, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--bpm", "115",
         "--out-fps", "30"],
        capsys,
    )
    assert code == 0, err
    assert "residual" in stdout and "periods" in stdout
    assert "Traceback" not in err
    assert io.read_bvh(out).fps == 30.0
    # the output line says where the dance's last landing falls, as the song goes on
    line = next(t for t in stdout.splitlines() if t.startswith("output"))
    assert re.search(r"\(\d+\.\d\d s(, the first pose held for \S+ s)?, the last landing at "
                     r"\d+\.\d\d s\)", line)  # fmt: skip


def test_sync_tempo_range_steers_the_metrical_level(inputs, tmp_path, capsys):
    # the song is a click track at 115 BPM; a range of 40-80 BPM takes every other click
    d, _, _ = inputs
    runs = {}
    for name, extra in (("default", []), ("range", ["--min-bpm", "40", "--max-bpm", "80"])):
        out = tmp_path / f"{name}.bvh"
        code, stdout, err = _run(
            ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--json", *extra],
            capsys,
        )
        assert code == 0, err
        runs[name] = json.loads(stdout)
    assert runs["default"]["n_music_beats"] == pytest.approx(38, abs=2)
    assert runs["range"]["n_music_beats"] == pytest.approx(19, abs=1)
    assert runs["range"]["beats_source"] == "track_beats(method='psf', min_bpm=40, max_bpm=80)"


def test_sync_align_accents(inputs, tmp_path, capsys):
    d, _, _ = inputs
    out = tmp_path / "out.bvh"
    code, stdout, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--align-accents", "--json"],
        capsys,
    )
    assert code == 0, err
    r = json.loads(stdout)["report"]
    assert abs(r["phase_offset_s"]) <= 60 / 115 / 2 + 1e-9
    assert r["max_abs_residual_frames"] <= 1.0


def test_sync_table_to_csv(inputs, tmp_path, capsys):
    d, _, _ = inputs
    out = tmp_path / "out.csv"
    code, _, err = _run(
        ["sync", str(d / "angles.csv"), str(d / "song.wav"), "-o", str(out), "--fps", "60",
         "--beats", str(d / "song.beats")],
        capsys,
    )
    assert code == 0, err
    assert out.is_file()


def test_sync_video(inputs, tmp_path, capsys):
    from beatsync.render import find_ffmpeg

    if find_ffmpeg() is None:
        pytest.skip("no ffmpeg")
    d, _, _ = inputs
    out, vid = tmp_path / "out.bvh", tmp_path / "out.mp4"
    code, _, err = _run(
        ["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(out), "--beats",
         str(d / "song.beats"), "--video", str(vid), "--video-fps", "8"],
        capsys,
    )
    assert code == 0, err
    assert vid.stat().st_size > 0


BAD = [
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--bpm", "120"], "conflict"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{d}/salsa.bvh"], "same"),
    # a tempo range is checked before any work, named as the options, and conflicts with a
    # fixed tempo or given beats
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--bpm", "115", "--max-bpm", "80"],
     "--max-bpm.*--bpm"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--min-bpm", "60", "--max-bpm", "80"], "--min-bpm and --max-bpm bound.*--beats"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--min-bpm", "300"],
     "--min-bpm 300.*--max-bpm 240.*default"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--max-bpm", "1"],
     "--max-bpm=1.0"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--align-accents", "--phase-offset",
      "0.1"], "phase"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/missing/x.bvh"], "does not exist"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.mp3"], ".bvh or .csv"),
    (["{d}/angles.csv", "{d}/song.wav", "-o", "{o}/x.bvh", "--fps", "60"], "skeleton"),
    (["{d}/noise.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--mode", "periods"], "periodic.*--mode beats"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--beats-per-bar", "0"], "beats-per-bar"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--period-range", "2", "1"],
     "period-range"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--dance-beats", "-3"], "dance-beats"),
    (["{d}/dancer.json", "{d}/song.wav", "-o", "{o}/x.bvh", "--fps", "25"], "json.*npy"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.json", "--beats", "{d}/song.beats"],
     "not joint positions"),
    (["{d}/angles.csv", "{d}/song.wav", "-o", "{o}/x.csv", "--fps", "60", "--beats",
      "{d}/song.beats", "--mode", "beats"], "positions"),
    (["{d}/salsa.bvh", "{d}/silence.wav", "-o", "{o}/x.bvh"], "silen"),
    (["{d}/salsa.bvh", "{d}/short.wav", "-o", "{o}/x.bvh"], "shorter"),
    (["{d}/salsa.bvh", "{d}/tone.wav", "-o", "{o}/x.bvh"], "no detectable beats"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--video", "{d}/song.wav"],
     "same|mp4"),
    # beat times in milliseconds: refused (the dance would run for hours, --fill stop and
    # --out-fps 1 only keep the old behaviour's output small)
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song_ms.beats",
      "--fill", "stop", "--out-fps", "1"], "milliseconds"),
    # a beats file with one beat: the file is named, not the music blamed
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/one.beats"],
     "one.beats' holds 1 beat time"),
    # song first, dance second: the message says the arguments look swapped
    (["{d}/song.wav", "{d}/salsa.bvh", "-o", "{o}/x.bvh"], "swapped"),
    # a bad video frame rate is refused before the motion is synced (named as the option)
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--video", "{o}/v.mp4", "--video-fps", "0"], "--video-fps=0"),
    # an absurd output or video frame rate: refused before the memory fills
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats", "{d}/song.beats",
      "--out-fps", "100000"], "--out-fps=100000"),
    # checked by the library, named as the option given for it
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--first-beat", "500",
      "--beats", "{d}/song.beats"], "--first-beat=500 but the music has only"),
    (["{d}/salsa.bvh", "{d}/song.wav", "-o", "{o}/x.bvh", "--beats-per-period", "0",
      "--beats", "{d}/song.beats"], "--beats-per-period=0 must be an integer >= 1"),
    # a frame rate checked on the motion is named as the option too
    (["{d}/dancer.json", "{d}/song.wav", "-o", "{o}/x.json", "--fps", "100000"],
     "error: --fps=100000"),
    # a frame rate 40 times too high squeezes the dance into a few tenths of a second
    (["{d}/dancer.json", "{d}/song.wav", "-o", "{o}/x.json", "--fps", "1000"],
     r"s at --fps=1000\); at least 2 are needed: .* frame rate wrong"),
]


@pytest.mark.filterwarnings("ignore::beatsync.errors.BeatsyncWarning")
@pytest.mark.parametrize("argv, match", BAD)
def test_sync_bad_inputs(inputs, tmp_path, capsys, argv, match):
    import re

    d, _, _ = inputs
    before = sorted(p.name for p in d.iterdir())
    argv = [a.format(d=d, o=tmp_path) for a in argv]
    code, stdout, err = _run(["sync", *argv], capsys)
    assert code == 3
    assert re.search(match, err, flags=re.IGNORECASE), err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written
    assert sorted(p.name for p in d.iterdir()) == before


@pytest.mark.parametrize("option, value", [("--mode", "bars"), ("--fill", "repeat")])
def test_sync_unknown_choice_is_a_usage_error(inputs, tmp_path, capsys, option, value):
    d, _, _ = inputs
    code = main(["sync", str(d / "salsa.bvh"), str(d / "song.wav"), "-o", str(tmp_path / "x.bvh"),
                 option, value])
    assert code == 2
    assert "invalid choice" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_sync_real_dancer_positions_end_to_end(inputs, tmp_path, capsys):
    d, _, beats = inputs  # 12 s of a real waltz dancer on a 20 s song
    out = tmp_path / "out.json"
    argv = ["sync", str(d / "dancer.json"), str(d / "song.wav"), "-o", str(out), "--fps", "25",
            "--beats", str(d / "song.beats"), "--json", "--beats-per-bar", "3"]
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    result = json.loads(stdout)
    r = result["report"]
    assert r["fill"] == "loop" and r["output_duration_s"] >= beats[-1] - 1 / 25
    assert r["max_abs_residual_frames"] <= 1.0
    assert result["beats_per_bar"] == 3 and r["meter_fit"] is not False
    # the counts follow the dancer's speed, not the song's meter alone (a waltz step of
    # 2 beats where 2 fit); the output plays within x0.8-1.25 of the dancer's speed
    assert r["playback_speed"]["instantaneous"]["in_band"] >= 0.95
    back = io.read_motion(out, fps=25)
    assert back.is_positional and back.n_frames == r["output_frames"]
    src = io.read_motion(d / "dancer.json", fps=25)
    bones = src.bones

    def lengths(m):
        p = m.positions()
        return np.linalg.norm(p[:, bones[:, 0]] - p[:, bones[:, 1]], axis=-1)

    # bone lengths through resampling: within 1 % of the source's range per bone
    lo, hi = lengths(src).min(axis=0), lengths(src).max(axis=0)
    got = lengths(back)
    assert np.all(got >= 0.99 * lo) and np.all(got <= 1.01 * hi)


def test_sync_keeps_the_input_center_track_and_reports_speed(inputs, tmp_path, capsys):
    d, _, beats = inputs  # 12 s of a real waltz dancer (JSON: skeletons relative to center)
    out, rep = tmp_path / "out.json", tmp_path / "report.json"
    argv = ["sync", str(d / "dancer.json"), str(d / "song.wav"), "-o", str(out), "--fps", "25",
            "--beats", str(d / "song.beats"), "--report", str(rep)]  # fmt: skip
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    src, got = json.loads((d / "dancer.json").read_text()), json.loads(out.read_text())
    # the joints keep their place relative to the dataset's root track: the joints'
    # centroid (what replaced it) would put their mean on it in every frame
    off_in = np.linalg.norm(np.asarray(src["skeletons"]).mean(axis=1), axis=1)  # [cm]
    off_out = np.linalg.norm(np.asarray(got["skeletons"]).mean(axis=1), axis=1)
    assert np.median(off_in) > 1.0
    assert np.median(off_out) == pytest.approx(np.median(off_in), rel=0.25)
    r = json.loads(rep.read_text())["report"]
    assert len(r["boundaries_s"]) == len(r["target_beats_s"]) == r["periods_used"] + 1
    assert sum(r["beats_per_motion_beat_used"].values()) == r["periods_used"]
    assert r["joins"] and all(j["peak_joint_speed"] > 0 for j in r["joins"])
    assert "beats    per motion beat used: " in stdout and "% of the output within" in stdout
    # the text counts motion beats, as the report's landings do (not the gaps between them)
    landed = re.search(r"mapping  (\d+) motion beats landed \((\d+) in the clip\)", stdout)
    assert landed and int(landed[1]) == len(r["target_beats_s"])
    seen = r["landings_seen"]
    assert f"seen     {seen['on_their_frame']} of {landed[1]} landings show" in stdout
    n_beats = kinematic_beats(io.read_motion(d / "dancer.json", fps=25)).size
    assert int(landed[2]) == n_beats
    seg = json.loads(rep.read_text())["segmentation"]  # named for what it holds
    assert seg["mode"] == "beats" and seg["n_motion_beats"] == n_beats
    assert seg["median_interval_s"] == pytest.approx(r["mean_motion_period_s"])


def test_sync_text_says_the_offset_the_held_start_and_what_is_seen(inputs, tmp_path, capsys):
    # with counts given, beats mode lands interval by interval: what the output shows is
    # still reported; an offset before the beat is said so; a long held start is said
    d, _, _ = inputs
    argv = ["sync", str(d / "dancer.json"), str(d / "song.wav"), "-o", str(tmp_path / "o.json"),
            "--fps", "25", "--beats", str(d / "song.beats"), "--mode", "beats",
            "--beats-per-period", "2", "--first-beat", "8", "--phase-offset", "-0.05",
            "--report", str(tmp_path / "r.json")]  # fmt: skip
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    r = json.loads((tmp_path / "r.json").read_text())["report"]
    assert r["landings_seen"]["landings"] == len(r["target_beats_s"])
    assert "first on beat 8, 50 ms before it" in stdout
    assert re.search(r"^seen     \d+ of \d+ landings show", stdout, re.M)
    held = r["playback_speed"]["held_lead_in_s"]
    assert held >= 3.5 and f"the first pose held for {held:.2f} s" in stdout


def test_sync_reports_the_dance_phrase_it_steers_onto_bar_lines(inputs, tmp_path, capsys):
    d, _, _ = inputs  # the real waltz dancer: a phrase of 3 motion beats, given
    argv = ["sync", str(d / "dancer.json"), str(d / "song.wav"), "-o", str(tmp_path / "o.json"),
            "--fps", "25", "--beats", str(d / "song.beats"), "--mode", "beats",
            "--beats-per-bar", "3", "--dance-beats", "3"]  # fmt: skip
    code, stdout, err = _run(argv, capsys)
    assert code == 0, err
    assert "dance    phrases of 3 motion beats (given) start on bar lines" in stdout


def test_sync_text_never_rounds_a_share_up_to_all():
    from beatsync.commands.sync import _share

    assert _share(0.996) == "99.6%" and _share(0.9999) == "99.9%" and _share(1.0) == "100%"
