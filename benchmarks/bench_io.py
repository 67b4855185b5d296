"""BVH reader: memory and time on a large file, against numpy.loadtxt of the same frames.

A large BVH is made by repeating the frames of the bundled CMU salsa clip 60_01
(132 channels, 2242 frames, 2.9 MB) ``--repeats`` times (30: 67,260 frames, 86 MB).
Each reader runs in its own process (one core), so its peak resident memory
(``ru_maxrss``) and its CPU time (``time.process_time``, robust to a busy machine) are
its own; the memory attributed to a reader is the peak minus the
process's resident memory after imports. The baseline is ``numpy.loadtxt`` of the
frame lines alone (no hierarchy, no checks), measured in the same run.

Targets: the reader needs at most 2x the memory of its float64 values array (the
former reader, which split the whole MOTION block into Python strings at once, needed
about 14x: a 1017 MB peak, 991 MB above imports, for this file), and at most 2x the
CPU time of numpy.loadtxt (it is a C parser without checks).

Usage::

    python benchmarks/bench_io.py [--repeats 30]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import machine_facts, pin_one_core  # noqa: E402

pin_one_core()

_PROBE = r"""
import json, resource, sys, time
import numpy as np
from beatsync import io
path, how, skip = sys.argv[1], sys.argv[2], int(sys.argv[3])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.process_time()
if how == "read_bvh":
    shape = io.read_bvh(path).values.shape
else:
    shape = np.loadtxt(path, skiprows=skip, dtype=np.float64, ndmin=2).shape
seconds = time.process_time() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"shape": shape, "seconds": seconds, "import_kb": before, "peak_kb": peak}))
"""


def make_large_bvh(src: Path, dst: Path, repeats: int) -> int:
    """Write ``src``'s hierarchy and its frames ``repeats`` times; return the header lines."""
    text = src.read_text()
    head, _, motion = text.partition("\nMOTION\n")
    lines = motion.splitlines()
    frames = "\n".join(ln for ln in lines[2:] if ln.strip()) + "\n"
    n = frames.count("\n")
    with open(dst, "w") as fh:
        fh.write(f"{head}\nMOTION\nFrames: {n * repeats}\n{lines[1]}\n")
        for _ in range(repeats):
            fh.write(frames)
    return head.count("\n") + 4


def probe(path: Path, how: str, skip: int) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, str(path), how, str(skip)],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30, help="copies of the clip's frames")
    args = ap.parse_args()
    from beatsync import datasets

    src = datasets.path("motion/cmu_salsa/60_01_scaled.bvh")
    with tempfile.TemporaryDirectory() as tmp:
        big = Path(tmp) / "large.bvh"
        skip = make_large_bvh(src, big, args.repeats)
        size_mb = big.stat().st_size / 1e6
        ours = probe(big, "read_bvh", skip)
        base = probe(big, "loadtxt", skip)
    if ours["shape"] != base["shape"]:
        raise RuntimeError(f"shapes differ: {ours['shape']} vs {base['shape']}")
    n, c = ours["shape"]
    values_mb = n * c * 8 / 1e6
    mem_ours = (ours["peak_kb"] - ours["import_kb"]) * 1024 / 1e6
    mem_base = (base["peak_kb"] - base["import_kb"]) * 1024 / 1e6
    mem_ratio = mem_ours / values_mb
    time_ratio = ours["seconds"] / base["seconds"]
    rows = [
        ("memory / values array", f"{mem_ratio:.2f}", "<= 2.0", mem_ratio <= 2.0),
        ("time / numpy.loadtxt", f"{time_ratio:.2f}", "<= 2.0", time_ratio <= 2.0),
    ]
    cmd = f"python benchmarks/bench_io.py --repeats {args.repeats}"
    md = [
        "# BVH reader: memory and time on a large file\n",
        f"Command:\n\n  .venv/bin/{cmd}\n",
        "Machine: " + ", ".join(f"{k} {v}" for k, v in machine_facts().items()) + "\n",
        f"File: the frames of CMU salsa 60_01 repeated {args.repeats} times: {n} frames x "
        f"{c} channels, {size_mb:.1f} MB; its float64 values take {values_mb:.1f} MB. Memory "
        "is each reader's peak resident memory minus its process's after imports; time is "
        "its process's CPU time. "
        "Baseline: `numpy.loadtxt` of the frame lines alone (no hierarchy, no checks), same "
        "run. The former reader (whole MOTION block split into strings at once) peaked at "
        "1017 MB for this file (991 MB above imports, about 14x the values array; 2.6 s "
        "CPU), measured with the same probe before the change.\n",
        "| reader | CPU time [s] | memory [MB] |",
        "|---|---|---|",
        f"| beatsync.io.read_bvh | {ours['seconds']:.2f} | {mem_ours:.0f} |",
        f"| numpy.loadtxt (baseline) | {base['seconds']:.2f} | {mem_base:.0f} |",
        "",
        "| target | value | threshold | result |",
        "|---|---|---|---|",
        *[f"| {a} | {b} | {t} | {'PASS' if ok else 'FAIL'} |" for a, b, t, ok in rows],
        "",
    ]
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    (out / "io.md").write_text("\n".join(md))
    record = {
        "command": cmd,
        "machine": machine_facts(),
        "file_mb": size_mb,
        "shape": [n, c],
        "read_bvh": ours,
        "loadtxt": base,
        "memory_ratio": mem_ratio,
        "time_ratio": time_ratio,
    }
    (out / "io.json").write_text(json.dumps(record, indent=2) + "\n")
    print("\n".join(md))
    return 0 if all(ok for *_, ok in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
