"""Benchmark of the tutorials' live sliders (``beatsync.learn.widgets.explore``).

For each tutorial in ``notebooks/tutorials/`` that shows a slider, the notebook's code
cells are run once in one namespace (its exercise and check cells left out) so that
the slider's ``update`` sees exactly the tutorial's data; then every slider state is
timed: **cold** (the first render of the state: ``update`` runs, its figure is drawn
to PNG) and **cached** (the same state again, as when a slider comes back to a value).
Target: an update takes at most 0.5 s on the tutorial's data. Baseline, measured in
the same run: drawing an empty figure of the same size to PNG (the floor of any
update that shows a figure).

Usage::

    .venv/bin/python benchmarks/bench_widgets.py [--only 01_segmentation ...]

Writes ``benchmarks/results/widgets.md`` and ``benchmarks/results/widgets.json``.
"""

from __future__ import annotations

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
TUTORIALS = HERE.parent / "notebooks" / "tutorials"
TARGET_S = 0.5


def _namespace(path: Path) -> dict:
    """Run a tutorial's code cells (not its exercises) and return their namespace."""
    import matplotlib

    matplotlib.use("Agg")
    import nbformat

    ns: dict = {"__name__": "__main__"}
    for cell in nbformat.read(path, as_version=4).cells:
        tags = cell.metadata.get("tags", [])
        if cell.cell_type == "code" and not {"exercise", "check"} & set(tags):
            exec(compile(cell.source, f"{path.name}", "exec"), ns)
    return ns


def _empty_figure_s(figsize: tuple[float, float], repeats: int = 5) -> float:
    import io

    import matplotlib.pyplot as plt

    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fig = plt.figure(figsize=figsize)
        fig.savefig(io.BytesIO(), format="png", dpi=80)
        plt.close(fig)
        times.append(time.perf_counter() - t0)
    return float(min(times))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", metavar="STEM", help="tutorials to time (file stems)")
    args = ap.parse_args()

    from beatsync import io
    from beatsync.learn.widgets import Explorer

    rows, summary = [], []
    for path in sorted(TUTORIALS.glob("*.ipynb")):
        if args.only and path.stem not in args.only:
            continue
        t0 = time.perf_counter()
        ns = _namespace(path)
        setup_s = time.perf_counter() - t0
        views = {k: v for k, v in ns.items() if isinstance(v, Explorer)}
        for name, view in views.items():
            view.clear()
            cold, cpu, cached = [], [], []
            for combo in view.combinations():
                t1, c1 = time.perf_counter(), time.process_time()
                state = view.render(**combo)
                cold.append(time.perf_counter() - t1)
                cpu.append(time.process_time() - c1)
                t1 = time.perf_counter()
                view.render(**combo)
                cached.append(time.perf_counter() - t1)
                rows.append({"tutorial": path.stem, "widget": name, "state": combo,
                             "cold_s": cold[-1], "cold_cpu_s": cpu[-1], "cached_s": cached[-1],
                             "png_bytes": len(state.png)})  # fmt: skip
            import matplotlib.pyplot as plt

            fig = view.update(**view.initial)
            fig = fig[0] if isinstance(fig, tuple) else fig
            floor = _empty_figure_s(tuple(fig.get_size_inches()))
            plt.close(fig)
            summary.append({
                "tutorial": path.stem, "widget": name, "states": len(cold),
                "setup_s": setup_s, "cold_median_s": float(np.median(cold)),
                "cold_max_s": float(np.max(cold)), "cold_cpu_max_s": float(np.max(cpu)),
                "cached_max_s": float(np.max(cached)),
                "empty_figure_s": floor, "ratio_to_empty_figure": float(np.median(cold)) / floor,
                "pass": float(np.max(cold)) <= TARGET_S,
                "pass_cpu": float(np.max(cpu)) <= TARGET_S,
            })  # fmt: skip
            print(summary[-1], flush=True)

    facts = {"command": "python benchmarks/bench_widgets.py", **_machine.machine_facts()}
    lines = [
        "## widgets: the tutorials' live sliders (issue 34)",
        "",
        f"Command: `{facts['command']}`  ",
        f"Machine: {facts['platform']}, {facts['processor']}, {facts['cpu_count']} CPUs "
        f"(1 used), Python {facts['python']}, numpy {facts['numpy']}, beatsync "
        f"{facts['beatsync']}; {facts['date_utc']}; load average "
        f"{', '.join(f'{v:.1f}' for v in facts['load_average'] or [])} (shared machine).",
        "",
        "Each tutorial's code cells run once (setup); then every slider state is rendered "
        "cold (`update` runs and its figure is drawn to PNG) and again from the cache. "
        "Baseline in the same run: an empty figure of the same size drawn to PNG. "
        f"Target: every cold update <= {TARGET_S:g} s (wall clock; the CPU time of the "
        "process shows what the machine's load added).",
        "",
        "| tutorial | widget | states | setup [s] | cold median [s] | cold max [s] | "
        "cold max, CPU [s] | cached max [ms] | cold median / empty figure | <= 0.5 s | "
        "CPU <= 0.5 s |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---|",
    ]
    for s in summary:
        lines.append(
            f"| {s['tutorial']} | `{s['widget']}` | {s['states']} | {s['setup_s']:.1f} | "
            f"{s['cold_median_s']:.3f} | {s['cold_max_s']:.3f} | {s['cold_cpu_max_s']:.3f} | "
            f"{s['cached_max_s'] * 1e3:.2f} | "
            f"{s['ratio_to_empty_figure']:.0f}x | {'PASS' if s['pass'] else 'FAIL'} | "
            f"{'PASS' if s['pass_cpu'] else 'FAIL'} |"
        )
    lines += ["", "Per state (cold [s]):", ""]
    for s in summary:
        states = [r for r in rows if (r["tutorial"], r["widget"]) == (s["tutorial"], s["widget"])]
        slowest = sorted(states, key=lambda r: -r["cold_s"])[:3]
        desc = "; ".join(
            f"{', '.join(f'{k}={v}' for k, v in r['state'].items())}: {r['cold_s']:.3f}"
            for r in slowest
        )
        lines.append(f"- {s['tutorial']} slowest: {desc}")
    lines.append("")
    md = "\n".join(lines)
    (HERE / "results").mkdir(exist_ok=True)
    with io.atomic_write(HERE / "results" / "widgets.md") as fh:
        fh.write(md)
    io.write_json(HERE / "results" / "widgets.json", {"facts": facts, "summary": summary,
                                                      "rows": rows})  # fmt: skip
    print(md)
    return 0 if all(s["pass"] for s in summary) else 1


if __name__ == "__main__":
    sys.exit(main())
