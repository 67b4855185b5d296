"""``beatsync evaluate beats``: score a beat tracker against annotations over a dataset."""

from __future__ import annotations

import argparse
from typing import Any

from . import COMMAND_HELP
from ._common import EXIT_FAILED_ITEMS, add_output_flags, emit

#: Unmatched audio files named in the text output before "... and N more".
SHOWN = 10


def register(subparsers: argparse._SubParsersAction) -> None:
    from ..other_trackers import TRACKERS

    p = subparsers.add_parser(
        "evaluate",
        help=COMMAND_HELP["evaluate"],
        description="Score a method over a dataset of files. WHAT is what is scored.",
        epilog="`beatsync evaluate WHAT --help` lists the options of WHAT (each accepts "
        "--json for machine-readable output).",
    )
    sub = p.add_subparsers(dest="what", metavar="WHAT")
    sub.required = True
    b = sub.add_parser(
        "beats",
        help="track every audio file and score it with mir_eval",
        description="Track the beats of every audio file under --audio with --method, score "
        "them with every mir_eval.beat metric against the annotation of the same name "
        "(NAME.beats under --annotations: one time [s] per line, an optional second column "
        "is ignored), on a Dask cluster (local by default). Each track's row is appended to "
        "RESULTS_DIR/tracks.jsonl as soon as its group finishes (a worker takes up to 8 "
        "tracks at a time, fewer toward the end), so an interrupted run loses only the "
        "groups in flight and a rerun skips the tracks already scored (--force re-runs "
        "them). At the end RESULTS_DIR/tracks.csv and RESULTS_DIR/summary.csv (means per "
        "method and folder) are written. A track that fails (unreadable, silent) is recorded "
        "with its error; audio without an annotation is listed and skipped.",
    )
    b.add_argument("--audio", required=True, metavar="DIR", help="folder of audio files")
    b.add_argument(
        "--annotations", required=True, metavar="DIR", help="folder of NAME.beats files [s]"
    )
    b.add_argument(
        "--method",
        default="psf",
        choices=list(TRACKERS),
        help="beat tracker (default psf, ours; essentia-* need pip install 'beatsync[peers]')",
    )
    b.add_argument("--out", required=True, metavar="RESULTS_DIR", help="results folder")
    b.add_argument(
        "--min-beat-time",
        type=float,
        default=0.0,
        help="beats before this time are not scored [s] (default 0; MIREX uses 5)",
    )
    b.add_argument(
        "--min-bpm",
        type=float,
        help="slowest tempo the tracker searches on every track [BPM] (default 40); "
        "essentia's trackers take whole BPM from 40 to 180, at least 20 below --max-bpm. "
        "With a bound other than the default, librosa searches a flat tempo prior inside "
        "the range instead of its own log-normal prior around 120 BPM. Only psf keeps its "
        "beats inside the range (librosa's bounds its tempo estimate, essentia's is a "
        "preference): the command counts the tracks whose beats fall outside it",
    )
    b.add_argument(
        "--max-bpm",
        type=float,
        help="fastest tempo the tracker searches [BPM] (default 240 for psf and librosa, "
        "208 for essentia's, which take whole BPM from 60 to 250)",
    )
    b.add_argument("--scheduler", help="address of an existing Dask scheduler")
    b.add_argument("--workers", type=int, help="local cluster workers (default: cores)")
    b.add_argument(
        "--force",
        action="store_true",
        help="re-run the tracks of this run although already scored (rows of other tracks "
        "in --out are kept; a track whose audio or annotation changed is always re-run)",
    )
    add_output_flags(b)
    b.set_defaults(func=run_beats)


def run_beats(args: argparse.Namespace) -> int:
    from pathlib import Path

    import pandas as pd

    from .. import other_trackers
    from ..errors import ParameterError
    from ..evaluate.beats import EMPTY_REFERENCE_TEXT
    from ..study.beat_dataset import RESULT_FILES, evaluate_dataset, find_tracks
    from ..validation import check_cluster_options, check_positive
    from ._common import Interrupted, check_output, feedback, interrupted_by

    fb = feedback(args)
    # cheapest first: options, then the output folder, then the inputs
    workers = check_cluster_options(args.scheduler, args.workers)
    mbt = check_positive(args.min_beat_time, name="--min-beat-time", unit="s", allow_zero=True)
    tempo = other_trackers.check_tempo_range(
        args.method, args.min_bpm, args.max_bpm, names=("--min-bpm", "--max-bpm")
    )
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--out {args.out!r} is a file; give a folder for the results")
    if out.is_dir():  # the files it will hold must be writable files
        for name in RESULT_FILES:
            check_output(out / name, option="--out")
        foreign = [n for n in RESULT_FILES[1:] if (out / n).exists()]
        if foreign and not (out / RESULT_FILES[0]).exists():
            # results are rebuilt from tracks.jsonl: without it these are not ours
            raise ParameterError(
                f"--out {args.out!r} holds {' and '.join(foreign)} but no {RESULT_FILES[0]}: "
                "files that evaluate beats did not write, which it would replace; choose "
                "another folder, or remove them"
            )
    other_trackers.get(args.method)
    found = find_tracks(args.audio, args.annotations)
    if found.unmatched:
        fb.warn(
            f"{len(found.unmatched)} audio file(s) without an annotation (NAME.beats) are "
            f"skipped: {_some(found.unmatched)}"
        )
    for note, users in list(found.shared.items())[:SHOWN]:
        fb.warn(
            f"annotation {str(note)!r} would serve more than one recording (found by name "
            f"only for {', '.join(str(p) for p in users[:SHOWN])}): skipped for "
            f"{'it' if len(users) == 1 else 'them'}; put each annotation at its audio "
            "file's relative path"
        )
    if len(found.shared) > SHOWN:
        fb.warn(f"... and {len(found.shared) - SHOWN} more annotations shared by name")
    if found.duplicates:
        fb.warn(
            f"{len(found.duplicates)} audio file(s) skipped: another file of the same name "
            f"with another suffix is scored instead: {_some(found.duplicates)}"
        )
    try:
        with fb.step(f"evaluate {args.method}") as bar:

            def progress(*a: Any, **k: Any) -> None:
                # a signal whose exception a garbage-collector callback swallowed ("Exception
                # ignored in ... Interrupted") let the run go on to the end: stop at the next
                # finished group of tracks
                signum = interrupted_by()
                if signum is not None:
                    raise Interrupted(signum)
                bar(*a, **k)

            run = evaluate_dataset(
                found.tracks,
                out,
                method=args.method,
                min_beat_time=mbt,
                force=args.force,
                **tempo,
                scheduler=args.scheduler,
                n_workers=workers,
                progress=progress,
            )
    except KeyboardInterrupt as exc:  # the finished tracks stay recorded: say so
        log = out / "tracks.jsonl"
        exc.outcome = (  # type: ignore[attr-defined]  # said by the error report
            f"; the finished tracks are recorded in {str(log)!r}: run the same command "
            "again to score the others"
            if log.is_file()
            else " before any track finished: nothing was recorded"
        )
        raise
    t = run.tracks
    failed = t[t["status"] != "ok"]
    warned = t["warning"].fillna("").astype(str) if "warning" in t else pd.Series("", t.index)
    outside = t[(t["status"] == "ok") & warned.str.contains(other_trackers.OUT_OF_RANGE_TEXT)]
    empty_ref = t[(t["status"] == "ok") & warned.str.contains(EMPTY_REFERENCE_TEXT)]
    result = {
        "method": args.method,
        "min_bpm": tempo.get("min_bpm"),
        "max_bpm": tempo.get("max_bpm"),
        "tracks": len(t),
        "scored_now": run.scored,
        "skipped": run.skipped,
        "changed": run.changed,
        "failed": failed[["key", "error"]].to_dict("records"),
        "outside_range": outside["key"].tolist(),
        "no_reference_beats": empty_ref["key"].tolist(),
        "unmatched": [str(p) for p in found.unmatched],
        "shared_annotations": {str(k): [str(p) for p in v] for k, v in found.shared.items()},
        "duplicates": [str(p) for p in found.duplicates],
        "summary": run.summary.to_dict("records"),
        "files": {k: str(v) for k, v in run.files.items()},
    }
    cols = ["method", "group", "tracks", "failed", "F-measure", "Correct Metric Level Total"]
    cols += ["Any Metric Level Total", "octave errors"]
    shown = run.summary[cols].rename(
        columns={"Correct Metric Level Total": "CMLt", "Any Metric Level Total": "AMLt"}
    )
    lines = [shown.to_string(index=False, float_format=lambda x: f"{x:.3f}"), ""]
    for _, row in failed.iterrows():
        lines.append(f"failed: {row['key']}: {row['error']}")
    if len(empty_ref):
        lines.append(
            f"{len(empty_ref)} track(s) have no annotated beat after --min-beat-time "
            f"{mbt:g} s and score 0 in the means: "
            f"{', '.join(empty_ref['key'].astype(str).tolist()[:SHOWN])}"
            + (" ..." if len(empty_ref) > SHOWN else "")
        )
    if len(outside):
        lines.append(
            f"{len(outside)} track(s) tapped outside the tempo range given (only psf keeps "
            f"to it; the warning column of {run.files['tracks'].name} says which)"
        )
    skipped = f", {run.skipped} already scored (--force re-runs them)" if run.skipped else ""
    if run.changed:
        skipped += (
            f", {run.changed} scored before and run again: their audio file or annotation "
            "changed since"
        )
    searched = "".join(f", --{k.replace('_', '-')} {v:g}" for k, v in tempo.items())
    lines.append(
        f"{len(t) - len(failed)}/{len(t)} tracks scored with {args.method}{searched} "
        f"({run.scored} run now{skipped}); results in {run.files['summary'].parent}"
    )
    emit(result, "\n".join(lines), args)
    return 0 if len(failed) < len(t) else EXIT_FAILED_ITEMS


def _some(paths: list) -> str:
    """The first :data:`SHOWN` paths, and how many more."""
    names = [str(p) for p in paths]
    more = f" ... and {len(names) - SHOWN} more" if len(names) > SHOWN else ""
    return ", ".join(names[:SHOWN]) + more
