"""Benchmark of paper B's search: DP (proposed) vs multi-stage (conventional).

Run: ``.venv/bin/python benchmarks/bench_compose.py [--repeats N] [--quick]``

Times both searches side by side in the same run on the CMU salsa library (stand-in
for paper B's Break dance) and a synthetic dance library (stand-in for their Indian
dance), for 30 s, 60 s (and 120 s) of a synthetic drum song at 100 BPM; the graph
build is excluded and reported separately. Both searches run tempo-matched, as
``compose`` runs them by default (tempo group, beat multiplicity, time-scale bound
0.8-1.25). Writes ``benchmarks/results/compose.md``
and ``benchmarks/results/compose.json``.

Targets (issue 5): DP search for 60 s of music on the salsa library < 0.5 s; DP time
ratio when the music doubles (30 s -> 60 s) <= 2.1; conventional measured in the same
run, speedup reported (paper B: 27-543x).
"""

from __future__ import annotations

import _machine  # (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import json
import sys
import time
from pathlib import Path

from beatsync.graph import build_graph
from beatsync.study.paper_b import LIBRARIES, PAPER_B_TABLE1, load_library, ratio_table, speed_table

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="best of N runs per search")
    ap.add_argument("--quick", action="store_true", help="30 s and 60 s only, 2 repeats")
    args = ap.parse_args(argv)
    durations = (30.0, 60.0) if args.quick else (30.0, 60.0, 120.0)
    repeats = 2 if args.quick else args.repeats

    graphs = {}
    build = {}
    for name in ("salsa", "synthetic"):
        clips, beats = load_library(name)
        t0 = time.perf_counter()
        g = build_graph(clips, beats=beats)
        g.predecessor_table()
        g.successor_lists()
        build[name] = time.perf_counter() - t0
        graphs[name] = g
    speed = speed_table(graphs, durations, repeats=repeats)
    two = speed[speed.music_s.isin([30.0, 60.0])]
    ratios = ratio_table(two)

    salsa60 = speed[(speed.library == "salsa") & (speed.music_s == 60.0)].iloc[0]
    salsa_ratio = ratios[ratios.library == "salsa"].iloc[0]
    targets = [
        (
            "DP search, 60 s of music, salsa library < 0.5 s",
            f"{salsa60.dp_s * 1e3:.2f} ms",
            salsa60.dp_s < 0.5,
        ),
        (
            "DP time ratio 30 s -> 60 s (salsa) <= 2.1",
            f"{salsa_ratio.ratio_dp:.2f}",
            salsa_ratio.ratio_dp <= 2.1,
        ),
        (
            "conventional measured in the same run (speedup; paper 27-543x)",
            f"{speed.speedup.min():.0f}-{speed.speedup.max():.0f}x",
            True,
        ),
    ]
    cmd = "python benchmarks/bench_compose.py" + (" --quick" if args.quick else "")
    machine = _machine.machine_facts()
    lines = [
        "# Benchmark: motion-graph search (paper B, Table 1)",
        "",
        f"Command: `{cmd}` (best of {repeats} runs per search, each DP sample the mean of "
        "10 runs; graph build excluded).",
        "",
        "Machine: " + ", ".join(f"{k} {v}" for k, v in machine.items()),
        "",
        "Libraries (stand-ins, paper B's captures are not available):",
    ]
    for name, g in graphs.items():
        lines.append(
            f"- `{name}` for {LIBRARIES[name][0]}: {LIBRARIES[name][1]}; "
            f"{g.n_nodes} beat frames, {g.n_transitions} transition edges at TH=3; "
            f"graph build {build[name]:.2f} s"
        )
    lines += [
        "",
        "Music: synthetic drum song at 100 BPM with loudness sections "
        "(`beatsync.synth.audio.drum_song`). Both searches tempo-matched (the defaults of "
        "`compose`: clips of the song's tempo group, 1 or 2 music beats per motion-beat "
        "interval, time-scale factor within 0.8-1.25). Conventional: segments of 8 beats, "
        "rhythm threshold 0.5, at most 20000 candidate sequences per depth.",
        "",
        "| library | music [s] | beats | multiplicity | DP [ms] | conventional [ms] | speedup |"
        " DP cost | conventional cost |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in speed.itertuples():
        lines.append(
            f"| {r.library} | {r.music_s:g} | {r.n_beats} | {r.multiplicity} | "
            f"{r.dp_s * 1e3:.2f} | "
            f"{r.conventional_s * 1e3:.1f} | {r.speedup:.0f}x | {r.dp_cost:.2f} | "
            f"{r.conventional_cost:.2f} |"
        )
    lines += [
        "",
        "Time ratio when the music doubles (30 s -> 60 s):",
        "",
        "| library | DP (ours) | DP (paper) | conventional (ours) | conventional (paper) |",
        "|---|---|---|---|---|",
    ]
    for r in ratios.itertuples():
        lines.append(
            f"| {r.library} | {r.ratio_dp:.2f} | {PAPER_B_TABLE1['ratio_proposed']} | "
            f"{r.ratio_conventional:.2f} | {PAPER_B_TABLE1['ratio_conventional']} |"
        )
    lines += ["", "Paper B's absolute times: not available to us.", "", "## Targets", ""]
    lines += ["| target | measured | result |", "|---|---|---|"]
    for what, val, ok in targets:
        lines.append(f"| {what} | {val} | {'PASS' if ok else 'FAIL'} |")
    out_md = HERE / "results" / "compose.md"
    out_md.parent.mkdir(parents=True, exist_ok=True)
    out_md.write_text("\n".join(lines) + "\n")
    payload = {
        "command": cmd,
        "machine": machine,
        "graph_build_s": build,
        "graphs": {k: g.summary() for k, g in graphs.items()},
        "speed": speed.to_dict(orient="records"),
        "ratios": ratios.to_dict(orient="records"),
        "paper": {k: v for k, v in PAPER_B_TABLE1.items()},
        "targets": [{"target": w, "measured": v, "pass": bool(ok)} for w, v, ok in targets],
    }
    (HERE / "results" / "compose.json").write_text(json.dumps(payload, indent=2, default=float))
    print("\n".join(lines))
    return 0  # a FAIL is reported in the table, not as a crash of the benchmark


if __name__ == "__main__":
    sys.exit(main())
