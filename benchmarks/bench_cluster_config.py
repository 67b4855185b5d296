"""Benchmark of the local cluster's Dask settings (``beatsync.cluster.LOCAL_CLUSTER_CONFIG``).

The local cluster of ``beatsync evaluate beats`` and ``beatsync batch`` runs without
the workers' statistical profiler (it feeds only a dashboard), and runs the system
monitor (for the dashboard) and the event-loop and memory checks less often than
Dask's defaults. This script measures what that changes, against Dask's defaults (the
baseline), in the same run:

1. idle: the CPU time per second of this process (scheduler, nannies, client) and of
   each worker, with a local cluster of 2 workers up and nothing to do;
2. steady state: the time of the Dask path of ``beatsync evaluate beats``
   (:func:`beatsync.study.beat_dataset.evaluate_dataset` on warmed workers, as in
   ``bench_evaluate.py``) on the same synthetic songs, with 1 and with 2 workers.

The two settings alternate run by run, the first of each pair alternating too, so a
slow spell of the shared machine falls on both alike; each ratio is the median of
the per-pair ratios (ours / Dask's defaults: below 1 is faster).

Usage::

    .venv/bin/python benchmarks/bench_cluster_config.py [--tracks 40] [--seconds 30] [--pairs 16]

Writes ``benchmarks/results/cluster_config.md`` and ``.json``.
"""

from __future__ import annotations

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # one thread per process (workers inherit it), before numpy

import argparse  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

SETTINGS = ("ours", "Dask's defaults")


@contextmanager
def settings(name: str):
    """The local cluster with our settings, or with Dask's defaults (the baseline)."""
    from beatsync import cluster

    saved = cluster.LOCAL_CLUSTER_CONFIG
    if name != "ours":
        cluster.LOCAL_CLUSTER_CONFIG = {}
    try:
        yield
    finally:
        cluster.LOCAL_CLUSTER_CONFIG = saved


def _cpu() -> float:
    return time.process_time()


def idle_cpu(seconds: float) -> tuple[float, list[float]]:
    """CPU seconds per second of this process and of each worker, 2 idle workers."""
    from beatsync.cluster import dask_client

    with dask_client(n_workers=2) as client:
        time.sleep(1.0)  # start-up settles
        w0, c0 = client.run(_cpu), time.process_time()
        time.sleep(seconds)
        w1, c1 = client.run(_cpu), time.process_time()
    return (c1 - c0) / seconds, sorted((w1[k] - w0[k]) / seconds for k in w0)


def steady_run(tracks, refs, out: Path, n_workers: int) -> float:
    """Seconds of the Dask path on warmed workers (``bench_evaluate.time_dask``)."""
    from bench_evaluate import time_dask

    return time_dask(tracks, refs, out, n_workers)[0]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tracks", type=int, default=40)
    ap.add_argument("--seconds", type=float, default=30.0, help="length of each song [s]")
    ap.add_argument("--pairs", type=int, default=16, help="alternating pairs of each measure")
    ap.add_argument("--idle", type=float, default=5.0, help="idle measurement [s]")
    args = ap.parse_args()

    import dask
    import distributed  # noqa: F401 (its config defaults loaded before any change)
    from bench_evaluate import SR, make_dataset

    from beatsync.cluster import LOCAL_CLUSTER_CONFIG
    from beatsync.study.beat_dataset import find_tracks, read_annotation

    # the baseline: this process's values (Dask's defaults unless configured otherwise)
    baseline = {key: dask.config.get(key) for key in LOCAL_CLUSTER_CONFIG}
    load_before = os.getloadavg()
    idle = {s: {"main": [], "workers": []} for s in SETTINGS}
    runs = {n: {s: [] for s in SETTINGS} for n in (1, 2)}
    with tempfile.TemporaryDirectory(prefix="bench-cluster-config-") as tmp:
        tmp = Path(tmp)
        audio, notes = make_dataset(tmp / "data", args.tracks, args.seconds)
        tracks = find_tracks(audio, notes).tracks
        refs = {t.key: read_annotation(t.annotation) for t in tracks}
        for p in range(args.pairs):
            order = SETTINGS if p % 2 == 0 else SETTINGS[::-1]
            for name in order:
                with settings(name):
                    main_cpu, workers_cpu = idle_cpu(args.idle)
                idle[name]["main"].append(main_cpu)
                idle[name]["workers"].append(workers_cpu)
            for n in (1, 2):
                for name in order:
                    with settings(name):
                        runs[n][name].append(steady_run(tracks, refs, tmp / f"{n}{name}{p}", n))
            print(f"pair {p + 1}/{args.pairs} done", file=sys.stderr, flush=True)
    ratios = {
        n: [a / b for a, b in zip(runs[n]["ours"], runs[n]["Dask's defaults"], strict=True)]
        for n in (1, 2)
    }
    ratio = {n: float(np.median(r)) for n, r in ratios.items()}
    speedup = {s: float(np.median(np.divide(runs[1][s], runs[2][s]))) for s in SETTINGS}
    med_idle = {
        s: {
            "main": float(np.median(idle[s]["main"])),
            "workers": float(np.median(np.ravel(idle[s]["workers"]))),
        }
        for s in SETTINGS
    }
    facts = {
        "command": f"python benchmarks/bench_cluster_config.py --tracks {args.tracks} "
        f"--seconds {args.seconds:g} --pairs {args.pairs}",
        **_machine.machine_facts(),
        "cores_used": 2,
        "load_average_before": [round(x, 2) for x in load_before],
        "load_average_after": [round(x, 2) for x in os.getloadavg()],
    }
    data = {
        "facts": facts,
        "settings": LOCAL_CLUSTER_CONFIG,
        "baseline_settings": baseline,
        "input": f"{len(tracks)} synthetic drum songs of {args.seconds:g} s at {SR} Hz",
        "idle_cpu_per_second": idle,
        "idle_cpu_median": med_idle,
        "run_seconds": {str(n): v for n, v in runs.items()},
        "ratio_ours_to_defaults": {str(n): v for n, v in ratio.items()},
        "pair_ratios": {str(n): v for n, v in ratios.items()},
        "speedup_2_vs_1_workers": speedup,
    }
    lines = [
        "## cluster_config: the local cluster's Dask settings against Dask's defaults",
        "",
        f"Command: `{facts['command']}`  ",
        f"Machine: {facts['platform']}, {facts['processor']}, {facts['cpu_count']} CPUs, "
        f"Python {facts['python']}, numpy {facts['numpy']}, beatsync {facts['beatsync']}; "
        f"{facts['date_utc']}; load average {facts['load_average_before']} before, "
        f"{facts['load_average_after']} after.",
        "",
        "Ours: "
        + ", ".join(f"`{k}: {v}`" for k, v in LOCAL_CLUSTER_CONFIG.items())
        + ". Baseline: Dask's defaults, "
        + ", ".join(f"`{k}: {v}`" for k, v in baseline.items())
        + f", alternating with ours run by run ({args.pairs} pairs, the first of each pair "
        "alternating). Input: "
        + data["input"]
        + "; the Dask path of `beatsync evaluate beats` on warmed single-threaded workers.",
        "",
        "| measure | Dask's defaults | ours | ours / defaults (median of pair ratios) |",
        "|---|---:|---:|---:|",
        f"| idle CPU of this process (scheduler, nannies, client) [% of a core] | "
        f"{100 * med_idle[SETTINGS[1]]['main']:.1f} | {100 * med_idle['ours']['main']:.1f} | |",
        f"| idle CPU of each worker [% of a core] | "
        f"{100 * med_idle[SETTINGS[1]]['workers']:.1f} | "
        f"{100 * med_idle['ours']['workers']:.1f} | |",
    ]
    for n in (1, 2):
        lines.append(
            f"| {len(tracks)} tracks, {n} worker{'s' * (n > 1)} [s, median] | "
            f"{np.median(runs[n][SETTINGS[1]]):.2f} | {np.median(runs[n]['ours']):.2f} | "
            f"{ratio[n]:.3f} |"
        )
    lower = {
        part: sum(
            np.mean(o) < np.mean(d) if part == "workers" else o < d
            for o, d in zip(idle["ours"][part], idle[SETTINGS[1]][part], strict=True)
        )
        for part in ("main", "workers")
    }
    lines += [
        f"| throughput 2 workers / 1 worker (median over pairs) | "
        f"{speedup[SETTINGS[1]]:.2f}x | {speedup['ours']:.2f}x | |",
        "",
        f"Idle CPU lower with ours in {lower['main']} of {args.pairs} pairs for this "
        f"process and in {lower['workers']} of {args.pairs} for the workers (their mean). "
        "Per-pair ratios of the run times, ours / defaults: 1 worker "
        + ", ".join(f"{r:.2f}" for r in ratios[1])
        + "; 2 workers "
        + ", ".join(f"{r:.2f}" for r in ratios[2])
        + ".",
        "",
    ]
    _machine.write_results("cluster_config", data, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
