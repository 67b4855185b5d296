"""Benchmark of beat-synchronous resampling (paper A, section 5).

End to end on the 37 s CMU salsa clip (60_01, 2242 frames at 60 fps, 132 channels)
with a 60 s song (synthetic drum pattern at 118 BPM, 44.1 kHz: stands in for a real
song), on one core, against the time of beat tracking alone measured in the same run
(the baseline: any synchronisation tool must at least track the beats).

Measured: reading the files, segmentation, beat tracking, synchronisation (warp +
slerp resampling), writing the BVH; the whole ``beatsync sync`` command (paper A's
behaviour: ``--mode periods --fill stop --period-range 0.25 1.25``); and the boundary
residual of the result.

Long dance on a whole song: ``beatsync sync`` of a 90 s dancer on a 4 min song with
the defaults (``--mode auto --fill loop``: the dance is repeated to the song's last
beat), as a separate process (interpreter start, imports, reading, beat tracking,
segmentation, looping, resampling, writing), against beat tracking of the same song
in the same run; target under 15 s. The dancer is the bundled 24 s excerpt of the real
rumba dancer DANCE_R_3 (Dance-with-Melody, 23 joint positions, 25 fps, JSON) tiled to
90 s (the full take is 89.4 s; only the excerpt is bundled); the song a synthetic drum
pattern of 4 min at 44.1 kHz. For comparison, the same with a 60 fps BVH dancer: the
salsa clip 60_01's 1 s step tiled to 90 s (no target).

Usage::

    .venv/bin/python benchmarks/bench_sync.py [--repeats 3]

Writes ``benchmarks/results/sync.md`` and ``benchmarks/results/sync.json``.
"""

from __future__ import annotations

import os

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io as _stdio  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

TARGET_E2E_S = 10.0
TARGET_LONG_S = 15.0
LONG_DANCE_S = 90.0
LONG_SONG_S = 240.0
SONG_S = 60.0
SONG_BPM = 118.0
SR = 44100


def _median_time(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def _long_dance(tmp: Path, dancer, path_name: str, what: str, repeats: int) -> dict:
    """``beatsync sync`` of a 90 s dancer on a 4 min song, as its own process."""
    import json
    import subprocess

    from beatsync import io
    from beatsync.beats import track_beats
    from beatsync.synth.audio import beat_times, drum_pattern

    dance_path = io.write_motion(tmp / path_name, dancer)
    song = tmp / "song4min.wav"
    y = drum_pattern(
        beat_times(SONG_BPM, duration=LONG_SONG_S, start=0.4), sr=SR, duration=LONG_SONG_S
    )
    io.write_audio(song, y, SR)
    t_beats, _ = _median_time(lambda: track_beats(y, SR), repeats)
    out, rep = tmp / f"long{dance_path.suffix}", tmp / "long_report.json"
    cmd = [sys.executable, "-m", "beatsync.cli", "sync", str(dance_path), str(song), "-o",
           str(out), "--report", str(rep), "--json"]  # fmt: skip
    if dance_path.suffix == ".json":
        cmd += ["--fps", f"{dancer.fps:g}"]
    t_process, proc = _median_time(
        lambda: subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ)),
        repeats,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"long sync failed: {proc.stderr[-400:]}")
    r = json.loads(rep.read_text())["report"]
    return {
        "t_beats": t_beats,
        "t_process": t_process,
        "dancer": what,
        "song": f"synthetic drum pattern, {SONG_BPM:g} BPM, {LONG_SONG_S:g} s, {SR} Hz",
        "command": f"beatsync sync {dance_path.name} song4min.wav -o {out.name}",
        "mode": r["mode"],
        "repetitions": r["repetitions"],
        "output_duration_s": r["output_duration_s"],
        "last_beat_s": float(r["covered_s"][1]),
        "max_abs_residual_frames": r["max_abs_residual_frames"],
    }


def _long_dancers(motion) -> list[tuple]:
    """The real 90 s dancer (target) and the 60 fps BVH stand-in (for comparison)."""
    from beatsync import datasets

    real = datasets.load_dance_pair("DANCE_R_3").motion
    n = int(round(LONG_DANCE_S * real.fps))
    real90 = real.with_values(np.resize(real.values, (n, real.n_channels)))
    step = motion.values[60:120].copy()  # one 1 s step of 60_01, root held: whole steps
    step[:, :3] = step[0, :3]
    m = int(round(LONG_DANCE_S * motion.fps))
    salsa90 = motion.with_values(np.resize(step, (m, step.shape[1])))
    return [
        (real90, "dancer90.json", f"real rumba dancer DANCE_R_3 excerpt tiled to "
         f"{LONG_DANCE_S:g} s ({n} frames, 23 joint positions at 25 fps, JSON)"),
        (salsa90, "dancer90.bvh", f"salsa 60_01 step tiled to {LONG_DANCE_S:g} s ({m} "
         "frames at 60 fps, BVH)"),
    ]  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})

    from beatsync import datasets, io
    from beatsync.beats import track_beats
    from beatsync.cli import main as cli_main
    from beatsync.segment import segment
    from beatsync.sync import synchronize
    from beatsync.synth.audio import beat_times, drum_pattern

    clip = datasets.path("motion/cmu_salsa/60_01_scaled.bvh")
    ref_beats = beat_times(SONG_BPM, duration=SONG_S, start=0.4)
    y = drum_pattern(ref_beats, sr=SR, duration=SONG_S)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        song = io.write_audio(tmp / "song.wav", y, SR)

        t_read, (motion, (ya, sra)) = _median_time(
            lambda: (io.read_bvh(clip, fps=60.0), io.read_audio(song)), args.repeats
        )
        t_seg, seg = _median_time(lambda: segment(motion), args.repeats)
        t_beats, track = _median_time(lambda: track_beats(ya, sra), args.repeats)
        t_sync, res = _median_time(
            lambda: synchronize(motion, seg.boundaries, track.beats), args.repeats
        )
        t_write, _ = _median_time(lambda: io.write_bvh(tmp / "out.bvh", res.motion), args.repeats)

        def _cli():
            with contextlib.redirect_stdout(_stdio.StringIO()):
                code = cli_main(["sync", str(clip), str(song), "-o", str(tmp / "cli.bvh"),
                                 "--fps", "60", "--mode", "periods", "--fill", "stop",
                                 "--period-range", "0.25", "1.25"])
            assert code == 0
            return code

        t_cli, _ = _median_time(_cli, args.repeats)
        long, long_bvh = (
            _long_dance(tmp, d, name, what, args.repeats) for d, name, what in _long_dancers(motion)
        )

    rep = res.report
    t_e2e = t_read + t_seg + t_beats + t_sync + t_write
    for name, t in [
        ("read BVH + audio", t_read),
        ("segment (periods)", t_seg),
        ("track_beats (baseline)", t_beats),
        ("synchronize (warp + slerp resampling)", t_sync),
        ("write BVH", t_write),
        ("sum of stages", t_e2e),
        ("`beatsync sync` command (cli.main in process, with file I/O)", t_cli),
    ]:
        rows.append({"step": name, "seconds": t, "ratio_to_beat_tracking": t / t_beats})

    for name, t in [
        (f"long: track_beats on the {LONG_SONG_S / 60:g} min song (baseline)", long["t_beats"]),
        (f"long: `beatsync sync` {LONG_DANCE_S:g} s real dancer (JSON, 25 fps) on a "
         f"{LONG_SONG_S / 60:g} min song, defaults (loop), whole process", long["t_process"]),
        (f"long, for comparison: {LONG_DANCE_S:g} s BVH dancer (60 fps) on the same song, "
         "whole process", long_bvh["t_process"]),
    ]:
        rows.append({"step": name, "seconds": t, "ratio_to_beat_tracking": t / long["t_beats"]})
    residual_frames = float(rep["max_abs_residual_frames"])
    passed_res = residual_frames <= 1.0
    passed_time = t_cli < TARGET_E2E_S
    passed_long = long["t_process"] < TARGET_LONG_S
    facts = {
        "command": f"python benchmarks/bench_sync.py --repeats {args.repeats}",
        **_machine.machine_facts(),
        "repeats": args.repeats,
    }
    data = {
        "facts": facts,
        "input": {
            "motion": "CMU salsa 60_01 (37.4 s, 2242 frames at 60 fps, 132 channels)",
            "music": f"synthetic drum pattern, {SONG_BPM:g} BPM, {SONG_S:g} s, {SR} Hz "
            "(stands in for a real song)",
        },
        "rows": rows,
        "sync": {
            "periods_used": rep["periods_used"],
            "beats_per_period": rep["beats_per_period"],
            "output_frames": rep["output_frames"],
            "max_abs_residual_ms": rep["max_abs_residual_ms"],
            "max_abs_residual_frames": residual_frames,
            "tempo_ratio_range": rep["tempo_ratio_range"],
            "n_beats": int(len(track.beats)),
            "tempo_bpm": float(track.tempo),
        },
        "long": {k: v for k, v in long.items() if not k.startswith("t_")},
        "long_bvh": {k: v for k, v in long_bvh.items() if not k.startswith("t_")},
        "targets": {
            "boundary residual <= 1 output frame": passed_res,
            f"end to end < {TARGET_E2E_S:g} s on one core": passed_time,
            f"{LONG_DANCE_S:g} s dancer on a {LONG_SONG_S / 60:g} min song < "
            f"{TARGET_LONG_S:g} s whole process": passed_long,
        },
    }
    lines = [
        "## sync: beat-synchronous resampling (paper A, sec. 5)",
        "",
        f"Command: `{facts['command']}`  ",
        f"Machine: {facts['platform']}, {facts['processor']}, {facts['cpu_count']} CPUs "
        f"(1 used), Python {facts['python']}, numpy {facts['numpy']}, beatsync "
        f"{facts['beatsync']}; {facts['date_utc']}; median of {args.repeats} runs; load "
        f"average {facts['load_average']} (a shared machine inflates absolute times: read "
        "the ratios).",
        "",
        f"Input: {data['input']['motion']}; {data['input']['music']}. "
        "Baseline: beat tracking alone (`track_beats`, phase-slope + HMM) in the same run.",
        "",
        f"Long dance: {long['dancer']}; {long['song']}; `{long['command']}`. "
        f"Comparison: {long_bvh['dancer']}.",
        "",
        "| step | time [s] | x beat tracking (of its own song) |",
        "|---|---:|---:|",
    ]
    for r in rows:
        lines.append(f"| {r['step']} | {r['seconds']:.3f} | {r['ratio_to_beat_tracking']:.2f} |")
    s = data["sync"]
    lines += [
        "",
        f"Result: {s['periods_used']} periods, {s['beats_per_period']} beats per period, "
        f"{s['output_frames']} output frames; {s['n_beats']} beats tracked "
        f"({s['tempo_bpm']:.1f} BPM); playback speed x{s['tempo_ratio_range'][0]:.3f}.."
        f"x{s['tempo_ratio_range'][1]:.3f}.",
        "",
        "| target | measured | |",
        "|---|---|---|",
        f"| boundary residual <= 1 output frame at every boundary | max "
        f"{s['max_abs_residual_ms']:.4f} ms on the warp, {s['max_abs_residual_frames']:.2f} "
        f"frame to the nearest frame | {'PASS' if passed_res else 'FAIL'} |",
        f"| end to end < {TARGET_E2E_S:g} s on one core | {t_cli:.2f} s (`beatsync sync`) | "
        f"{'PASS' if passed_time else 'FAIL'} |",
        f"| {LONG_DANCE_S:g} s dancer on a {LONG_SONG_S / 60:g} min song < {TARGET_LONG_S:g} s, "
        f"whole process | {long['t_process']:.2f} s: mode {long['mode']}, "
        f"{long['repetitions']} repetitions, {long['output_duration_s']:.1f} s of dance for "
        f"{long['last_beat_s']:.1f} s to the last beat, residual max "
        f"{long['max_abs_residual_frames']:.2f} frame | {'PASS' if passed_long else 'FAIL'} |",
        "",
    ]
    _machine.write_results("sync", data, lines)
    return 0 if (passed_res and passed_time and passed_long) else 1


if __name__ == "__main__":
    sys.exit(main())
