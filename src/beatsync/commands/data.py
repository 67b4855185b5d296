"""``beatsync data``: list and verify the bundled real data."""

from __future__ import annotations

import argparse

from ._common import add_json_flag, emit


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "data",
        help="list the bundled data files and verify their SHA-256 checksums",
        description="Verify every file of the bundled data against data/README.md's checksums.",
    )
    add_json_flag(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import datasets

    status = datasets.verify_all()
    lines = [f"{'OK ' if ok else 'BAD'} {rel}" for rel, ok in status.items()]
    bad = [rel for rel, ok in status.items() if not ok]
    lines.append(f"data folder: {datasets.data_dir()}")
    emit({"data_dir": str(datasets.data_dir()), "files": status}, "\n".join(lines), args)
    return 1 if bad else 0
