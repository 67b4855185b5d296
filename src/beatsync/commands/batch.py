"""``beatsync batch``: synchronise many clips with many songs on Dask."""

from __future__ import annotations

import argparse

from . import COMMAND_HELP
from ._common import (
    EXIT_FAILED_ITEMS,
    EXIT_OK,
    Outputs,
    add_output_flags,
    add_period_range,
    emit,
    feedback,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "batch",
        help=COMMAND_HELP["batch"],
        description="Track each song's beats once, segment each clip once, then sync every "
        "(clip, song) pair on a Dask cluster (local by default). Writes "
        "OUT_DIR/<clip>__<song>.bvh and a summary CSV; a pair that fails on bad input "
        "records its error in the summary instead of stopping the run. The clips and the "
        "summary appear in OUT_DIR only when the whole run finished.",
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
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .. import io
    from ..batch import sync_grid
    from ..cluster import check_cluster_options

    workers = check_cluster_options(args.scheduler, args.workers)
    outs = Outputs(inputs=[*args.clips, *args.songs])
    out_dir = outs.add_folder(args.out_dir, option="--out-dir")
    summary = outs.add(args.summary or out_dir / "summary.csv", option="--summary")
    suffix = {c: ".bvh" if c.lower().endswith(".bvh") else ".csv" for c in args.clips}
    pair_files = {
        out_dir / f"{Path(c).stem}__{Path(s).stem}{suffix[c]}"
        for c in args.clips
        for s in args.songs
    }  # (repeated names are refused by sync_grid, with the reason)
    for f in sorted(pair_files):
        outs.add(f, option="--out-dir")
    with outs:  # every synchronised clip and the summary appear together, or none
        table = sync_grid(
            args.clips,
            args.songs,
            outs.staging_folder(out_dir),
            scheduler=args.scheduler,
            n_workers=workers,
            fps=args.fps,
            bpm=args.bpm,
            period_range=tuple(args.period_range),
            progress=feedback(args).bars,
        )
        for i in table.index[table["status"] == "ok"]:
            table.at[i, "output"] = str(outs.adopt(table.at[i, "output"], option="--out-dir"))
        io.write_csv(outs.path(summary), table)
    n_ok = int((table["status"] == "ok").sum())
    text = table.to_string(index=False) + f"\n{n_ok}/{len(table)} pairs synchronised; {summary}"
    emit({"summary": str(summary), "rows": table.to_dict("records")}, text, args)
    return EXIT_OK if n_ok else EXIT_FAILED_ITEMS
