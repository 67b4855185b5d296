"""A new user's acceptance cases on the bundled real data (via beatsync.cli.main).

Each case reproduces a problem met when running the CLI on ``data/`` as an animator or
a careless user would; the command must either work or refuse with a clear message
before any work, writing nothing.
"""

from __future__ import annotations

import json

import numpy as np

from beatsync import datasets, io
from beatsync.cli import main

MAT = str(datasets.path("motion/mocaptoolbox/mcdemodata.mat"))
SONG = str(datasets.path("audio/real_dev/hainsworth_001.flac"))
SONG_BEATS = str(datasets.path("audio/real_dev/hainsworth_001.beats"))


def test_sync_mat_markers_with_dropouts(tmp_path, capsys):
    # MoCap Toolbox walk1 has marker dropouts of 11 and 16 frames (0.18 s, 0.27 s at
    # 60 Hz); sync used to fail after all its work with "joint positions contains 81 NaN"
    out = tmp_path / "walk1.csv"
    argv = ["sync", MAT, SONG, "--variable", "walk1", "--beats", SONG_BEATS, "-o", str(out)]
    assert main([*argv, "-q"]) == 3
    err = capsys.readouterr().err
    assert "'Shoulder_R' is missing (NaN) for 16 frames" in err and "max_gap" in err
    assert "Traceback" not in err and list(tmp_path.iterdir()) == []
    # the longest gap is 0.27 s: --max-gap 0.3 fills both and the sync runs
    assert main([*argv, "--max-gap", "0.3", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    synced = io.read_motion(out, fps=60)
    assert np.isfinite(synced.values).all() and synced.n_channels == 84
    assert res["report"]["output_frames"] == synced.n_frames
