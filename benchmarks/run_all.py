"""Run every benchmark (benchmarks/bench_*.py) and gather their tables into RESULTS.md.

Each benchmark times beatsync against a named baseline in the same run and writes
``benchmarks/results/<name>.md`` (and ``.json``). This script runs them one after the
other (so they do not compete for the cores) and concatenates the Markdown files.

Usage::

    python benchmarks/run_all.py            # run all, then collect
    python benchmarks/run_all.py --only segment beats
    python benchmarks/run_all.py --collect  # only rebuild RESULTS.md from results/
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


#: Further runs of a benchmark, each with these arguments (after its run with none).
EXTRA_RUNS = {"bench_evaluate": [["--source", "real", "--tracks", "42"]]}


def collect() -> Path:
    parts = [
        "# Benchmark results\n",
        "Produced by `make bench` (`python benchmarks/run_all.py`); each section below is "
        "written by one `benchmarks/bench_<name>.py` and names the command that reproduces "
        "it. Times are ratios against a baseline measured in the same run.\n",
    ]
    for md in sorted((HERE / "results").glob("*.md")):
        parts.append(md.read_text().rstrip() + "\n")
    dest = HERE / "RESULTS.md"
    fd, tmp = tempfile.mkstemp(dir=HERE, prefix=".RESULTS.", suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        fh.write("\n".join(parts))
    os.replace(tmp, dest)
    return dest


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", metavar="NAME", help="run only bench_NAME.py")
    ap.add_argument("--collect", action="store_true", help="only rebuild RESULTS.md")
    args = ap.parse_args()
    failed = []
    if not args.collect:
        scripts = sorted(HERE.glob("bench_*.py"))
        if args.only:
            scripts = [s for s in scripts if s.stem.removeprefix("bench_") in args.only]
        for script in scripts:
            for extra in [[], *EXTRA_RUNS.get(script.stem, [])]:
                print(f"== {' '.join([script.name, *extra])}", flush=True)
                if subprocess.run([sys.executable, str(script), *extra]).returncode != 0:
                    failed.append(" ".join([script.name, *extra]))
    print(f"wrote {collect()}")
    if failed:
        print(f"benchmarks that failed to run: {failed}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
