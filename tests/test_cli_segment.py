"""End-to-end tests of ``beatsync segment`` via ``beatsync.cli.main``."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest

from beatsync import datasets
from beatsync.cli import main
from beatsync.synth.motion import periodic_motion


@pytest.fixture
def synth_csv(tmp_path):
    s = periodic_motion(n_frames=400, n_channels=6, n_periods=12, snr_db=25, seed=4)
    p = tmp_path / "angles.csv"
    pd.DataFrame(s.motion.values, columns=list(s.motion.channels)).to_csv(p, index=False)
    return p, s


def test_segment_csv_json_and_out(tmp_path, synth_csv, capsys):
    path, s = synth_csv
    out = tmp_path / "bounds.csv"
    rc = main(["segment", str(path), "--fps", "25", "--periods", "12", "--json", "--out", str(out)])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["n_periods"] == 12
    assert np.abs(np.array(res["boundary_frames"]) - s.boundary_frames).max() <= 1
    assert res["mean_period_s"] == pytest.approx(s.period, rel=0.01)
    table = pd.read_csv(out)
    assert list(table.columns) == ["boundary", "time_s", "frame"]
    np.testing.assert_allclose(table["time_s"], res["boundaries_s"])


def test_segment_text_output(synth_csv, capsys):
    path, _ = synth_csv
    assert main(["segment", str(path), "--fps", "25", "--alpha", "0.15"]) == 0
    text = capsys.readouterr().out
    assert "periods, mean period" in text and "boundaries [s]:" in text


def test_segment_bvh_with_fps_override_and_channels(capsys):
    bvh = datasets.path("motion/cmu_salsa/60_01_scaled.bvh")
    rc = main(["segment", str(bvh), "--fps", "60", "--channels", "rShin_Xrotation",
               "lShin_Xrotation", "--json"])  # fmt: skip
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["mean_period_s"] == pytest.approx(1.0, abs=0.08)
    assert res["channels"] == ["rShin_Xrotation", "lShin_Xrotation"]


def test_segment_mat_markers_become_angles(capsys):
    mat = datasets.path("motion/mocaptoolbox/mcdemodata.mat")
    rc = main(["segment", str(mat), "--variable", "dance2", "--channels", "knee_L_angle",
               "knee_R_angle", "--json"])  # fmt: skip
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["marker_angles"] is True
    assert res["mean_period_s"] == pytest.approx(0.51, abs=0.04)


def test_mat_lists_only_its_marker_recordings(capsys):
    # 'wiidata' has the fields of a marker struct but 3 columns for no marker: it was
    # offered as a choice, then refused for its shape
    mat = str(datasets.path("motion/mocaptoolbox/mcdemodata.mat"))
    assert main(["segment", mat]) == 3
    err = capsys.readouterr().err
    assert "['dance1', 'dance2', 'walk1', 'walk2']" in err and "wiidata" not in err
    assert main(["segment", mat, "--variable", "wiidata"]) == 3
    assert "'wiidata' (is not marker data)" in capsys.readouterr().err


def _bad_files(tmp_path):
    trunc = tmp_path / "trunc.bvh"
    trunc.write_text("HIERARCHY\nROOT hip\n{\n  OFFSET 0 0 0\n")
    nan_csv = tmp_path / "nan.csv"
    v = periodic_motion(n_frames=200, n_channels=3, n_periods=8, seed=0).motion.values
    v[3, 1] = np.nan
    pd.DataFrame(v, columns=["a_angle", "b_angle", "c_angle"]).to_csv(nan_csv, index=False)
    short = tmp_path / "short.csv"
    pd.DataFrame(v[20:30], columns=["a_angle", "b_angle", "c_angle"]).to_csv(short, index=False)
    noise = tmp_path / "noise.csv"
    rnd = np.random.default_rng(0).standard_normal((300, 4))
    pd.DataFrame(rnd, columns=[f"c{i}_angle" for i in range(4)]).to_csv(noise, index=False)
    return {"trunc": trunc, "nan": nan_csv, "short": short, "noise": noise}


@pytest.mark.parametrize(
    "key,extra,match",
    [
        ("missing", ["--fps", "25"], "nope.bvh"),
        ("trunc", [], "no MOTION section"),
        ("nan", ["--fps", "25"], "NaN"),
        ("short", ["--fps", "25"], "clip of 10 frames"),
        ("noise", ["--fps", "25"], "not periodic"),
        ("pirouette", [], "not periodic"),
        ("good", ["--fps", "0"], "fps"),
        ("good", ["--fps", "25", "--alpha", "0.7"], "alpha"),
        ("good", ["--fps", "25", "--period-range", "1.25", "0.25"], "reversed"),
        ("good", [], "fps"),  # a table without --fps
    ],
)
def test_segment_bad_input_writes_nothing(tmp_path, synth_csv, capsys, key, extra, match):
    files = _bad_files(tmp_path)
    files["missing"] = tmp_path / "nope.bvh"
    files["good"] = synth_csv[0]
    files["pirouette"] = datasets.path("motion/cmu_walk_modern/005_02.bvh")
    out = tmp_path / "out.csv"
    rc = main(["segment", str(files[key]), *extra, "--out", str(out)])
    assert rc == 3
    err = capsys.readouterr().err
    assert err.startswith("beatsync segment: error:")
    assert re.search(match, err), err
    assert "Traceback" not in err
    assert not out.exists()


def test_segment_refuses_out_equal_to_input(synth_csv, capsys):
    path, _ = synth_csv
    before = path.read_bytes()
    assert main(["segment", str(path), "--fps", "25", "--out", str(path)]) == 3
    assert path.read_bytes() == before


def test_segment_marker_table_becomes_angles_like_mat(tmp_path, capsys):
    """A marker-position CSV goes through motion.segmentation_view, like the .mat file."""
    m = datasets.load_mocap_toolbox("dance2")
    path = tmp_path / "dance2_markers.csv"
    pd.DataFrame(m.values, columns=list(m.channels)).to_csv(path, index=False)
    chans = ["--channels", "knee_L_angle", "knee_R_angle", "--json"]
    assert main(["segment", str(path), "--fps", str(m.fps), *chans]) == 0
    from_csv = json.loads(capsys.readouterr().out)
    mat = datasets.path("motion/mocaptoolbox/mcdemodata.mat")
    assert main(["segment", str(mat), "--variable", "dance2", *chans]) == 0
    from_mat = json.loads(capsys.readouterr().out)
    assert from_csv["marker_angles"] is True
    assert from_csv["channels"] == ["knee_L_angle", "knee_R_angle"]
    np.testing.assert_allclose(from_csv["boundaries_s"], from_mat["boundaries_s"], atol=1e-9)


def test_segment_periods_is_honoured(synth_csv, capsys):
    """True count 12; --periods 11 used to come back as 12 periods."""
    path, _ = synth_csv
    rc = main(["segment", str(path), "--fps", "25", "--periods", "11", "--alpha", "0.2", "--json"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["n_periods"] == 11
    assert len(res["boundaries_s"]) == 12
    rc = main(["segment", str(path), "--fps", "25", "--periods", "15"])
    assert rc == 3
    assert "n_periods=15 was given" in capsys.readouterr().err


def test_segment_bpm_searches_one_to_eight_beats(tmp_path, capsys):
    """A 4 s figure: refused in the default 0.25-1.25 s, found with the music's tempo."""
    s = periodic_motion(n_frames=1001, n_channels=12, fps=25.0, n_periods=10, snr_db=20, seed=2)
    path = tmp_path / "figure.csv"
    pd.DataFrame(s.motion.values, columns=list(s.motion.channels)).to_csv(path, index=False)
    assert main(["segment", str(path), "--fps", "25"]) == 3
    assert "not periodic" in capsys.readouterr().err
    assert main(["segment", str(path), "--fps", "25", "--bpm", "120", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["period_range_s"] == pytest.approx([0.45, 4.25])  # 1-8 beats, with room
    assert res["mean_period_s"] == pytest.approx(4.0, rel=0.03)


@pytest.mark.parametrize(
    "extra,match",
    [
        (["--bpm", "0.5"], "--bpm=0.5 is outside the plausible range"),
        (["--bpm", "120", "--period-range", "0.3", "2"], "either --bpm or --period-range"),
        (["--bpm", "120", "--periods", "12"], "leave out --bpm"),
    ],
)
def test_segment_bpm_bad_input(synth_csv, capsys, extra, match):
    path, _ = synth_csv
    assert main(["segment", str(path), "--fps", "25", *extra]) == 3
    assert re.search(match, capsys.readouterr().err)
