"""Benchmark of the program's start: what ``beatsync`` imports before it does any work.

The program imports only the module of the subcommand it runs. Baseline, measured in
the same run: the same program registering every subcommand eagerly (importing all
their modules, as it did before), and a bare interpreter (``python -c pass``).

Measured (whole process, wall time, median of ``--repeats``, interleaved so that a
load change hits all rows alike): ``python -c 'import beatsync.cli'``, ``beatsync
--help``, ``beatsync data --help``, ``beatsync beats --help``; and the sum of the
module import times reported by ``python -X importtime`` for each.

Usage::

    .venv/bin/python benchmarks/bench_cli.py [--repeats 9]

Writes ``benchmarks/results/cli.md`` and ``benchmarks/results/cli.json``.
"""

from __future__ import annotations

import os

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()

import argparse  # noqa: E402
import re  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
TARGET_HELP_RATIO = 0.5  # `beatsync --help` at most half the eager program's start

EAGER = (
    "import sys\nfrom beatsync.cli import build_parser\n"
    "build_parser().parse_args(sys.argv[1:])"  # every subcommand module imported
)
CASES = {
    "bare interpreter (python -c pass)": ["-c", "pass"],
    "python -c 'import beatsync.cli'": ["-c", "import beatsync.cli"],
    "beatsync --help": ["-m", "beatsync.cli", "--help"],
    "beatsync --help, eager (baseline)": ["-c", EAGER, "--help"],
    "beatsync data --help": ["-m", "beatsync.cli", "data", "--help"],
    "beatsync beats --help": ["-m", "beatsync.cli", "beats", "--help"],
    "beatsync beats --help, eager (baseline)": ["-c", EAGER, "beats", "--help"],
}
_LINE = re.compile(r"import time:\s+(\d+) \|\s+\d+ \|")


def _once(argv: list[str], importtime: bool) -> float:
    """Wall time [s] of one process, or its summed import time [s] with -X importtime."""
    cmd = [sys.executable, *(["-X", "importtime"] if importtime else []), *argv]
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise RuntimeError(f"{argv} failed: {out.stderr[-400:]}")
    if importtime:
        return sum(int(m[1]) for m in _LINE.finditer(out.stderr)) / 1e6
    return wall


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=9)
    args = ap.parse_args()
    src = str(HERE.parent / "src")
    os.environ["PYTHONPATH"] = src + os.pathsep + os.environ.get("PYTHONPATH", "")
    for argv in CASES.values():  # warm the byte-code caches
        _once(argv, False)
    wall: dict[str, list[float]] = {k: [] for k in CASES}
    imports: dict[str, list[float]] = {k: [] for k in CASES}
    for _ in range(args.repeats):
        for name, argv in CASES.items():
            wall[name].append(_once(argv, False))
            imports[name].append(_once(argv, True))
    med = {k: statistics.median(v) for k, v in wall.items()}
    imp = {k: statistics.median(v) for k, v in imports.items()}
    ratio_help = med["beatsync --help"] / med["beatsync --help, eager (baseline)"]
    ratio_beats = med["beatsync beats --help"] / med["beatsync beats --help, eager (baseline)"]

    facts = _machine.machine_facts()
    lines = [
        "# Program start (CLI imports)",
        "",
        "Command:",
        "",
        f"  .venv/bin/python benchmarks/bench_cli.py --repeats {args.repeats}",
        "",
        "Machine: " + ", ".join(f"{k} {v}" for k, v in facts.items()),
        "",
        "Whole process, wall time, median of the repeats (rows interleaved). Baseline: the "
        "same program registering every subcommand eagerly (all their modules imported), "
        "measured in the same run. Import time: sum of `python -X importtime`.",
        "",
        "| process | wall [ms] | imports [ms] |",
        "|---|---|---|",
        *(f"| {k} | {med[k] * 1e3:.0f} | {imp[k] * 1e3:.0f} |" for k in CASES),
        "",
        "| target | value | threshold | result |",
        "|---|---|---|---|",
        f"| `beatsync --help` / eager baseline | {ratio_help:.3f} | <= {TARGET_HELP_RATIO} | "
        f"{'PASS' if ratio_help <= TARGET_HELP_RATIO else 'FAIL'} |",
        f"| `beatsync beats --help` / eager baseline | {ratio_beats:.3f} | (reported) | - |",
        "",
    ]
    data = {
        "machine": facts,
        "repeats": args.repeats,
        "wall_s": med,
        "imports_s": imp,
        "ratio_help_vs_eager": ratio_help,
        "ratio_beats_help_vs_eager": ratio_beats,
    }
    _machine.write_results("cli", data, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
