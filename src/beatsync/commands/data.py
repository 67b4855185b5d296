"""``beatsync data``: list and verify the bundled real data."""

from __future__ import annotations

import argparse

from . import COMMAND_HELP
from ._common import EXIT_FAILED_ITEMS, EXIT_OK, add_output_flags, emit


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "data",
        help=COMMAND_HELP["data"],
        description="Verify every file of the bundled data against data/README.md's checksums.",
    )
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import datasets

    status = datasets.verify_all()
    lines = [f"{'OK ' if ok else 'BAD'} {rel}" for rel, ok in status.items()]
    bad = [rel for rel, ok in status.items() if not ok]
    lines.append(f"data folder: {datasets.data_dir()}")
    emit({"data_dir": str(datasets.data_dir()), "files": status}, "\n".join(lines), args)
    return EXIT_FAILED_ITEMS if bad else EXIT_OK
