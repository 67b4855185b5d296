"""Tests of beatsync.render: stick figures, frame strips and video writing."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from beatsync import render
from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.motion import Joint, Motion, Skeleton

FPS = 20.0


def _motion(n: int = 30) -> Motion:
    skel = Skeleton(
        (
            Joint("hip", -1, np.zeros(3), ("Xposition", "Yposition", "Zposition",
                                           "Zrotation", "Xrotation", "Yrotation")),
            Joint("spine", 0, np.array([0.0, 0.5, 0.0]), ("Zrotation", "Xrotation", "Yrotation")),
            Joint("head", 1, np.array([0.0, 0.3, 0.0]), (), True),
            Joint("leg", 0, np.array([0.1, -0.5, 0.0]), ("Zrotation", "Xrotation", "Yrotation")),
            Joint("foot", 3, np.array([0.0, -0.4, 0.0]), (), True),
        )
    )
    t = np.arange(n) / FPS
    v = np.zeros((n, 12))
    v[:, 1] = 0.9
    v[:, 9] = 30 * np.sin(2 * np.pi * t)
    return Motion(v, FPS, skel.channel_names(), skel, "toy")


def test_pose_positions_bones():
    pos, bones = render.pose_positions(_motion())
    assert pos.shape == (30, 5, 3)
    assert bones.tolist() == [[1, 0], [2, 1], [3, 0], [4, 3]]


def test_project_y_up():
    p = np.array([[1.0, 2.0, 3.0]])
    assert np.allclose(render.project(p, up=1), [[1.0, 2.0]])
    assert np.allclose(render.project(p, up=1, azimuth=90), [[3.0, 2.0]])
    assert np.allclose(render.project(p, up=2), [[2.0, 3.0]])


def test_plot_frames_marks_beats():
    fig = render.plot_frames(_motion(), [0.0, 0.25, 0.5], beats=np.array([0.25, 1.0]))
    ax = fig.axes[0]
    colours = [tuple(np.round(c.get_colors()[0][:3], 3)) for c in ax.collections]
    red = tuple(np.round(matplotlib.colors.to_rgb(render._BEAT_COLOR), 3))
    assert colours.count(red) == 1 and len(colours) == 3
    assert any("beat" in t.get_text() for t in ax.texts)


def test_plot_beat_timeline(tmp_path):
    fig = render.plot_beat_timeline(_motion(), beats=[0.5, 1.0], motion_beats=[0.25],
                                    boundaries=[0.0, 1.0])
    out = render.save_figure(fig, tmp_path / "t.png")
    assert out.stat().st_size > 1000


def _streams(path) -> str:
    exe = render.find_ffmpeg()
    return subprocess.run([exe, "-hide_banner", "-i", str(path)], capture_output=True,
                          text=True).stderr


@pytest.mark.skipif(render.find_ffmpeg() is None, reason="no ffmpeg")
def test_write_video_mp4_with_sound(tmp_path):
    sr = 8000
    y = 0.1 * np.sin(2 * np.pi * 440 * np.arange(2 * sr) / sr).astype(np.float32)
    out = render.write_video(_motion(), tmp_path / "v.mp4", audio=(y, sr), beats=[0.5, 1.0],
                             size=(96, 64))
    assert out == tmp_path / "v.mp4" and out.stat().st_size > 0
    info = _streams(out)
    assert "Video: h264" in info and "Audio: aac" in info
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]  # no temporary left


def test_write_video_fallback_gif_and_wav(tmp_path):
    sr = 8000
    y = np.zeros(sr, dtype=np.float32)
    with pytest.warns(BeatsyncWarning, match="no ffmpeg"):
        out = render.write_video(_motion(10), tmp_path / "v.mp4", audio=(y, sr), ffmpeg=False,
                                 size=(64, 64))
    assert out.suffix == ".gif" and out.is_file()
    assert (tmp_path / "v.wav").is_file()
    assert not (tmp_path / "v.mp4").exists()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"fps": 0}, "fps"),
        ({"size": (8, 8)}, r"size=\(8, 8\)"),
        ({"audio": (np.zeros((2, 10)), 8000)}, r"\(2, 10\)"),
        ({"audio": (np.zeros(10), 0)}, "sr=0"),
        ({"audio": (np.full(10, np.nan), 8000)}, "10 NaN"),
        ({"audio": 3}, "audio=int"),
        ({"beats": [1.0, 0.5]}, r"beats .*\(0\.5 s\)"),
        ({"duration": -1.0}, "duration"),
        ({"preset": "turbo"}, "turbo"),
    ],
)
def test_write_video_bad_inputs(tmp_path, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        render.write_video(_motion(), tmp_path / "v.mp4", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_write_video_missing_folder(tmp_path):
    with pytest.raises(ParameterError, match="nope"):
        render.write_video(_motion(), tmp_path / "nope" / "v.mp4")


def test_beat_strip_times():
    t = render.beat_strip_times([0.0, 0.5, 1.0, 1.5, 2.0], start=0.4, n_beats=2, per_beat=2)
    assert np.allclose(t, [0.5, 0.75, 1.0, 1.25, 1.5])
    with pytest.raises(ParameterError, match="start=1.0"):
        render.beat_strip_times([0.0, 0.5], start=1.0)


def _duration_s(path) -> float:
    import re

    m = re.search(r"Duration: (\d+):(\d+):([\d.]+)", _streams(path))
    return int(m.group(1)) * 3600 + int(m.group(2)) * 60 + float(m.group(3))


@pytest.mark.skipif(render.find_ffmpeg() is None, reason="no ffmpeg")
def test_write_video_lasts_as_long_as_asked_holding_the_last_pose(tmp_path):
    sr = 8000
    y = 0.1 * np.sin(2 * np.pi * 440 * np.arange(4 * sr) / sr).astype(np.float32)
    m = _motion(30)  # 1.5 s of motion, 4 s of song
    short = render.write_video(m, tmp_path / "a.mp4", audio=(y, sr), fps=10, size=(64, 64))
    full = render.write_video(m, tmp_path / "b.mp4", audio=(y, sr), fps=10, size=(64, 64),
                              duration=4.0)
    assert _duration_s(short) < 2.0
    assert abs(_duration_s(full) - 4.0) < 0.15



def test_position_only_motion_is_drawn_with_bones():
    pos = np.zeros((4, 3, 3))
    pos[:, 1, 2] = 0.5
    pos[:, 2, 2] = 1.0
    names = tuple(f"{j}_{a}" for j in ("a", "b", "c") for a in "xyz")
    m = Motion(pos.reshape(4, -1), FPS, names, None, "positions")
    _, bones = render.pose_positions(m)
    assert len(bones) == 2  # a-b and b-c: drawn as bones, not dots


def _children() -> set[int]:
    pid = os.getpid()
    kids: set[int] = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        kids.update(int(k) for k in text)
    return kids


@pytest.mark.skipif(render.find_ffmpeg() is None, reason="no ffmpeg")
@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs /proc")
def test_write_video_progress_callable_and_interruption_leaves_no_ffmpeg(tmp_path):
    seen = []

    def progress(done, total):
        seen.append((done, total))
        if done == 5:
            raise KeyboardInterrupt  # as a Ctrl-C during the video

    before = _children()
    with pytest.raises(KeyboardInterrupt):
        render.write_video(_motion(), tmp_path / "v.mp4", size=(64, 64), progress=progress)
    assert seen == [(k, seen[0][1]) for k in range(1, 6)] and seen[0][1] > 5
    assert _children() - before == set()  # ffmpeg was killed and reaped
    assert list(tmp_path.iterdir()) == []  # no temporary folder, no partial video
    # the same callable, not interrupted, counts every frame
    done = []
    render.write_video(_motion(), tmp_path / "v.mp4", size=(64, 64),
                       progress=lambda d, t: done.append((d, t)))
    assert done[-1] == (done[-1][1], done[-1][1]) and len(done) == done[-1][1]


def _frames(path, size):
    import imageio_ffmpeg

    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    assert tuple(meta["size"]) == size
    return [np.frombuffer(f, np.uint8).reshape(size[1], size[0], 3) for f in gen]


def _walker(n: int = 100, fps: float = 25.0, metres: float = 6.0) -> Motion:
    """A 1.7 m stick figure (z up, 5 joints) that walks ``metres`` along x."""
    base = np.array([[0, 0, 1.0], [0, 0, 1.45], [0, 0, 1.7], [0.1, 0, 0], [-0.1, 0, 0]])
    pos = np.repeat(base[None], n, axis=0)
    pos[:, :, 0] += np.linspace(0, metres, n)[:, None]
    names = tuple(f"{j}_{a}" for j in ("hip", "neck", "head", "lfoot", "rfoot") for a in "xyz")
    return Motion(pos.reshape(n, -1), fps, names, None, "walker")


def _figure_box(frame: np.ndarray) -> tuple[float, float, float]:
    """Centre x, top and bottom rows of the figure's pixels (dark or red)."""
    r, g, b = (frame[..., c].astype(int) for c in range(3))
    body = ((r < 120) & (b > r)) | ((r > 170) & (g < 90) & (b < 90))
    body[-40:] = False  # the beat ruler
    body[:30] = False  # the caption and the beat dot
    ys, xs = np.nonzero(body)
    return float(xs.mean()), float(ys.min()), float(ys.max())


@pytest.mark.skipif(render.find_ffmpeg() is None, reason="no ffmpeg")
def test_write_video_default_is_640x480_and_the_camera_follows_the_dancer(tmp_path):
    out = render.write_video(_walker(), tmp_path / "v.mp4", up="z")
    frames = _frames(out, (640, 480))
    first, last = _figure_box(frames[1]), _figure_box(frames[-1])
    # a 6 m walk: the figure stays near the middle of the frame to its last step (the
    # camera lagged behind at the ends), fills a good part of it, and keeps clear of the
    # caption above
    for x, top, bottom in (first, last):
        assert 260 < x < 380
        assert bottom - top > 0.4 * 480 and top > 40


@pytest.mark.skipif(render.find_ffmpeg() is None, reason="no ffmpeg")
def test_write_video_marks_the_beat_in_red(tmp_path):
    out = render.write_video(_walker(50), tmp_path / "v.mp4", up="z", beats=[1.0])
    frames = _frames(out, (640, 480))
    red = [int(((f[..., 0] > 170) & (f[..., 1] < 90) & (f[..., 2] < 90)).sum()) for f in frames]
    assert red[25] > 50 * max(red[10], 1) and red[25] > 500  # lit on the beat at 1.0 s only


def test_write_video_bad_elevation(tmp_path):
    with pytest.raises(ParameterError, match="elevation=95"):
        render.write_video(_motion(), tmp_path / "v.mp4", elevation=95)
    assert list(tmp_path.iterdir()) == []


def test_a_real_dancer_and_their_shadow_stay_between_the_caption_and_the_ruler():
    # DANCE_W_5's shadow crossed the beat ruler (and left the frame) in over a third of
    # the frames, and a raised hand came within 8 px of the top
    from beatsync import datasets

    m = datasets.load_dance_pair("DANCE_W_5").motion
    pos, bones = render.pose_positions(m)
    stage = render._Stage(pos, bones, [], up=2, azimuth=30.0, elevation=12.0, fps=m.fps,
                          size=(640, 480), title="", mode="RGB")  # fmt: skip
    rows = np.concatenate([stage.joints[..., 1], stage.shadow[..., 1]], axis=1)
    assert rows.min() > 30 and rows.max() < 480 - 30
