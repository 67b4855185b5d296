"""``beatsync batch``: synchronise many clips with many songs on Dask."""

from __future__ import annotations

import argparse

from . import COMMAND_HELP
from ._common import (
    add_mode,
    add_output_flags,
    add_period_range,
    add_tempo_range,
    emit,
    tempo_options,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "batch",
        help=COMMAND_HELP["batch"],
        description="Track each song's beats once, segment each clip once, then sync every "
        "(clip, song) pair on a Dask cluster (local by default), as `beatsync sync` does with its "
        "defaults (--mode auto, the dance looped to the song's end). Clips or songs "
        "whose file names repeat (one folder per take) are named by their folder. Writes "
        "OUT_DIR/<clip>__<song> in the clip's own kind of file (.bvh with a skeleton; joint "
        "positions in the input's layout: .json, .npy, .npz, .c3d; else .csv) and a "
        "summary CSV, all at the end (an error or Ctrl-C "
        "leaves OUT_DIR as it was); a pair that fails on bad input records its error in "
        "the summary instead of stopping the run. Workers of an existing cluster "
        "(--scheduler) must see the same paths.",
    )
    p.add_argument(
        "--clips",
        nargs="+",
        required=True,
        help="motion files (.bvh, .mat, .csv, .npy, .npz, .json, .c3d)",
    )
    p.add_argument("--songs", nargs="+", required=True, help="audio files")
    p.add_argument("--out-dir", required=True, help="existing output folder")
    p.add_argument("--fps", type=float, help="frame-rate override for every clip [Hz]")
    p.add_argument(
        "--variable",
        help="recording inside a .mat file, or array inside an .npz (e.g. dance2), of every clip",
    )
    p.add_argument("--bpm", type=float, help="known tempo of every song [BPM]")
    add_tempo_range(p)
    add_period_range(p)
    add_mode(p, default="auto")
    p.add_argument("--scheduler", help="address of an existing Dask scheduler")
    p.add_argument("--workers", type=int, help="local cluster workers (default: cores)")
    p.add_argument("--summary", help="summary CSV (default OUT_DIR/summary.csv)")
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import io
    from ..errors import ParameterError
    from ..io import check_input_file
    from ..sync_grid import item_names, output_suffixes, sync_grid
    from ..validation import check_cluster_options
    from ._common import Outputs, check_output, feedback

    tempo = tempo_options(args)  # before any work
    workers = check_cluster_options(args.scheduler, args.workers)
    inputs = [check_input_file(p, "clip") for p in args.clips]
    inputs += [check_input_file(p, "song") for p in args.songs]
    # all or nothing: the pairs are written into a staging folder inside --out-dir and
    # moved into place with the summary only when the whole grid has run
    with Outputs(inputs=inputs) as outs:
        out_dir = outs.add_folder(args.out_dir, option="--out-dir")
        summary = outs.add(
            args.summary or out_dir / "summary.csv", option="--summary", suffixes=[".csv"]
        )
        clip_names = item_names(args.clips, "clip")
        song_names = item_names(args.songs, "song")
        for c, cn in zip(args.clips, clip_names, strict=True):
            for sn in song_names:
                for suffix in output_suffixes(c):  # the pair's output, whichever it will be
                    name = f"{cn}__{sn}{suffix}"
                    pair = check_output(out_dir / name, option="--out-dir", inputs=inputs)
                    if pair.resolve() == summary.resolve():
                        raise ParameterError(
                            f"--summary {str(summary)!r} would be the synchronised "
                            f"{cn} x {sn} in --out-dir; give the "
                            "summary another name"
                        )
        fb = feedback(args)
        with fb.step("batch") as progress:
            table = sync_grid(
                args.clips,
                args.songs,
                outs.staging_folder(out_dir),
                scheduler=args.scheduler,
                n_workers=workers,
                fps=args.fps,
                variable=args.variable,
                **tempo,
                period_range=tuple(args.period_range),
                mode=args.mode,
                progress=progress,
            )
        for i in table.index[table["status"] == "ok"]:
            table.loc[i, "output"] = str(outs.adopt(table.loc[i, "output"], option="--out-dir"))
        io.write_csv(outs.path(summary), table)
    for row in table.to_dict("records"):
        for note in filter(None, row["warnings"].split(" | ")):
            fb.warn(f"{row['clip']} x {row['song']}: {note}")
    n_ok = int((table["status"] == "ok").sum())
    text = _text(table, args.out_dir) + f"\n{n_ok}/{len(table)} pairs synchronised; {summary}"
    emit({"summary": str(summary), "rows": table.to_dict("records")}, text, args)
    return 0 if n_ok else 1


def _text(table, out_dir: str) -> str:
    """A line per pair and its note or error on a line of its own (the columns are in the
    summary CSV and ``--json``), outputs shown in ``out_dir`` as given."""
    from pathlib import Path

    lines = []
    for row in table.to_dict("records"):
        head = f"{row['clip']} x {row['song']}"
        if row["status"] != "ok":
            lines.append(f"{head}: error: {row['error']}")
            continue
        mode = "periods" if row["mode"] == "periods" else "motion beats"
        lines.append(
            f"{head}: {mode}, {row['tempo_bpm']:.1f} BPM, {row['input_frames']:.0f} -> "
            f"{row['output_frames']:.0f} frames, largest residual "
            f"{row['max_abs_residual_ms']:.2f} ms -> {Path(out_dir) / Path(row['output']).name}"
        )
        if row.get("note"):
            lines.append(f"  {row['note']}")
    return "\n".join(lines)
