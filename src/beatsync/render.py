"""Stick-figure drawings and videos of motion, with music beats marked.

Figures (:func:`plot_frames`: paper A's Figure 3; :func:`plot_beat_timeline`) use an
orthographic view. :func:`write_video` films the dancer in perspective with a camera
that follows them over a floor: Pillow draws each frame and pipes it to ffmpeg
(``imageio-ffmpeg``'s, or one on ``PATH``); without ffmpeg it writes an animated GIF
and the music as a WAV beside it, and says so with a
:class:`~beatsync.errors.BeatsyncWarning`.

Data contract: poses come from forward kinematics for skeletal motion, or from
``<marker>_x/_y/_z`` channels (:func:`beatsync.motion_beats.motion_positions`); BVH
skeletons are y-up, marker data z-up (``up=`` overrides). Times and beats are seconds
in the motion's timeline (frame ``k`` at ``k / fps``); audio is mono ``y`` at ``sr``
[Hz] from the motion's time 0. Every file is written atomically.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ParameterError, warn
from .validation import (
    check_audio,
    check_choice,
    check_fps,
    check_motion_fps,
    check_positive,
    check_times,
    frames_to_time,
    nearest,
    time_to_frames,
)

__all__ = [
    "beat_strip_times",
    "pose_positions",
    "project",
    "plot_frames",
    "plot_beat_timeline",
    "save_figure",
    "find_ffmpeg",
    "write_video",
]

_BEAT_COLOR = "#d62728"
_POSE_COLOR = "#333333"


def pose_positions(motion: Any) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions [shape=(n_frames, n_joints, 3)] and the bones to draw between them:
    pairs of joint indices, (child, parent) for a skeleton, the motion's bones for
    position-only motion."""
    from .motion_beats import motion_positions

    return motion_positions(motion), motion.bones


def _up_axis(motion: Any, up: str | None) -> int:
    if up is None:
        up = "y" if getattr(motion, "skeleton", None) is not None else "z"
    return "xyz".index(check_choice(up, ("x", "y", "z"), name="up"))


def project(positions: Any, *, up: int = 1, azimuth: float = 0.0) -> np.ndarray:
    """Orthographic projection of positions [shape=(..., 3)] on a vertical image plane
    [shape=(..., 2)]: ``up`` is the vertical axis (1 for y-up BVH, 2 for z-up markers),
    ``azimuth`` [deg] the camera's rotation about it (0: the image's horizontal axis is
    the axis before ``up``)."""
    p = np.asarray(positions, dtype=np.float64)
    h1, h2 = (up + 1) % 3, (up + 2) % 3  # y-up: z, x ; z-up: x, y
    a = np.deg2rad(azimuth)
    # horizontal axis: h2 rotated towards h1 by the azimuth
    horiz = np.cos(a) * p[..., h2] + np.sin(a) * p[..., h1]
    return np.stack([horiz, p[..., up]], axis=-1)


def _near_beat(times: np.ndarray, beats: np.ndarray | None, tol: float) -> np.ndarray:
    if beats is None or len(beats) == 0:
        return np.zeros(times.shape, dtype=bool)
    return np.abs(times - nearest(times, beats)) <= tol


def beat_strip_times(
    beats: Any, *, start: float = 0.0, n_beats: int = 4, per_beat: int = 2
) -> np.ndarray:
    """Times [s] for a strip of poses: ``per_beat`` evenly spaced poses in each of
    ``n_beats`` beat intervals from the first beat at or after ``start`` [s], and the
    beat that ends them."""
    b = check_times(beats, name="beats", allow_empty=False)
    if int(n_beats) < 1 or int(per_beat) < 1:
        raise ParameterError(f"n_beats={n_beats!r} and per_beat={per_beat!r} must be >= 1")
    i0 = int(np.searchsorted(b, float(start) - 1e-9))
    seg = b[i0 : i0 + int(n_beats) + 1]
    if seg.size < 2:
        raise ParameterError(
            f"fewer than 2 beats at or after start={start!r} s (last beat {b[-1]:.2f} s)"
        )
    u = np.arange(int(per_beat)) / int(per_beat)
    times = (seg[:-1, None] + u[None, :] * np.diff(seg)[:, None]).ravel()
    return np.concatenate([times, seg[-1:]])


def plot_frames(
    motion: Any,
    times: Any = None,
    *,
    beats: Any = None,
    n_frames: int = 8,
    ax: Any = None,
    up: str | None = None,
    azimuth: float = 0.0,
    spacing: float | None = None,
    tol: float | None = None,
) -> Any:
    """Draw skeleton poses at ``times`` [s] side by side; poses within ``tol`` [s] of a
    beat in colour, labelled; returns the Figure.

    ``times`` are snapped to frames (default: ``n_frames`` spread over the motion);
    ``up`` is the vertical axis (default ``y`` for skeletons, ``z`` for markers);
    ``azimuth`` [deg] turns the camera about it; ``spacing`` [position unit] defaults to
    1.3 times the widest pose, ``tol`` to half a frame.
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fps = check_fps(motion.fps)
    if times is None:
        if n_frames < 1:
            raise ParameterError(f"n_frames={n_frames!r} must be >= 1")
        times = np.linspace(0, (motion.n_frames - 1) / fps, int(n_frames))
    times = np.atleast_1d(np.asarray(times, dtype=np.float64))
    frames = np.clip(time_to_frames(times, fps=fps), 0, motion.n_frames - 1)
    shown_t = frames_to_time(frames, fps=fps)
    beats_arr = None if beats is None else check_times(beats, name="beats")
    tol = 0.5 / fps + 1e-9 if tol is None else float(tol)
    on_beat = _near_beat(shown_t, beats_arr, tol)

    pos, bones = pose_positions(motion)
    xy = project(pos[frames], up=_up_axis(motion, up), azimuth=azimuth)
    centred = xy - xy[:, :, :1].mean(axis=1, keepdims=True) * np.array([1.0, 0.0])
    width = float(np.ptp(centred[..., 0], axis=1).max()) if len(frames) else 1.0
    spacing = 1.3 * max(width, 0.3) if spacing is None else float(spacing)
    if ax is None:
        fig, ax = plt.subplots(figsize=(max(4.0, 1.2 * len(frames)), 3.2))
    else:
        fig = ax.figure
    for k, (pose, beat) in enumerate(zip(centred, on_beat, strict=True)):
        p = pose + np.array([k * spacing, 0.0])
        color = _BEAT_COLOR if beat else _POSE_COLOR
        if len(bones):
            ax.add_collection(LineCollection(p[bones], colors=color, linewidths=1.6))
        else:
            ax.plot(p[:, 0], p[:, 1], "o", ms=2.5, color=color)
        label = f"{shown_t[k]:.2f} s" + ("\nbeat" if beat else "")
        ax.text(
            k * spacing,
            float(np.min(xy[..., 1])) - 0.05 * np.ptp(xy[..., 1]),
            label,
            ha="center",
            va="top",
            fontsize=7,
            color=color,
        )
    ax.set_xlim(-spacing * 0.6, (len(frames) - 0.4) * spacing)
    lo, hi = float(np.min(xy[..., 1])), float(np.max(xy[..., 1]))
    ax.set_ylim(lo - 0.25 * (hi - lo + 1e-9), hi + 0.05 * (hi - lo + 1e-9))
    ax.set_aspect("equal")
    ax.axis("off")
    return fig


def plot_beat_timeline(
    motion: Any,
    *,
    beats: Any = None,
    motion_beats: Any = None,
    boundaries: Any = None,
    ax: Any = None,
    smooth: float = 0.05,
) -> Any:
    """Mean joint speed over time (Gaussian-smoothed over ``smooth`` [s]) with music
    ``beats`` (red lines), kinematic ``motion_beats`` (dots) and period ``boundaries``
    (dashed), all [s]; returns the Figure."""

    import matplotlib.pyplot as plt

    from .motion_beats import motion_positions, speed_curve

    speed = speed_curve(motion_positions(motion), fps=motion.fps, smooth=smooth)
    t = frames_to_time(np.arange(speed.size), fps=motion.fps)
    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 2.4))
    else:
        fig = ax.figure
    ax.plot(t, speed, color=_POSE_COLOR, lw=1, label="mean joint speed")
    if beats is not None:
        b = check_times(beats, name="beats")
        b = b[b <= t[-1]]
        for i, x in enumerate(b):
            ax.axvline(
                x, color=_BEAT_COLOR, lw=0.8, alpha=0.7, label="music beat" if i == 0 else None
            )
    if boundaries is not None:
        s = check_times(boundaries, name="boundaries")
        for i, x in enumerate(s):
            ax.axvline(x, color="0.5", lw=1.2, ls="--", label="period boundary" if i == 0 else None)
    if motion_beats is not None:
        mb = check_times(motion_beats, name="motion_beats")
        ax.plot(mb, np.interp(mb, t, speed), "o", ms=4, color="#1f77b4", label="motion beat")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("speed [unit/s]")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=7, ncol=4, frameon=False)
    return fig


def save_figure(fig: Any, path: str | os.PathLike[str], *, dpi: int = 100) -> Path:
    """Save a matplotlib figure atomically; the format follows the suffix (PNG, PDF, SVG)."""
    from .io import atomic_write

    dest = Path(path)
    fmt = dest.suffix.lstrip(".").lower() or "png"
    with atomic_write(dest, "wb") as fh:
        # fixed metadata so PNG/PDF bytes do not depend on the date or version
        meta = {"Software": None} if fmt == "png" else {}
        fig.savefig(fh, format=fmt, dpi=dpi, bbox_inches="tight", metadata=meta)
    return dest


def find_ffmpeg() -> str | None:
    """Path of an ffmpeg binary: imageio-ffmpeg's bundled one, else ``ffmpeg`` on PATH."""
    try:
        import imageio_ffmpeg

        exe = imageio_ffmpeg.get_ffmpeg_exe()
        if exe and Path(exe).is_file():
            return str(exe)
    except Exception:  # noqa: BLE001 - any failure means "not available"
        pass
    return shutil.which("ffmpeg")


class _Stage:
    """Draws the dancer in perspective into a Pillow image per frame (H.264's YCbCr for
    ffmpeg, RGB for the GIF fallback).

    The camera looks from ``azimuth`` [deg] about the vertical axis and ``elevation``
    [deg] above the floor at the joints' horizontal centroid smoothed over a second, so
    steps move the figure over a floor grid fixed in the world; the dancer's height sets
    the distance (the figure fills a little over half the frame whatever the units).
    Bones are drawn far to near over their shadows; on a beat the figure turns red and a
    dot lights; a ruler at the bottom scrolls the beats within 2 s past a playhead. The
    geometry of all frames is planned at once (:meth:`_plan`).
    """

    def __init__(
        self,
        pos: np.ndarray,
        bones: np.ndarray,
        names: list[str],
        *,
        up: int,
        azimuth: float,
        elevation: float,
        fps: float,
        size: tuple[int, int],
        title: str,
        mode: str = "YCbCr",
    ):
        from PIL import Image, ImageDraw, ImageFont
        from scipy.ndimage import gaussian_filter1d

        w, h = size
        self.size, self.bones, self.mode = size, bones, mode
        # world -> (h1, h2, up) with the vertical last: a right-handed frame
        order = [(up + 1) % 3, (up + 2) % 3, up]
        p = pos[..., order]
        self.floor = float(np.percentile(p[..., 2].min(axis=1), 1))
        height = float(np.percentile(np.ptp(p[..., 2], axis=1), 95)) or 1.0
        # the camera's target: the joints' centroid's horizontal track, smoothed over a
        # second so that the view does not shake with the hips; extended beyond both ends
        # by point reflection, so that it keeps up with a dancer still travelling there
        pad = min(4 * int(np.ceil(fps)), len(p) - 1)
        ext = np.pad(p.mean(axis=1)[:, :2], ((pad, pad), (0, 0)), "reflect", reflect_type="odd")
        track = gaussian_filter1d(ext, sigma=fps, axis=0, mode="nearest")[pad : pad + len(p)]
        a, e = np.deg2rad(azimuth), np.deg2rad(elevation)
        # at azimuth 0 the image's horizontal axis is h2, as in :func:`project`
        right = np.array([-np.sin(a), np.cos(a), 0.0])
        back = np.array([np.cos(a), np.sin(a), 0.0])  # from the dancer towards the camera
        fwd = -(np.cos(e) * back) - np.sin(e) * np.array([0.0, 0.0, 1.0])
        cam_up = np.cross(right, fwd)
        self.f = 0.5 * h / np.tan(np.deg2rad(20.0))  # 40 degrees vertical field of view
        # the figure about 0.55 of the frame high, aimed a little below its middle: room
        # for raised arms above, and for the shadows and the beat ruler below
        dist = self.f * height / (0.55 * h)
        target = np.column_stack([track, np.full(len(track), self.floor + 0.45 * height)])
        self.eye = target - dist * fwd
        self.basis = np.stack([right, cam_up, fwd])  # rows: camera x, y, depth
        self.centre = np.array([w / 2.0, h / 2.0])
        self.joints = self._screen(p)
        shadow = p.copy()
        shadow[..., 2] = self.floor
        self.shadow = self._screen(shadow)
        self.thick = 0.045 * height
        self.head = _head_joint(p, bones, names)
        self.height = height
        self.grid = self._grid_segments(track, height)
        self.draw_module = ImageDraw
        self.font = ImageFont.load_default(size=max(11, h // 32))
        # sky above the horizon, floor below: the same for every frame
        horizon = int(np.clip(self.centre[1] - self.f * np.tan(e), 0, h))
        bg = Image.new(mode, (w, h), self._ink(_SKY))
        ImageDraw.Draw(bg).rectangle((0, horizon, w, h), fill=self._ink(_FLOOR))
        self.background = bg
        self.palette = tuple(self._ink(c) for c in (_GRID, _SHADOW, _RED, (30, 30, 30)))
        # the title once, on the background; each frame writes only its time after it
        title_box = ImageDraw.Draw(bg).textbbox((8, 6), title, font=self.font)
        ImageDraw.Draw(bg).text((8, 6), title, fill=self.palette[3], font=self.font)
        self.clock_at = (title_box[2] + 12, 6)
        self._plan()

    def _screen(self, p: np.ndarray) -> np.ndarray:
        """(x, y, depth) in pixels of points ``p`` [shape=(n_frames, k, 3)]."""
        return self._pixels((p - self.eye[:, None, :]) @ self.basis.T)

    def _pixels(self, c: np.ndarray) -> np.ndarray:
        """(x, y, depth) in pixels of camera coordinates ``c`` [shape=(..., 3)]."""
        z = np.maximum(c[..., 2], 1e-6)
        x = self.centre[0] + self.f * c[..., 0] / z
        y = self.centre[1] - self.f * c[..., 1] / z
        return np.stack([x, y, c[..., 2]], axis=-1)

    def _grid_segments(self, track: np.ndarray, height: float) -> np.ndarray:
        """Screen segments [shape=(n_frames, n_lines, 4)] of the floor grid, NaN where
        a line lies behind the camera. Lines about a metre apart (0.6 of the dancer's
        height), out to three heights beyond where the dancer goes."""
        step = 0.6 * height
        c0 = np.round(np.median(track, axis=0) / step) * step
        reach = np.ptp(track, axis=0).max() / 2 + 3 * height
        ticks = np.arange(-reach, reach + step / 2, step)
        lines = []
        for u in ticks:
            lines.append(((c0[0] + u, c0[1] - reach), (c0[0] + u, c0[1] + reach)))
            lines.append(((c0[0] - reach, c0[1] + u), (c0[0] + reach, c0[1] + u)))
        ends = np.asarray(lines, dtype=np.float64)  # (n_lines, 2, 2)
        ends = np.concatenate([ends, np.full(ends.shape[:2] + (1,), self.floor)], axis=-1)
        # clip each line to the part in front of the camera (depth >= near), per frame
        cam = (ends[None, :, :, :] - self.eye[:, None, None, :]) @ self.basis.T
        near = 0.3 * height
        d0, d1 = cam[..., 0, 2], cam[..., 1, 2]
        s0 = np.clip((near - d0) / np.where(d1 != d0, d1 - d0, 1e-12), 0, 1)
        s1 = np.clip((near - d1) / np.where(d0 != d1, d0 - d1, 1e-12), 0, 1)
        span = cam[..., 1, :] - cam[..., 0, :]
        a = cam[..., 0, :] + np.where(d0 < near, s0, 0)[..., None] * span
        b = cam[..., 1, :] - np.where(d1 < near, s1, 0)[..., None] * span
        seg = np.concatenate([self._pixels(a)[..., :2], self._pixels(b)[..., :2]], axis=-1)
        w, h = 2 * self.centre
        behind = (d0 < near) & (d1 < near)
        outside = ((seg[..., 0] < 0) & (seg[..., 2] < 0)) | ((seg[..., 0] > w) & (seg[..., 2] > w))
        outside |= (seg[..., 1] > h) & (seg[..., 3] > h)
        seg[behind | outside] = np.nan
        return seg

    def _ink(self, rgb: Any) -> tuple[int, int, int]:
        """One sRGB colour in the frame's mode (see :func:`_colours`)."""
        return tuple(_colours(np.asarray(rgb, dtype=np.float64), self.mode).tolist())

    def _plan(self) -> None:
        """Everything a frame draws, for all frames at once (numpy), as Python lists:
        the per-frame loop in :meth:`draw` then only calls Pillow."""
        n = len(self.joints)
        z = self.joints[..., 2]
        width = np.maximum(self.f * self.thick / np.maximum(z, 1e-6), 2.0)
        self.grid_ops = [
            [tuple(seg) for seg in frame[frame[:, 0] == frame[:, 0]].tolist()]
            for frame in self.grid
        ]
        b0, b1 = self.bones[:, 0], self.bones[:, 1]
        sh = self.shadow
        shadow = np.concatenate(
            [sh[:, b0, :2], sh[:, b1, :2], (0.8 * width[:, b0])[..., None].astype(int)], axis=-1
        )
        self.shadow_ops = [[(tuple(o[:4]), int(o[4])) for o in f] for f in shadow.tolist()]
        # bones far to near; each in the tone and with the round cap of its far end
        order = np.argsort(-(z[:, b0] + z[:, b1]), axis=1, kind="stable")
        i = np.take_along_axis(np.broadcast_to(b0, order.shape), order, axis=1)
        j = np.take_along_axis(np.broadcast_to(b1, order.shape), order, axis=1)
        rows = np.arange(n)[:, None]
        far = np.where(z[rows, i] > z[rows, j], i, j)
        r = np.rint(np.minimum(width[rows, i], width[rows, j])).astype(int)
        q = self.joints
        ends = np.concatenate([q[rows, i, :2], q[rows, j, :2]], axis=-1)
        cap = np.concatenate(
            [q[rows, far, :2] - r[..., None] / 2, q[rows, far, :2] + r[..., None] / 2], -1
        )
        # farther joints fade towards the floor's colour: depth at a glance
        span = np.maximum(np.ptp(z, axis=1, keepdims=True), 1e-9)
        depth = 0.45 * (z - z.min(axis=1, keepdims=True)) / span
        self.tones = {}
        for beat, rgb in ((False, _FIGURE), (True, _RED)):
            base = np.asarray(rgb, dtype=np.float64)
            tone = base + depth[..., None] * (np.asarray(_FLOOR, dtype=np.float64) - base)
            self.tones[beat] = _colours(tone, self.mode)
        self.bone_ops = [
            list(zip(map(tuple, e), map(tuple, c), f, rr, strict=True))
            for e, c, f, rr in zip(
                ends.tolist(), cap.tolist(), far.tolist(), r.tolist(), strict=True
            )
        ]
        if self.head is not None:
            rad = self.f * 0.055 * self.height / np.maximum(z[:, self.head], 1e-6)
            c = q[:, self.head, :2]
            self.head_ops = [
                tuple(b) for b in np.concatenate([c - rad[:, None], c + rad[:, None]], 1).tolist()
            ]
        self.dots = (np.maximum(self.f * self.thick / np.maximum(z, 1e-6) / 2, 1.5)).tolist()

    def draw(self, k: int, t: float, beat: bool, ruler: np.ndarray) -> Any:
        """Frame ``k`` at time ``t`` [s]; ``ruler``: beats within 2 s of ``t`` [s]."""
        im = self.background.copy()
        d = self.draw_module.Draw(im)
        w, h = self.size
        grid, shadow, red, dark = self.palette
        for seg in self.grid_ops[k]:
            d.line(seg, fill=grid, width=1)
        for seg, width in self.shadow_ops[k]:
            d.line(seg, fill=shadow, width=width)
        tone = list(map(tuple, self.tones[beat][k].tolist()))
        for seg, cap, n, width in self.bone_ops[k]:
            d.line(seg, fill=tone[n], width=width)
            d.ellipse(cap, fill=tone[n])
        if not len(self.bones):
            for (x, y, _), rad, c in zip(self.joints[k].tolist(), self.dots[k], tone, strict=True):
                d.ellipse((x - rad, y - rad, x + rad, y + rad), fill=c)
        if self.head is not None:
            d.ellipse(self.head_ops[k], fill=tone[self.head])
        # the beat ruler: 4 s of beats scrolling past the playhead in the middle
        y = h - max(14, h // 24)
        d.line((0, y, w, y), fill=grid, width=1)
        for b in ruler.tolist():
            x = w / 2 + (b - t) * w / 4
            d.line((x, y - 6, x, y + 6), fill=red, width=2)
        d.line((w / 2, y - 10, w / 2, y + 10), fill=dark, width=2)
        if beat:
            r = max(8, h // 30)
            d.ellipse((w - 3 * r, 1 * r, w - r, 3 * r), fill=red)
        d.text(self.clock_at, f"t = {t:6.2f} s", fill=dark, font=self.font)
        return im


def _video_frames(
    motion: Any, fps: float, beats: np.ndarray | None, duration: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output times [s], the motion frame shown at each, and whether a beat is lit."""
    last = (motion.n_frames - 1) / motion.fps if duration is None else duration - 1.0 / fps
    n_out = int(np.floor(max(last, 0.0) * fps + 1e-9)) + 1
    t = frames_to_time(np.arange(n_out), fps=fps)
    src = np.clip(time_to_frames(t, fps=motion.fps), 0, motion.n_frames - 1)
    # a beat lights up for 0.1 s (at least one frame)
    flash = max(0.1, 1.0 / fps)
    on = np.zeros(n_out, dtype=bool)
    if beats is not None and len(beats):
        idx = np.searchsorted(beats, t, side="right") - 1
        ok = idx >= 0
        on[ok] = (t[ok] - beats[idx[ok]]) < flash - 1e-9
    return t, src, on


def write_video(
    motion: Any,
    path: str | os.PathLike[str],
    *,
    audio: tuple[np.ndarray, int] | None = None,
    fps: float | None = None,
    beats: Any = None,
    size: tuple[int, int] = (640, 480),
    up: str | None = None,
    azimuth: float = 30.0,
    elevation: float = 12.0,
    title: str | None = None,
    ffmpeg: str | bool | None = None,
    progress: bool | Callable[[int, int], None] = False,
    duration: float | None = None,
    preset: str = "ultrafast",
) -> Path:
    """Write a video of ``motion`` seen in perspective (:class:`_Stage`), with the music.

    ``audio`` is ``(y, sr)`` from motion time 0, cut to the video's length. ``fps`` [Hz]
    defaults to the motion's (frames are picked, not interpolated). From each of
    ``beats`` [s] the figure is red for 0.1 s. ``size`` [px] is rounded to even numbers.
    ``azimuth`` [deg] 0 is :func:`plot_frames`' side view; ``elevation`` [deg, 0-80] the
    camera's angle down on the dancer. ``ffmpeg``: a binary, ``None`` to find one
    (:func:`find_ffmpeg`), ``False`` for the GIF + WAV fallback. ``progress``: True for a
    tqdm bar, or ``progress(done, total)`` after each frame. ``duration`` [s] longer than
    the motion holds the last pose. ``preset``: x264's speed/size trade-off
    (``"veryfast"`` files are about three times smaller than ``"ultrafast"`` ones).

    Returns ``path``, or ``path`` with suffix ``.gif`` in the fallback (the music then
    beside it as ``.wav``).
    """
    from .io import check_output_folder

    dest = Path(path)
    parent = check_output_folder(dest)
    fps = check_motion_fps(motion.fps if fps is None else fps, name="video fps")
    w, h = (int(size[0]) // 2 * 2, int(size[1]) // 2 * 2)
    if w < 32 or h < 32:
        raise ParameterError(f"size={size!r} is too small; give (width, height) in pixels >= 32")
    beats_arr = None if beats is None else check_times(beats, name="beats")
    if duration is not None:
        duration = check_positive(duration, name="duration", unit="s")
    y_sr = None
    if audio is not None:
        try:
            y, sr = audio
        except (TypeError, ValueError):
            raise ParameterError(f"audio={type(audio).__name__} is not a pair (y, sr)") from None

        y, sr = check_audio(y, sr, name="audio")
        y_sr = (np.asarray(y, dtype=np.float32), int(sr))

    if not 0.0 <= float(elevation) <= 80.0:
        raise ParameterError(f"elevation={elevation!r} must be in [0, 80] degrees")
    check_choice(preset, _PRESETS, name="preset")
    exe = find_ffmpeg() if ffmpeg is None else (ffmpeg or None)
    t, src, on = _video_frames(motion, fps, beats_arr, duration)
    pos, bones = pose_positions(motion)
    stage = _Stage(
        pos[src], bones, list(getattr(motion, "joint_names", [])),
        up=_up_axis(motion, up), azimuth=float(azimuth), elevation=float(elevation),
        fps=fps, size=(w, h), title=motion.name if title is None else title,
        mode="YCbCr" if exe is not None else "RGB",
    )  # fmt: skip
    ruler = _rulers(t, beats_arr)
    frames_iter: Any = range(len(t))
    if callable(progress):
        frames_iter = _reporting(frames_iter, progress)
    elif progress:
        from tqdm import tqdm

        frames_iter = tqdm(frames_iter, desc="video", unit="frame", leave=False)
    frames = (stage.draw(k, float(t[k]), bool(on[k]), ruler[k]) for k in frames_iter)
    if y_sr is not None:  # the music cut to the video's length
        y, sr = y_sr
        y_sr = (y[: int(np.ceil(len(t) / fps * sr))], sr)
    if exe is None:
        return _write_gif(dest, frames, fps, y_sr)

    with tempfile.TemporaryDirectory(dir=parent, prefix=".beatsync-video-") as tmp:
        tmp_video = Path(tmp) / ("out" + (dest.suffix or ".mp4"))
        cmd = [
            str(exe), "-y", "-loglevel", "error",
            "-f", "rawvideo", "-vcodec", "rawvideo", "-pix_fmt", "yuv420p",
            "-s", f"{w}x{h}", "-r", f"{fps:.6f}", "-i", "-",
        ]  # fmt: skip
        if y_sr is not None:
            from .io import write_audio

            cmd += ["-i", str(write_audio(Path(tmp) / "audio.wav", *y_sr))]
        cmd += ["-c:v", "libx264", "-preset", preset, "-crf", "23"]
        if y_sr is not None:
            cmd += ["-c:a", "aac", "-b:a", "128k"]
        cmd += ["-movflags", "+faststart", str(tmp_video)]
        try:
            proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
        except OSError as exc:
            raise ParameterError(f"cannot run ffmpeg {exe!r}: {exc}") from None
        assert proc.stdin is not None
        # a thread writes each frame to ffmpeg while the next one is drawn (the write
        # waits for ffmpeg, with the GIL released); at most 4 frames wait in between
        pending: deque[Future[int]] = deque()
        with ThreadPoolExecutor(1) as writer:
            try:
                for im in frames:
                    pending.append(writer.submit(proc.stdin.write, _yuv420(im)))
                    if len(pending) > 4:
                        pending.popleft().result()
                while pending:
                    pending.popleft().result()
                proc.stdin.close()
            except BrokenPipeError:
                pass
            except BaseException:  # Ctrl-C, SIGTERM, a drawing error: no ffmpeg left behind
                proc.kill()
                proc.wait()
                raise
        err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
        code = proc.wait()
        if code != 0 or not tmp_video.is_file():
            raise ParameterError(f"ffmpeg failed (exit {code}) writing {str(dest)!r}: {err[-400:]}")
        os.replace(tmp_video, dest)
    return dest


_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow")
_SKY, _FLOOR, _GRID, _SHADOW = (226, 232, 240), (206, 203, 196), (178, 174, 166), (160, 156, 150)
_RED, _FIGURE = (214, 39, 40), (40, 52, 82)


def _colours(rgb: np.ndarray, mode: str) -> np.ndarray:
    """sRGB colours [0-255, shape=(..., 3)] as ints in a frame's mode: ``"YCbCr"`` is
    H.264's limited-range BT.601 (ffmpeg then converts nothing, a third of its work),
    ``"RGB"`` (the GIF fallback) is rounded as it is."""
    if mode != "YCbCr":
        return np.rint(rgb).astype(int)
    m = np.array([[65.481, 128.553, 24.966], [-37.797, -74.203, 112.0], [112.0, -93.786, -18.214]])
    return np.rint(rgb @ m.T / 255 + np.array([16.0, 128.0, 128.0])).astype(int)


def _yuv420(im: Any) -> bytes:
    """A YCbCr frame as planar 4:2:0 bytes (chroma of every other pixel and row)."""
    _, cb, cr = im.resize((im.width // 2, im.height // 2), 0).split()  # 0: nearest
    return im.getchannel(0).tobytes() + cb.tobytes() + cr.tobytes()


def _head_joint(p: np.ndarray, bones: np.ndarray, names: list[str]) -> int | None:
    """The joint drawn as a head: one named so, else the highest joint (median over
    frames, ``p`` z-up) if it ends a single bone; None if neither."""
    named = [i for i, n in enumerate(names) if "head" in n.lower()]
    if named:
        return named[-1]
    if not len(bones):
        return None
    top = int(np.argmax(np.median(p[..., 2], axis=0)))
    return top if int(np.sum(bones == top)) == 1 else None


def _rulers(t: np.ndarray, beats: np.ndarray | None) -> list[np.ndarray]:
    """The beats within 2 s of each output time (the ruler at the bottom of a frame)."""
    if beats is None or not len(beats):
        return [np.zeros(0)] * len(t)
    lo = np.searchsorted(beats, t - 2.0)
    hi = np.searchsorted(beats, t + 2.0)
    return [beats[a:b] for a, b in zip(lo, hi, strict=True)]


def _reporting(frames: range, progress: Callable[[int, int], None]) -> Iterator[int]:
    """The frame indices, calling ``progress(done, total)`` after each one."""
    total = len(frames)
    for done, k in enumerate(frames, start=1):
        yield k
        progress(done, total)


def _write_gif(dest: Path, frames: Iterator[Any], fps: float, audio: Any) -> Path:
    """Without ffmpeg: the frames as an animated GIF, the ``audio`` as a WAV beside it."""
    from .io import atomic_write, write_audio

    gif, wav = dest.with_suffix(".gif"), dest.with_suffix(".wav")
    images = list(frames)
    with atomic_write(gif, "wb") as fh:
        images[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(round(1000 / fps)),
            loop=0,
        )
    msg = f"no ffmpeg found: wrote the animation as {str(gif)!r} without sound"
    if audio is not None:
        write_audio(wav, *audio)
        msg += f" and the music as {str(wav)!r}; play them together"
    msg += " (install ffmpeg or `pip install imageio-ffmpeg` for an MP4 with sound)"
    warn(msg, stacklevel=3)
    return gif
