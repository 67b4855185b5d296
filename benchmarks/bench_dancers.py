"""Benchmark: ``beatsync sync`` of a 90 s real dancer (joint positions) to a 4 min song.

The dancer is the bundled Dance-with-Melody rumba excerpt (``DANCE_R_3``: 24 s, 23
joint positions at 25 fps, the dataset's JSON layout) tiled to 90 s by playing it
forwards and backwards in turn (so the positions stay continuous: no jump at the
joins), written as JSON in the same layout. The song is that excerpt's own song
(28 s, mono 22.05 kHz Ogg Vorbis) repeated to 4 min. The whole command runs as its
own process (interpreter start, imports, reading and gap checks of the JSON, unit and
axis detection, beat tracking, segmentation of the angles between the inferred bones,
``--mode auto --fill loop`` synchronisation, writing the CSV), on one core.

Baseline, measured in the same run: beat tracking of the same 4 min song alone (any
tool that synchronises a dance to a song must at least find its beats). Target: the
whole process under 15 s (wall clock). Its CPU time is recorded too: on a loaded
shared machine the wall clock says more about the load than about beatsync.

Usage::

    .venv/bin/python benchmarks/bench_dancers.py [--repeats 3]

Writes ``benchmarks/results/dancers.md`` and ``benchmarks/results/dancers.json``.
"""

from __future__ import annotations

import os

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import contextlib  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
TARGET_S = 15.0
DANCE_S = 90.0
SONG_S = 240.0
PAIR = "DANCE_R_3"


def _median_time(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def ping_pong(values: np.ndarray, n: int) -> np.ndarray:
    """``values`` played forwards, backwards, forwards... until ``n`` frames."""
    cycle = np.concatenate([values, values[-2:0:-1]])
    reps = int(np.ceil(n / len(cycle)))
    return np.tile(cycle, (reps, 1))[:n]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})

    from beatsync import datasets, io
    from beatsync.beats import track_beats

    pair = datasets.load_dance_pair(PAIR)
    motion = pair.motion
    n = int(round(DANCE_S * motion.fps))
    dancer = motion.with_values(ping_pong(motion.values, n))
    y = np.resize(pair.y, int(SONG_S * pair.sr))
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        dance_path = io.write_motion(tmp / "dancer90.json", dancer)
        song = io.write_audio(tmp / "song4min.wav", y, pair.sr)
        c0 = time.process_time()
        t_beats, _ = _median_time(lambda: track_beats(y, pair.sr), args.repeats)
        cpu_beats = (time.process_time() - c0) / args.repeats
        out, rep = tmp / "synced.csv", tmp / "report.json"
        cmd = [sys.executable, "-m", "beatsync.cli", "sync", str(dance_path), str(song), "-o",
               str(out), "--fps", "25", "--report", str(rep), "--json"]  # fmt: skip
        cpu = []

        def _run():
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            done = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
            return done

        t_proc, proc = _median_time(_run, args.repeats)
        if proc.returncode != 0:
            raise RuntimeError(f"sync of the 90 s dancer failed: {proc.stderr[-600:]}")
        report = json.loads(rep.read_text())["report"]
        out_frames = sum(1 for _ in out.open()) - 1
    result = {
        "dancer": f"{PAIR} excerpt played forwards/backwards to {DANCE_S:g} s ({n} frames at "
        "25 fps, 23 joint positions, JSON)",
        "song": f"{PAIR}'s song excerpt repeated to {SONG_S:g} s ({pair.sr} Hz mono)",
        "command": "beatsync sync dancer90.json song4min.wav -o synced.csv --fps 25",
        "t_beats_s": t_beats,
        "t_process_s": t_proc,
        "ratio_process_to_beats": t_proc / t_beats,
        "cpu_process_s": float(np.median(cpu)),
        "cpu_beats_s": cpu_beats,
        "target_s": TARGET_S,
        "pass": bool(t_proc < TARGET_S),
        "mode": report.get("mode"),
        "repetitions": report.get("repetitions"),
        "output_frames": out_frames,
        "repeats": args.repeats,
        "machine": _machine.machine_facts(),
    }
    md = [
        "## dancers: sync of a 90 s real dancer (joint positions) to a 4 min song\n",
        f"Command: `.venv/bin/python benchmarks/bench_dancers.py --repeats {args.repeats}` "
        f"(one core, median of {args.repeats}). Dancer: {result['dancer']}. Song: "
        f"{result['song']}. Baseline: beat tracking of the same song in the same run.\n",
        "| measure | time [s] | ratio to beat tracking | target | result |",
        "|---|---|---|---|---|",
        f"| beat tracking of the 4 min song (baseline) | {t_beats:.2f} | 1.00 | | |",
        f"| the same, CPU time (baseline of the CPU ratio) | {cpu_beats:.2f} | 1.00 | | |",
        f"| `beatsync sync` whole process (mode {result['mode']}, {result['repetitions']} "
        f"repetitions, {out_frames} output frames) | {t_proc:.2f} | "
        f"{t_proc / t_beats:.2f} | < {TARGET_S:g} s | {'PASS' if result['pass'] else 'FAIL'} |",
        f"| the same process, CPU time (user + system) | {result['cpu_process_s']:.2f} | "
        f"{result['cpu_process_s'] / cpu_beats:.2f} (to its CPU time) | | |",
        "",
        f"Machine: {result['machine']['platform']}, {result['machine']['processor']}, "
        f"load average {result['machine']['load_average']} (shared machine: absolute times "
        "are noisy, the ratio less so).\n",
    ]
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "dancers.md").write_text("\n".join(md))
    (HERE / "results" / "dancers.json").write_text(json.dumps(result, indent=2) + "\n")
    print("\n".join(md))
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
