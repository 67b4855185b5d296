"""Time the beat tracker of this working tree against an earlier revision, in one process.

The shared machine's speed drifts by up to half between runs an hour apart, more than
most changes to the tracker are worth. This script takes the earlier revision's
``src/beatsync`` out of git (``git archive``) into a temporary folder, imports it under
another name (``beatsync_base``; the package imports itself relatively) and calls both
trackers in turn, the order alternating, on the bundled recordings: a slow spell falls
on both alike. It reports each tracker's fastest and median call and the median of the
per-pair time ratios, and checks that both give the same beats.

Usage::

    .venv/bin/python benchmarks/compare_revisions.py --base 5d3b6f9
    .venv/bin/python benchmarks/compare_revisions.py --base HEAD~3 --pairs 100

It prints a table and writes it to ``benchmarks/results/compare_revisions.md`` (and
``.json``), with the command and the machine, for ``run_all.py --collect``.

One core, as in the other benchmarks (``_machine.pin_one_core``).
"""

from __future__ import annotations

import _machine  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

_machine.pin_one_core()  # before numpy is imported

import argparse  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tarfile  # noqa: E402
import tempfile  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def load_revision(rev: str, dest: Path):
    """The ``beatsync.beats`` package of git revision ``rev``, imported as ``beatsync_base``."""
    found = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}"],
        capture_output=True,
        text=True,
    )
    if found.returncode != 0:
        sys.exit(f"--base {rev!r}: not a commit of {ROOT} (a hash, tag, branch or HEAD~N)")
    listed = subprocess.run(
        ["git", "-C", str(ROOT), "ls-tree", "--name-only", rev, "src/beatsync/beats/"],
        capture_output=True,
        text=True,
    )
    if "src/beatsync/beats/tracker.py" not in listed.stdout.split():
        sys.exit(f"--base {rev!r}: that revision has no src/beatsync/beats/tracker.py to compare")
    archive = dest / "src.tar"
    with archive.open("wb") as fh:
        subprocess.run(
            ["git", "-C", str(ROOT), "archive", "--format=tar", rev, "src/beatsync"],
            stdout=fh,
            check=True,
        )
    with tarfile.open(archive) as tar:
        tar.extractall(dest, filter="data")
    (dest / "src" / "beatsync").rename(dest / "beatsync_base")
    sys.path.insert(0, str(dest))
    return importlib.import_module("beatsync_base.beats")


def items():
    """(name, audio, rate, pairs factor): the madmom sample, 30 s of two recordings."""
    from beatsync import datasets

    y, sr = datasets.load_madmom_sample()[:2]
    out = [("madmom sample (2.8 s)", y, sr, 1.0)]
    for name, start in (("ballroom_waltz", 0.0), ("hainsworth_001", 10.0)):
        y, sr = datasets.load_real_dev(name)[:2]
        out.append(
            (f"{name}, 30 s from {start:g} s", y[int(start * sr) : int((start + 30) * sr)], sr, 0.1)
        )
    return out


def compare(base, new, y, sr, pairs: int) -> dict:
    b_beats = base.track_beats(y, sr).beats  # warm-up, and the beats to compare
    n_beats = new.track_beats(y, sr).beats
    same = b_beats.shape == n_beats.shape
    diff = float(np.max(np.abs(b_beats - n_beats))) if same and b_beats.size else 0.0
    times = _machine.interleaved_times(
        [lambda: base.track_beats(y, sr), lambda: new.track_beats(y, sr)], pairs
    )
    tb, tn = (np.array(t) * 1e3 for t in times)
    return {
        "base min [ms]": tb.min(),
        "base median [ms]": np.median(tb),
        "new min [ms]": tn.min(),
        "new median [ms]": np.median(tn),
        "new/base (median of pair ratios)": float(np.median(tn / tb)),
        "same beats": "yes"
        if same and diff == 0.0
        else ("no" if not same else f"within {diff:.1e} s"),
    }


def _git(*args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True
    ).stdout.strip()


def _md_table(rows: list[dict]) -> str:
    cols = list(rows[0])
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        cells = [f"{v:.3f}" if isinstance(v, float) else str(v) for v in r.values()]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="git revision to compare against")
    ap.add_argument(
        "--pairs",
        type=int,
        default=300,
        help="call pairs on the madmom sample (a tenth on the 30 s items)",
    )
    args = ap.parse_args()
    if args.pairs < 1:
        ap.error(f"--pairs {args.pairs}: give at least one pair of calls")
    warnings.simplefilter("ignore")  # the no-clear-pulse warning, on both
    import beatsync.beats as new

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base = load_revision(args.base, Path(tmp))
        print(f"base {args.base} ({base.__file__}) against the working tree ({new.__file__})")
        for name, y, sr, factor in items():
            row = {"item": name, **compare(base, new, y, sr, max(int(args.pairs * factor), 5))}
            rows.append(row)
            print(
                ", ".join(
                    f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()
                )
            )
    base_hash = _git("rev-parse", "--short", f"{args.base}^{{commit}}")
    head = _git("rev-parse", "--short", "HEAD")
    dirty = " (with uncommitted changes)" if _git("status", "--porcelain", "--", "src") else ""
    facts = _machine.machine_facts()
    md = [
        "# The tracker against an earlier revision (interleaved, one process)",
        "",
        "Command:",
        "",
        f"  .venv/bin/python benchmarks/compare_revisions.py --base {args.base} "
        f"--pairs {args.pairs}",
        "",
        "Machine: " + ", ".join(f"{k} {v}" for k, v in facts.items()),
        "",
        f"Base: {args.base} ({base_hash}); new: the working tree at {head}{dirty}. Each call "
        "of one tracker is followed by a call of the other, the order alternating; "
        "new/base is the median of the per-pair time ratios, which a slow spell of the "
        "shared machine moves much less than the medians themselves. `same beats`: the "
        "two trackers' beats compared exactly.",
        "",
        _md_table(rows),
        "",
    ]
    out = Path(__file__).resolve().parent / "results"
    out.mkdir(exist_ok=True)
    (out / "compare_revisions.md").write_text("\n".join(md))
    payload = {
        "base": args.base,
        "base_hash": base_hash,
        "head": head,
        "rows": rows,
        "machine": facts,
    }
    (out / "compare_revisions.json").write_text(json.dumps(payload, indent=1, default=float))
    print(f"wrote {out / 'compare_revisions.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
