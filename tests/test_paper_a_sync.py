"""Tests of the study layer of paper A's synchronisation (beatsync.study.paper_a_sync)."""

from __future__ import annotations

import numpy as np
import pytest

from beatsync.errors import ParameterError
from beatsync.motion import Joint, Motion, Skeleton
from beatsync.study import paper_a_sync as study


def _bounce(fps: float = 60.0, seconds: float = 12.0) -> Motion:
    skel = Skeleton(
        (
            Joint("hip", -1, np.zeros(3), ("Xposition", "Yposition", "Zposition")),
            Joint("end", 0, np.array([0.0, 0.5, 0.0]), (), True),
        )
    )
    t = np.arange(int(seconds * fps)) / fps
    # a bounce of period 1.1 s whose speed minima (turning points) sit at phase 0.3
    v = np.zeros((t.size, 3))
    v[:, 1] = np.cos(2 * np.pi * (t / 1.1 - 0.3))
    return Motion(v, fps, skel.channel_names(), skel, "bounce")


def test_evaluate_sync_aligned_accents_hit_the_beat():
    m = _bounce()
    bounds = np.arange(0.0, 11.9, 1.1)
    beats = 0.5 + np.arange(40) * 0.5  # 1 period -> 2 beats of 0.5 s
    row = study.evaluate_sync(m, beats, boundaries=bounds, n_control=20)
    assert row["max_residual_frames"] <= 0.5 + 1e-6
    assert row["after_phase"] > 0.9  # phase-locked after sync
    assert row["aligned_motion"] > 0.9  # and on the beat once the lag is removed
    assert row["aligned_motion"] > row["control_motion"]


def test_crop_by_seconds():
    m = _bounce(seconds=3.0)
    assert study.crop(m, 1.0).n_frames == 60
    assert study.crop(m, 10.0).n_frames == m.n_frames
    with pytest.raises(ParameterError, match="seconds=-1"):
        study.crop(m, -1.0)


@pytest.mark.filterwarnings("ignore:no limb:beatsync.errors.BeatsyncWarning")
def test_sync_table_and_views():
    m = _bounce()
    clips = {"bounce": {"motion": m, "data": "synthetic bounce"}}
    songs = {"s": {"beats": 0.5 + np.arange(40) * 0.5, "bpm": 120.0, "data": "grid"}}
    table = study.sync_table(clips, songs, period_range=(0.8, 1.4), n_control=10)
    assert list(study.frame_count_view(table).columns) == study.FRAME_COUNT_COLUMNS
    assert study.alignment_view(table)["after_phase"].iloc[0] > 0.9
    assert study.alignment_summary(table).shape[0] == 1


def test_make_songs_bad_source():
    with pytest.raises(ParameterError, match="beat_source"):
        study.make_songs([96.0, 132.0], beat_source="guess")


def test_residual_table_rounds_for_display_without_negative_zeros():
    from types import SimpleNamespace

    report = {
        "input_frames": 10,
        "output_frames": 12,
        "periods_used": 2,
        "beats_per_period": 1,
        "boundaries_s": [0.5, 1.0],
        "target_beats_s": [0.5, 1.0],
        "residual_ms": [-0.0001, 0.004],
        "residual_nearest_frame_ms": [3.3333, -0.002],
    }
    counts, raw = study.residual_table(SimpleNamespace(report=report))
    assert counts == {"input_frames": 10, "output_frames": 12, "periods_used": 2,
                      "beats_per_period": 1}  # fmt: skip
    assert raw["residual warp [ms]"].tolist() == [-0.0001, 0.004]
    _, shown = study.residual_table(SimpleNamespace(report=report), decimals=2)
    assert shown["residual nearest frame [ms]"].tolist() == [3.33, 0.0]
    assert not np.signbit(shown.to_numpy()).any()  # no "-0.0" in the notebook's table
