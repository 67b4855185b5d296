"""``beatsync batch``: synchronise many clips with many songs on Dask."""

from __future__ import annotations

import argparse
import sys

from ._common import add_json_flag, add_period_range, emit


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "batch",
        help="sync every motion clip with every song, in parallel on Dask",
        description="Track each song's beats once, segment each clip once, then sync every "
        "(clip, song) pair on a Dask cluster (local by default). Writes "
        "OUT_DIR/<clip>__<song>.bvh and a summary CSV; a pair that fails on bad input "
        "records its error in the summary instead of stopping the run.",
    )
    p.add_argument("--clips", nargs="+", required=True, help="motion files (.bvh/.mat/.csv/.npy)")
    p.add_argument("--songs", nargs="+", required=True, help="audio files")
    p.add_argument("--out-dir", required=True, help="existing output folder")
    p.add_argument(
        "--fps", type=float, default=None, help="frame-rate override for every clip [Hz]"
    )
    p.add_argument("--bpm", type=float, default=None, help="known tempo of every song [BPM]")
    add_period_range(p)
    p.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler")
    p.add_argument(
        "--workers", type=int, default=None, help="local cluster workers (default: cores)"
    )
    p.add_argument("--summary", default=None, help="summary CSV (default OUT_DIR/summary.csv)")
    add_json_flag(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .. import io
    from ..batch import sync_grid
    from ..cluster import check_cluster_options
    from ._common import check_output_path

    workers = check_cluster_options(args.scheduler, args.workers)
    summary = Path(args.summary) if args.summary else Path(args.out_dir) / "summary.csv"
    check_output_path(summary, *args.clips, *args.songs)
    table = sync_grid(
        args.clips,
        args.songs,
        args.out_dir,
        scheduler=args.scheduler,
        n_workers=workers,
        fps=args.fps,
        bpm=args.bpm,
        period_range=tuple(args.period_range),
        progress=sys.stderr.isatty() and not args.json and not getattr(args, "quiet", False),
    )
    io.write_csv(summary, table)
    n_ok = int((table["status"] == "ok").sum())
    text = table.to_string(index=False) + f"\n{n_ok}/{len(table)} pairs synchronised; {summary}"
    emit({"summary": str(summary), "rows": table.to_dict("records")}, text, args)
    return 0 if n_ok else 1
