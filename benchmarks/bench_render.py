"""Time the video renderer against an earlier revision's, on a real dancer and a song.

A real dancer (Dance-with-Melody ``DANCE_C_4``, 24 s of joint positions) is looped to
the length of a song (default 4 minutes, the dancer's own song tiled) and written as an
MP4 with sound by :func:`beatsync.render.write_video` of this working tree and of the
``--base`` revision (imported from ``git archive`` as ``beatsync_base``), in turn, at
25 fps and each renderer's default size. The time is the whole call (drawing, H.264
encoding, the soundtrack); the target is 20 times faster than real time (a 4-minute
song in at most 12 s).

Usage::

    .venv/bin/python benchmarks/bench_render.py --base 65844eb
    .venv/bin/python benchmarks/bench_render.py --base 65844eb --seconds 60 --rounds 2
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from pathlib import Path

import _machine
import numpy as np
from compare_revisions import load_revision

ROOT = Path(__file__).resolve().parent.parent


def dancer_and_song(seconds: float):
    """The looped dancer (25 fps), the tiled song (y, sr) and its beats [s]."""
    from beatsync import beats, io

    folder = ROOT / "data" / "motion" / "dance_with_melody" / "DANCE_C_4"
    motion = io.read_motion(folder / "skeletons.json", fps=25.0)
    n = int(round(seconds * motion.fps))
    values = np.resize(motion.values, (n, motion.values.shape[1]))
    looped = dataclasses.replace(motion, values=values)
    y, sr = io.read_audio(folder / "audio.ogg", sr=22050)
    song = np.resize(y, int(seconds * sr))
    period = beats.track_beats(y, sr).beats
    beat_times = np.arange(period[0], seconds, float(np.median(np.diff(period))))
    return looped, (song, sr), beat_times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the revision whose renderer is compared")
    ap.add_argument("--seconds", type=float, default=240.0, help="song length [s]")
    ap.add_argument("--rounds", type=int, default=1, help="calls of each renderer")
    args = ap.parse_args()

    import beatsync.render as new

    with tempfile.TemporaryDirectory() as tmp:
        base = load_revision(args.base, Path(tmp)).__name__.split(".")[0]
        import importlib

        old = importlib.import_module(f"{base}.render")
        motion, audio, beat_times = dancer_and_song(args.seconds)
        times: dict[str, list[float]] = {"base": [], "new": []}
        sizes: dict[str, int] = {}
        for r in range(args.rounds):
            order = [("base", old), ("new", new)] if r % 2 == 0 else [("new", new), ("base", old)]
            for name, module in order:
                out = Path(tmp) / f"{name}.mp4"
                t0 = time.perf_counter()
                module.write_video(motion, out, audio=audio, beats=beat_times, fps=25.0)
                times[name].append(time.perf_counter() - t0)
                sizes[name] = out.stat().st_size
                os.remove(out)
    best = {k: min(v) for k, v in times.items()}
    lines = [
        "## Video rendering (`bench_render.py`)",
        "",
        f"Command: `.venv/bin/python benchmarks/bench_render.py --base {args.base} "
        f"--seconds {args.seconds:g} --rounds {args.rounds}`. A real dancer (DANCE_C_4) "
        f"looped to a {args.seconds:g} s song at 25 fps, written as MP4 with sound; the "
        "whole `write_video` call, fastest of the rounds.",
        "",
        "| renderer | size | time [s] | x real time | file [MB] |",
        "|---|---|---|---|---|",
        f"| {args.base} (matplotlib side view) | 480x360 | {best['base']:.1f} | "
        f"{args.seconds / best['base']:.1f} | {sizes['base'] / 1e6:.1f} |",
        f"| this tree (perspective, following camera) | 640x480 | {best['new']:.1f} | "
        f"{args.seconds / best['new']:.1f} | {sizes['new'] / 1e6:.1f} |",
        "",
        f"New / base time: {best['new'] / best['base']:.2f}. Target: at least 20x real time "
        f"({'met' if args.seconds / best['new'] >= 20 else 'NOT met'}).",
        f"Load average during the run: {os.getloadavg()[0]:.2f}.",
        "",
    ]
    _machine.write_results(
        "render", {"times_s": times, "sizes_bytes": sizes, **_machine.machine_facts()}, lines
    )


if __name__ == "__main__":
    main()
