"""Shared by the benchmark scripts: one-core pinning and the machine facts each
result file records (so a number can be read against the machine that made it)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
import sys

THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


def pin_one_core() -> None:
    """Limit numeric libraries to one thread; call before numpy is imported."""
    for var in THREAD_VARS:
        os.environ[var] = "1"


def machine_facts() -> dict[str, object]:
    """Date, platform, CPU, Python and library versions, load average."""
    import librosa
    import numpy as np

    import beatsync

    return {
        "date_utc": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "python": sys.version.split()[0],
        "cpu_count": os.cpu_count(),
        "cores_used": 1,
        "numpy": np.__version__,
        "librosa": librosa.__version__,
        "beatsync": beatsync.__version__,
        "load_average": [round(x, 2) for x in os.getloadavg()]
        if hasattr(os, "getloadavg")
        else None,
    }


def write_results(name: str, data: dict, lines: list[str]) -> None:
    """Write ``benchmarks/results/<name>.json`` and ``<name>.md`` (each atomic; the
    Markdown, for ``run_all.py --collect``, last: a failure leaves the old pair, or a new
    JSON beside the old Markdown, never a new table without its data) and print the
    Markdown."""
    from pathlib import Path

    from beatsync import io

    results = Path(__file__).resolve().parent / "results"
    results.mkdir(exist_ok=True)
    io.write_json(results / f"{name}.json", data)
    with io.atomic_write(results / f"{name}.md") as fh:
        fh.write("\n".join(lines))
    print("\n".join(lines))


def interleaved_times(fns, rounds: int) -> list[list[float]]:
    """Seconds of each call of each function, their calls interleaved (the order
    rotating each round, so over any ``len(fns)`` consecutive rounds each function goes
    first once; with two functions the order alternates), so that a slow spell of the shared machine
    falls on all of them alike: ``times[i][r]`` is function ``i`` in round ``r``."""
    import time

    n = len(fns)
    times: list[list[float]] = [[] for _ in fns]
    for r in range(rounds):
        for i in [(r + k) % n for k in range(n)]:
            t0 = time.perf_counter()
            fns[i]()
            times[i].append(time.perf_counter() - t0)
    return times
