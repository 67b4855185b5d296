"""Real dancers (Dance-with-Melody excerpts): reading, bones, writing back."""

import json

import numpy as np
import pytest

from beatsync import datasets, io
from beatsync.motion import bone_lengths, segmentation_view


@pytest.mark.parametrize("name", datasets.DANCE_PAIRS)
def test_dance_pair_loads_verified(name):
    pair = datasets.load_dance_pair(name)
    m = pair.motion
    assert m.is_positional and m.fps == 25.0 and m.n_frames == 600
    assert len(m.joint_names) == 23
    assert pair.sr == 22050 and abs(len(pair.y) / pair.sr - 28.0) < 0.01
    assert pair.audio_offset == 2.0
    pos = m.positions()
    height = np.median(pos[:, :, 2].max(axis=1) - pos[:, :, 2].min(axis=1))
    assert 1.3 < height < 1.8  # metres, z up: ankles to head joint
    assert np.median(pos[:, :, 2].min(axis=1)) > -0.2  # feet near the floor, not below


def test_real_excerpt_units_and_axis_are_detected():
    p = datasets.path("motion/dance_with_melody/DANCE_W_5/skeletons.json")
    m = io.read_motion(p, fps=25)
    info = m.position_info
    assert (info.units, info.up, info.units_source, info.up_source) == (
        "cm",
        "y",
        "detected",
        "detected",
    )


def test_real_excerpt_bones_are_limbs():
    m = datasets.load_dance_pair("DANCE_W_5").motion
    bones = {tuple(sorted(b)) for b in m.bones.tolist()}
    assert len(bones) == 22  # a tree over 23 joints
    # forearm, shin and foot chains of both sides (checked against the anatomy)
    for bone in [(4, 5), (5, 6), (13, 21), (14, 21), (8, 9), (9, 10), (17, 18), (18, 19)]:
        assert bone in bones
    lengths = bone_lengths(m.positions(), m.bones)
    assert np.median(lengths) < 0.6  # bones, not cross-body links
    view = segmentation_view(m)
    assert view.n_channels > 10 and all(c.endswith("_angle") for c in view.channels)


def test_real_excerpt_written_back_in_its_layout(tmp_path):
    src = datasets.path("motion/dance_with_melody/DANCE_C_4/skeletons.json")
    m = io.read_motion(src, fps=25)
    out = io.write_motion(tmp_path / "skeletons.json", m)
    a, b = json.loads(out.read_text()), json.loads(src.read_text())
    assert a["length"] == b["length"] == 600
    np.testing.assert_allclose(a["skeletons"], b["skeletons"], atol=1e-9)
    np.testing.assert_allclose(a["center"], b["center"], atol=1e-9)


def test_cli_reads_a_real_dancer(tmp_path, capsys):
    from beatsync.cli import main

    src = str(datasets.path("motion/dance_with_melody/DANCE_W_5/skeletons.json"))
    args = ["segment", src, "--fps", "25", "--period-range", "1", "5", "--json"]
    assert main(args + ["--up", "y", "--units", "cm"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["n_periods"] >= 5
    assert res["positions"].startswith("json file in cm (given), y up (given)")
    assert main(args[:-1]) == 0  # detected, and said so in the text output
    assert "json file in cm (detected), y up (detected)" in capsys.readouterr().out
    beats = tmp_path / "beats.txt"
    beats.write_text("\n".join(f"{0.5 + 0.7 * k:.3f}" for k in range(39)))  # within 28 s
    audio = str(datasets.path("motion/dance_with_melody/DANCE_W_5/audio.ogg"))
    out = tmp_path / "synced.csv"
    sync = ["sync", src, audio, "-o", str(out), "--fps", "25", "--beats", str(beats)]
    assert main(sync + ["--period-range", "1", "5", "--json"]) == 0
    synced = io.read_motion(out, fps=25)
    assert synced.n_channels == 69 and synced.n_frames > 100
    capsys.readouterr()
    out_json = tmp_path / "synced.json"  # joint positions back in the input's layout
    assert main(sync[:4] + [str(out_json)] + sync[5:] + ["--period-range", "1", "5"]) == 0
    assert "json file in cm (detected)" in capsys.readouterr().out
    back = json.loads(out_json.read_text())
    assert list(back) == ["length", "center", "skeletons"]
    assert np.asarray(back["skeletons"]).shape == (synced.n_frames, 23, 3)


def test_cli_refuses_position_options_for_bvh(capsys):
    from beatsync.cli import main

    bvh = str(datasets.path("motion/cmu_salsa/60_01_scaled.bvh"))
    assert main(["segment", bvh, "--fps", "60", "--units", "cm"]) != 0
    assert "units='cm' apply to joint-position files" in capsys.readouterr().err


@pytest.mark.slow
def test_resynchronised_waltzes_beat_control_and_own_song():
    from beatsync.study import paper_a_dancers as study

    pairs = study.load_pairs(["DANCE_W_5", "DANCE_W_10"])
    songs = study.track_songs(pairs)
    table, results = study.dancer_table(pairs, songs, modes=("beats",), n_control=20)
    summary = study.summary_table(table, mode="beats")
    assert summary["beats_motion_target"].all() and summary["beats_music_target"].all()
    res = results[("DANCE_W_5", "beats")]
    assert res.report["mode"] == "beats" and res.report["repetitions"] >= 1
    # the loop covers the song to its last beat
    assert res.motion.duration >= songs["DANCE_W_10"]["beats"][-1] - 0.1
    assert res.motion.is_positional and res.motion.position_info.layout == "json"


def test_video_html_embeds_the_mp4(tmp_path):
    from beatsync.study.paper_a_dancers import video_html

    mp4 = tmp_path / "v.mp4"
    mp4.write_bytes(b"\x00\x00\x00\x18ftypmp42")
    html = video_html(mp4, width=300).data
    assert html.startswith('<video width="300" controls>') and "data:video/mp4;base64," in html
    assert "No MP4" in video_html(tmp_path / "v.gif").data
