"""Benchmark of the optimal periodic segmentation (paper A, section 3).

Paper scale (n = 750 frames, 29 channels at 25 Hz, alpha = 0.1, period 1.2 s) and
n = 750 * 2^k up to 12000 frames at the same period, on one core, against a literal
loop-by-loop implementation of eqs. 1-5 (``beatsync.segment.reference.segment_literal``: one
Python loop per DAG edge, per channel and per sample) measured in the same run. The
literal version takes about a minute at n = 750, so it runs only up to
``--literal-max-n`` (default 750); both must find the same optimum (the same energy
within 1e-3 and every boundary within +-1 frame: the fast path sums in float32).

Timed: ``segment_values(values, fps=25, alpha=0.1, n_periods=n/30)`` (the period count
given, as when it comes from the music), which is edge costs + DP + the periodicity
check; and separately with the period estimated (``period_method="energy"``).

Usage::

    .venv/bin/python benchmarks/bench_segment.py [--repeats 5] [--literal-max-n 750]

Writes ``benchmarks/results/segment.md`` and ``benchmarks/results/segment.json``.
"""

from __future__ import annotations

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
FPS = 25.0
N_CH = 29
ALPHA = 0.1
FRAMES_PER_PERIOD = 30  # 1.2 s at 25 Hz
SIZES = [750 * 2**k for k in range(5)]  # 750 ... 12000
TARGET_PAPER_MS = 50.0
TARGET_SPEEDUP = 50.0
TARGET_EXPONENT = 1.15  # "about linear": t ~ n^e with e <= 1.15


def _best_time(fn, repeats):
    """Best (minimum) wall time of ``repeats`` runs: the least disturbed by other load."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.min(times)), out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--literal-max-n", type=int, default=750)
    args = ap.parse_args()
    # single-threaded BLAS (set above); not pinned to a core: on a shared machine the
    # scheduler then picks the idle one

    from beatsync import io
    from beatsync import segment as S
    from beatsync.segment.channels import standardise
    from beatsync.segment.reference import segment_literal
    from beatsync.segment.search import period_band
    from beatsync.synth.motion import periodic_motion

    rows = []
    for n in SIZES:
        p = round((n - 1) / FRAMES_PER_PERIOD)
        synth = periodic_motion(n_frames=n, n_channels=N_CH, fps=FPS, n_periods=p, jitter=0.08,
                                snr_db=20.0, seed=0)  # fmt: skip
        vals = synth.motion.values
        S.segment_values(vals, fps=FPS, alpha=ALPHA, n_periods=p)  # warm-up (kernel cache)
        t_fast, seg = _best_time(
            lambda vals=vals, p=p: S.segment_values(vals, fps=FPS, alpha=ALPHA, n_periods=p),
            args.repeats,
        )
        t_est, seg_e = _best_time(
            lambda vals=vals: S.segment_values(vals, fps=FPS, alpha=ALPHA),
            max(1, args.repeats // 2),
        )
        err = np.abs(seg.boundary_frames - synth.boundary_frames)
        row = {
            "n_frames": n,
            "n_periods": p,
            "fast_given_s": t_fast,
            "fast_estimated_s": t_est,
            "max_boundary_error_frames": int(err.max()) if err.size else None,
            "estimated_n_periods": seg_e.n_periods,
            "literal_s": None,
            "speedup": None,
            "same_optimum": None,
        }
        if n <= args.literal_max_n:
            x = standardise(vals)
            lo, hi = period_band((n - 1) / p, ALPHA)
            t_lit, (f_lit, e_lit) = _best_time(
                lambda x=x, lo=lo, hi=hi: segment_literal(x, lo, hi), 1
            )
            row["literal_s"] = t_lit
            row["speedup"] = t_lit / t_fast
            # same optimum: same count, energies within 1e-3, boundaries within +-1 frame
            # (the fast path sums in float32, the literal one in float64)
            f_fast = seg.boundary_frames
            row["same_optimum"] = bool(
                f_lit.size == f_fast.size
                and np.abs(f_lit - f_fast).max() <= 1
                and abs(e_lit - seg.energy) < 1e-3
            )
            row["literal_energy"] = e_lit
            row["fast_energy"] = seg.energy
        rows.append(row)
        print(json.dumps(row), flush=True)

    t = np.array([r["fast_given_s"] for r in rows])
    ns = np.array(SIZES, dtype=float)
    exponent = float(np.polyfit(np.log(ns), np.log(t), 1)[0])
    paper = rows[0]
    checks = [
        (f"paper scale (n=750, 29 ch, alpha 0.1) < {TARGET_PAPER_MS:g} ms",
         f"{paper['fast_given_s'] * 1e3:.1f} ms", paper["fast_given_s"] * 1e3 < TARGET_PAPER_MS),
        (f">= {TARGET_SPEEDUP:g}x faster than the literal eqs. 1-5 (n=750)",
         f"{paper['speedup']:.0f}x" if paper["speedup"] else "not run",
         bool(paper["speedup"] and paper["speedup"] >= TARGET_SPEEDUP)),
        ("same optimum as the literal implementation", str(paper["same_optimum"]),
         bool(paper["same_optimum"])),
        (f"time ~ linear in n for a fixed period (fitted exponent <= {TARGET_EXPONENT})",
         f"t ~ n^{exponent:.2f} (750..12000)", exponent <= TARGET_EXPONENT),
    ]  # fmt: skip
    facts = {
        "command": f"python benchmarks/bench_segment.py --repeats {args.repeats} "
        f"--literal-max-n {args.literal_max_n}",
        **_machine.machine_facts(),
    }
    lines = [
        "## segment: optimal periodic segmentation (paper A, sec. 3)",
        "",
        f"Command: `{facts['command']}`  ",
        f"Machine: {facts['platform']}, {facts['processor']}, {facts['cpu_count']} CPUs "
        f"(1 used), Python {facts['python']}, numpy {facts['numpy']}, beatsync "
        f"{facts['beatsync']}; {facts['date_utc']}; load average "
        f"{', '.join(f'{v:.1f}' for v in facts['load_average'] or [])} (shared machine); "
        f"best of {args.repeats} runs (the literal: one run).",
        "",
        "Input: synthetic 29-channel joint-angle signal (`beatsync.synth.motion`), 25 Hz, "
        "period 1.2 s (30 frames) with +-8% jitter, 20 dB SNR, alpha 0.1 (band 26-33 frames)."
        " Baseline: `segment.reference.segment_literal`, a loop-by-loop implementation of "
        "eqs. 1-5 (Python loops over edges, channels and samples), run only for "
        f"n <= {args.literal_max_n}.",
        "",
        "| n frames | periods | segment, count given [ms] | segment, count estimated [ms] "
        "| literal eqs. 1-5 [s] | speed-up | same optimum | max boundary error [frames] |",
        "|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for r in rows:
        lit = f"{r['literal_s']:.1f}" if r["literal_s"] is not None else "not run"
        sp = f"{r['speedup']:.0f}x" if r["speedup"] is not None else "-"
        same = "yes" if r["same_optimum"] else ("-" if r["same_optimum"] is None else "NO")
        lines.append(
            f"| {r['n_frames']} | {r['n_periods']} | {r['fast_given_s'] * 1e3:.1f} | "
            f"{r['fast_estimated_s'] * 1e3:.1f} | {lit} | {sp} | {same} | "
            f"{r['max_boundary_error_frames']} |"
        )
    lines += [
        "",
        f"Growth: fitted t ~ n^{exponent:.2f} over n = 750..12000 (count given).",
        "",
        "| target | measured | |",
        "|---|---|---|",
    ]
    lines += [f"| {name} | {val} | {'PASS' if ok else 'FAIL'} |" for name, val, ok in checks]
    lines.append("")
    (HERE / "results").mkdir(exist_ok=True)
    md = "\n".join(lines)
    with io.atomic_write(HERE / "results" / "segment.md") as fh:
        fh.write(md)
    io.write_json(
        HERE / "results" / "segment.json",
        {"facts": facts, "rows": rows, "exponent": exponent,
         "checks": [{"target": a, "measured": b, "pass": c} for a, b, c in checks]},
    )  # fmt: skip
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
