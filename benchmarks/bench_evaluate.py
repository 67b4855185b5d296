"""Benchmark of dataset-scale beat evaluation on Dask (``beatsync evaluate beats``).

Generates a dataset of synthetic songs (drum patterns at tempi spread over 70-180 BPM,
with their exact beats as ``.beats`` annotations) in a temporary folder, then
measures, in the same run:

1. the baseline: a plain in-process loop over the tracks (read, track with ``psf``,
   score), after one warm-up track (imports, compilation);
2. the same work through the Dask path (:func:`beatsync.study.beat_dataset
   .evaluate_dataset`: the tracks in groups, one task each, and every row appended to
   ``tracks.jsonl``) on a local cluster of 1 and of 2 single-threaded worker
   processes, each worker warmed by one untimed track, so the times are the
   steady-state throughput of a long run;
   the per-track overhead of the Dask path is (Dask, 1 worker - plain loop) / tracks;
3. this machine's reference for 2 workers: the same tracks read, tracked and scored
   by 1 and by 2 plain processes (no Dask; each warmed, then started together, taking
   the next track as they come free), whose time ratio is what two processes doing
   this work get here; the Dask ratio is also given as a share of it;
4. the whole command as a user runs it (``beatsync evaluate beats --workers 1`` and
   ``--workers 2`` in fresh processes: cluster start-up, worker imports and
   compilation included).

Target: 2 workers >= 1.7x the throughput of 1 worker (steady state). The machine
has 2 cores; the ratio is only meaningful when nothing else runs. Each repeat runs
1 and 2 workers one after the other, the first of the two alternating from repeat to
repeat; the ratio is the median of the repeats' ratios (the shared machine's speed
drifts between runs a minute apart: a pair of runs side by side shares its spell).

With ``--source real`` the tracks are copies of the three bundled recordings with
human beat annotations (Hainsworth 001, the Ballroom waltz, the madmom sample; 2.8-56 s
long, so the tasks are uneven), in turn.

Usage::

    .venv/bin/python benchmarks/bench_evaluate.py [--tracks 40] [--seconds 30] [--repeats 2]
    .venv/bin/python benchmarks/bench_evaluate.py --source real --tracks 42 --repeats 6

Writes ``benchmarks/results/evaluate.md`` and ``.json`` (``evaluate_real`` with
``--source real``).
"""

from __future__ import annotations

import os

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # one thread per process (workers inherit it), before numpy

import argparse  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

TARGET_SPEEDUP = 1.7
SR = 22050


def make_dataset(root: Path, n: int, seconds: float, seed: int = 0) -> tuple[Path, Path]:
    """``n`` drum songs with exact beats: ``root/audio/*.wav``, ``root/annotations``."""
    from beatsync import io
    from beatsync.synth.audio import beat_times, drum_pattern

    rng = np.random.default_rng(seed)
    audio, notes = root / "audio", root / "annotations"
    audio.mkdir(parents=True)
    notes.mkdir()
    for i in range(n):
        bpm = float(rng.uniform(70.0, 180.0))
        ref = beat_times(bpm, duration=seconds, start=float(rng.uniform(0.2, 0.6)))
        y = drum_pattern(ref, sr=SR, duration=seconds, seed=i)
        io.write_audio(audio / f"song{i:03d}.wav", y, SR)
        io.write_beats(notes / f"song{i:03d}.beats", ref)
    return audio, notes


#: The bundled recordings with human beat annotations (``--source real``).
REAL_RECORDINGS = (
    "audio/real_dev/hainsworth_001.flac",
    "audio/real_dev/ballroom_Media-105901.wav",
    "audio/madmom/sample.wav",
)


def make_real_dataset(root: Path, n: int) -> tuple[Path, Path]:
    """``n`` copies of :data:`REAL_RECORDINGS` in turn, each with its annotation."""
    import shutil

    from beatsync import datasets

    audio, notes = root / "audio", root / "annotations"
    audio.mkdir(parents=True)
    notes.mkdir()
    for i in range(n):
        rel = REAL_RECORDINGS[i % len(REAL_RECORDINGS)]
        src = datasets.path(rel)
        beats = datasets.path(rel.rsplit("/", 1)[0] + f"/{src.stem}.beats")
        shutil.copy(src, audio / f"{src.stem}_{i:03d}{src.suffix}")
        shutil.copy(beats, notes / f"{src.stem}_{i:03d}.beats")
    return audio, notes


def _real_input(n: int) -> str:
    import soundfile as sf

    from beatsync import datasets

    parts = []
    for i, rel in enumerate(REAL_RECORDINGS):
        p = datasets.path(rel)
        count = len(range(i, n, len(REAL_RECORDINGS)))
        parts.append(f"{count} of {p.name} ({sf.info(str(p)).duration:.1f} s)")
    return f"{n} copies of the bundled recordings with human beat annotations: " + ", ".join(parts)


def _warm(path: str, reference: np.ndarray) -> None:
    from beatsync.study.beat_dataset import evaluate_track

    evaluate_track(path, reference, method="psf", min_beat_time=0.0, name="warm-up")


def time_dask(tracks, refs, out: Path, n_workers: int) -> tuple[float, float, float, float]:
    """Steady-state time of the Dask path on ``n_workers`` warmed workers, start-up time,
    the summed time the tasks spent reading and tracking (measured in the workers), and
    the CPU time of this process during the run: the command's own process, which holds
    the scheduler, the nannies, the client and the log (every thread of it)."""
    from beatsync.cluster import dask_client
    from beatsync.study.beat_dataset import evaluate_dataset

    t0 = time.perf_counter()
    with dask_client(n_workers=n_workers) as client:  # the local cluster of the command
        client.run(_warm, str(tracks[0].audio), refs[tracks[0].key])  # on every worker
        t_start = time.perf_counter() - t0
        t1, cpu1 = time.perf_counter(), time.process_time()
        run = evaluate_dataset(tracks, out, scheduler=client.scheduler.address)
        t_run, cpu = time.perf_counter() - t1, time.process_time() - cpu1
    assert (run.tracks["status"] == "ok").all()
    return t_run, t_start, float(run.tracks["seconds"].sum()), cpu


#: Seconds a plain process may take to warm up, and to finish, before the run gives up.
PLAIN_TIMEOUT = 300.0


def _plain_process(items, counter, barrier, done) -> None:
    """One plain process of :func:`time_plain_processes`: warm up, wait for the others,
    then take the next track (a shared counter, as Dask hands tracks to the first free
    worker) until none is left; report the seconds."""
    from beatsync.study.beat_dataset import evaluate_track

    _warm(*items[0])
    barrier.wait(timeout=PLAIN_TIMEOUT)
    t0 = time.perf_counter()
    while True:
        with counter.get_lock():
            i = counter.value
            counter.value += 1
        if i >= len(items):
            break
        evaluate_track(items[i][0], items[i][1], method="psf", min_beat_time=0.0, name="plain")
    done.put(time.perf_counter() - t0)


def time_plain_processes(tracks, refs, n_proc: int) -> float:
    """Wall time of ``n_proc`` plain processes (no Dask) reading, tracking and scoring
    the tracks, each warmed up and all started together: what this machine gives
    ``n_proc`` single-threaded processes doing the work of ``n_proc`` workers, the
    reference for the Dask path's ratio. A process that fails or hangs stops the run
    with an error (after :data:`PLAIN_TIMEOUT` seconds at most)."""
    import multiprocessing
    import queue
    import threading

    ctx = multiprocessing.get_context("spawn")
    items = [(str(t.audio), refs[t.key]) for t in tracks]
    counter = ctx.Value("i", 0)
    barrier = ctx.Barrier(n_proc + 1)
    done = ctx.Queue()
    procs = [
        ctx.Process(target=_plain_process, args=(items, counter, barrier, done))
        for _ in range(n_proc)
    ]
    for proc in procs:
        proc.start()
    try:
        barrier.wait(timeout=PLAIN_TIMEOUT)
        t0 = time.perf_counter()
        for _ in procs:
            done.get(timeout=PLAIN_TIMEOUT)
        wall = time.perf_counter() - t0
    except (threading.BrokenBarrierError, queue.Empty) as exc:
        raise RuntimeError(f"a plain process failed or hung ({type(exc).__name__})") from exc
    finally:
        for proc in procs:
            proc.join(timeout=10)
            if proc.is_alive():
                proc.terminate()
    if any(proc.exitcode != 0 for proc in procs):
        raise RuntimeError(f"a plain process failed (exit codes {[p.exitcode for p in procs]})")
    return wall


def time_command(audio: Path, notes: Path, out: Path, n_workers: int) -> float:
    cmd = [
        sys.executable,
        "-m",
        "beatsync.cli",
        "evaluate",
        "beats",
        "--audio",
        str(audio),
        "--annotations",
        str(notes),
        "--out",
        str(out),
        "--workers",
        str(n_workers),
    ]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tracks", type=int, default=40)
    ap.add_argument("--seconds", type=float, default=30.0, help="length of each synthetic song [s]")
    ap.add_argument(
        "--source",
        choices=("synthetic", "real"),
        default="synthetic",
        help="the tracks: synthetic drum songs (results/evaluate.md), or copies of the "
        "bundled recordings with human beat annotations in turn (results/evaluate_real.md)",
    )
    ap.add_argument(
        "--repeats",
        type=int,
        default=2,
        help="runs of each measurement (median); an even count runs each order equally",
    )
    args = ap.parse_args()

    from beatsync.study.beat_dataset import (
        GROUP_TRACKS,
        evaluate_track,
        find_tracks,
        read_annotation,
    )

    load_before = os.getloadavg()
    res: dict[str, list[float]] = {
        k: [] for k in ("loop", "dask1", "dask2", "plain1", "plain2", "cmd1", "cmd2")
    }
    startup: dict[str, list[float]] = {"dask1": [], "dask2": []}
    work: dict[str, list[float]] = {"loop": [], "dask1": [], "dask2": []}
    coordinator: dict[str, list[float]] = {"dask1": [], "dask2": []}
    with tempfile.TemporaryDirectory(prefix="bench-evaluate-") as tmp:
        tmp = Path(tmp)
        if args.source == "real":
            audio, notes = make_real_dataset(tmp / "data", args.tracks)
        else:
            audio, notes = make_dataset(tmp / "data", args.tracks, args.seconds)
        tracks = find_tracks(audio, notes).tracks
        refs = {t.key: read_annotation(t.annotation) for t in tracks}
        _warm(str(tracks[0].audio), refs[tracks[0].key])
        for r in range(args.repeats):
            t0 = time.perf_counter()
            rows = [
                evaluate_track(
                    str(t.audio), refs[t.key], method="psf", min_beat_time=0.0, name=t.key
                )
                for t in tracks
            ]
            res["loop"].append(time.perf_counter() - t0)
            assert all(row["status"] == "ok" for row in rows)
            work["loop"].append(sum(row["seconds"] for row in rows))
            order = (1, 2) if r % 2 == 0 else (2, 1)
            for n in order:
                t_run, t_start, t_work, cpu = time_dask(tracks, refs, tmp / f"dask{n}_{r}", n)
                res[f"dask{n}"].append(t_run)
                coordinator[f"dask{n}"].append(cpu)
                startup[f"dask{n}"].append(t_start)
                work[f"dask{n}"].append(t_work)
            for n in order:
                res[f"plain{n}"].append(time_plain_processes(tracks, refs, n))
            for n in order:
                res[f"cmd{n}"].append(time_command(audio, notes, tmp / f"cmd{n}_{r}", n))
        f_mean = float(np.mean([row["F-measure"] for row in rows]))
    med = {k: float(np.median(v)) for k, v in res.items()}
    n = len(tracks)
    # per repeat: the two runs of a repeat are side by side in time
    ratios = [a / b for a, b in zip(res["dask1"], res["dask2"], strict=True)]
    ratios_cmd = [a / b for a, b in zip(res["cmd1"], res["cmd2"], strict=True)]
    # the machine's own reference: two plain processes against one, same repeat
    references = [a / b for a, b in zip(res["plain1"], res["plain2"], strict=True)]
    # Dask's 2-worker ratio as a share of that reference, repeat by repeat
    shares = [d / c for d, c in zip(ratios, references, strict=True)]
    speedup = float(np.median(ratios))
    speedup_cmd = float(np.median(ratios_cmd))
    reference = float(np.median(references))
    share = float(np.median(shares))
    overhead_ms = 1000.0 * (med["dask1"] - med["loop"]) / n
    med_work = {k: float(np.median(v)) for k, v in work.items()}
    # wall time of 1 worker beyond the reading and tracking it did: scheduling, transfer,
    # the log and the tables (the same work is slower in a worker if the cores are shared)
    overhead_beyond_work_ms = 1000.0 * (med["dask1"] - med_work["dask1"]) / n
    # the same measure in the plain loop: scoring (mir_eval) and building the row
    loop_beyond_work_ms = 1000.0 * (med["loop"] - med_work["loop"]) / n
    # CPU of the command's own process per track: with 2 workers on 2 cores it is taken
    # from the workers' cores; with 1 worker it has a core of its own
    coord_ms = {k: 1000.0 * float(np.median(v)) / n for k, v in coordinator.items()}
    passed = speedup >= TARGET_SPEEDUP
    results_name = "evaluate_real" if args.source == "real" else "evaluate"
    load_after = os.getloadavg()
    facts = {
        "command": f"python benchmarks/bench_evaluate.py --tracks {args.tracks} "
        + ("--source real" if args.source == "real" else f"--seconds {args.seconds:g}")
        + f" --repeats {args.repeats}",
        **_machine.machine_facts(),
        "cores_used": 2,
        "load_average_before": [round(x, 2) for x in load_before],
        "load_average_after": [round(x, 2) for x in load_after],
    }
    data = {
        "facts": facts,
        "input": _real_input(n)
        if args.source == "real"
        else f"{n} synthetic drum songs of {args.seconds:g} s at {SR} Hz, 70-180 BPM "
        "(generated by the benchmark; exact beats as annotations)",
        "seconds": res,
        "startup_seconds": startup,
        "median": med,
        "speedup_2_vs_1_workers": speedup,
        "speedup_per_repeat": ratios,
        "speedup_of_medians": med["dask1"] / med["dask2"],
        "plain_processes_2_vs_1": reference,
        "plain_processes_2_vs_1_per_repeat": references,
        "speedup_share_of_plain_processes": share,
        "speedup_share_of_plain_processes_per_repeat": shares,
        "speedup_command": speedup_cmd,
        "speedup_command_per_repeat": ratios_cmd,
        "dask_overhead_ms_per_track": overhead_ms,
        "work_seconds_in_tasks": work,
        "dask_overhead_beyond_work_ms_per_track": overhead_beyond_work_ms,
        "loop_beyond_work_ms_per_track": loop_beyond_work_ms,
        "coordinator_cpu_seconds": coordinator,
        "coordinator_cpu_ms_per_track": coord_ms,
        "mean_f_measure": f_mean,
        "targets": {f"2 workers >= {TARGET_SPEEDUP}x 1 worker": passed},
    }
    rows_md = [
        (
            "plain in-process loop (baseline)",
            med["loop"],
            f"reading + tracking {med_work['loop']:.1f} s",
        ),
        (
            "Dask path, 1 worker (warmed)",
            med["dask1"],
            f"start-up + warm-up {np.median(startup['dask1']):.1f} s; reading + tracking "
            f"in the worker {med_work['dask1']:.1f} s",
        ),
        (
            "Dask path, 2 workers (warmed)",
            med["dask2"],
            f"start-up + warm-up {np.median(startup['dask2']):.1f} s; reading + tracking "
            f"in the workers {med_work['dask2']:.1f} s (sum of both)",
        ),
        (
            "plain process, no Dask (warmed; the baseline of the reference)",
            med["plain1"],
            "the loop above, in a process of its own",
        ),
        (
            "2 plain processes, no Dask, started together (warmed)",
            med["plain2"],
            "each takes the next track as it comes free",
        ),
        ("`beatsync evaluate beats --workers 1` (whole process)", med["cmd1"], ""),
        ("`beatsync evaluate beats --workers 2` (whole process)", med["cmd2"], ""),
    ]
    lines = [
        f"## {results_name}: dataset-scale beat evaluation on Dask (`beatsync evaluate beats`)"
        + (", on copies of the real recordings" if args.source == "real" else ""),
        "",
        f"Command: `{facts['command']}`  ",
        f"Machine: {facts['platform']}, {facts['processor']}, {facts['cpu_count']} CPUs, "
        f"Python {facts['python']}, numpy {facts['numpy']}, beatsync {facts['beatsync']}; "
        f"{facts['date_utc']}; load average {facts['load_average_before']} before, "
        f"{facts['load_average_after']} after; median of {args.repeats} run(s).",
        "",
        f"Input: {data['input']}; "
        f"method `psf`; mean F-measure {f_mean:.3f}. Each worker is a single-threaded "
        f"process; the Dask path sends the tracks in groups of at most {GROUP_TRACKS}, "
        "smaller toward the end (one task each). Baseline: a plain loop over the same "
        "tracks in one process, same run.",
        "",
        "| run | time [s] | tracks/s | note |",
        "|---|---:|---:|---|",
    ]
    for name, t, note in rows_md:
        lines.append(f"| {name} | {t:.2f} | {n / t:.2f} | {note} |")
    lines += [
        "",
        "| measure | value | target | result |",
        "|---|---:|---|---|",
        f"| throughput 2 workers / 1 worker (steady state; median of the repeats: "
        f"{', '.join(f'{x:.2f}' for x in ratios)}) | {speedup:.2f}x | >= "
        f"{TARGET_SPEEDUP}x | {'PASS' if passed else 'FAIL'} |",
        f"| this machine's reference: 2 plain processes / 1, no Dask (median of the repeats: "
        f"{', '.join(f'{x:.2f}' for x in references)}) | {reference:.2f}x | (reported) | |",
        f"| Dask's 2-worker ratio as a share of that reference (median of the repeats: "
        f"{', '.join(f'{x:.2f}' for x in shares)}) | {share:.2f} | (reported) | |",
        f"| whole command, 1 worker / 2 workers (median of the repeats: "
        f"{', '.join(f'{x:.2f}' for x in ratios_cmd)}) | {speedup_cmd:.2f}x | (start-up "
        "included) | |",
        f"| Dask overhead per track (1 worker - plain loop) / tracks | {overhead_ms:.1f} ms | | |",
        f"| time per track beyond the reading + tracking, plain loop (scoring, the row) | "
        f"{loop_beyond_work_ms:.1f} ms | | |",
        f"| time per track beyond the reading + tracking done in the worker, Dask path "
        f"(the same, plus scheduling, transfer, the log) | {overhead_beyond_work_ms:.1f} ms "
        "| | |",
        f"| Dask's own share per track (the difference of the two) | "
        f"{overhead_beyond_work_ms - loop_beyond_work_ms:.1f} ms | | |",
        f"| CPU of the command's own process per track (scheduler, nannies, client, the "
        f"log), 1 worker / 2 workers | {coord_ms['dask1']:.1f} / {coord_ms['dask2']:.1f} ms "
        "| | |",
        f"| the same, as a share of the 2-worker run's two cores | "
        f"{coord_ms['dask2'] * n / 1000.0 / (2 * med['dask2']):.0%} | | |",
        "",
        "Reading the table: the 2-worker ratio needs two idle cores. The summed reading + "
        "tracking time of the workers tells whether they had them: with two free cores it "
        "stays near the 1-worker figure; if it doubles, the cores were shared with other "
        "work and the ratio says nothing about Dask. The reference is what the machine "
        "gives two processes doing the same work without Dask, in the same repeat: when "
        "two compute at once, each may run slower than one alone (the two CPUs share the "
        "machine's hardware). It is measured a few seconds apart from the Dask runs, so "
        "a share above 1 is the machine's speed changing in between. The command's own "
        "process (Dask's scheduler and nannies, the client, the log) needs CPU for every "
        "task and every row; with 1 worker it runs on the other core, with 2 workers on 2 "
        "cores it is taken from the workers (the share of the two cores above). That and the run's "
        "fixed steps (connecting, the summary tables), which a second worker does not "
        "shorten, are where the 2-worker ratio falls short of the reference.",
        "",
    ]
    _machine.write_results(results_name, data, lines)
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())
