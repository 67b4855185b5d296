"""``beatsync segment``: split a periodic motion into its periods (paper A, sec. 3)."""

from __future__ import annotations

import argparse

from . import COMMAND_HELP
from ._common import (
    Outputs,
    add_output_flags,
    add_period_range,
    add_position_options,
    emit,
    feedback,
    position_options,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "segment",
        help=COMMAND_HELP["segment"],
        description=(
            "Globally optimal segmentation of a periodic motion into its periods: "
            "consecutive periods are as similar as possible (Pearson correlation of joint "
            "angles) while every period stays within +-alpha of the nominal period. "
            "MOTION is a .bvh (rotations), .mat (MoCap Toolbox markers, converted to "
            "joint angles), or a .csv/.npy table (needs --fps) of joint angles or of marker "
            "positions (columns <marker>_x/_y/_z, converted to joint angles). With "
            "--periods N the result has exactly N periods."
        ),
    )
    p.add_argument("motion", metavar="MOTION", help="motion file (.bvh, .mat, .csv, .npy)")
    p.add_argument(
        "--fps",
        type=float,
        help="frame rate [Hz]; overrides a BVH header (CMU salsa files: 60), required for "
        ".csv/.npy",
    )
    p.add_argument(
        "--alpha",
        type=float,
        default=0.1,
        help="allowed relative deviation of each period from the nominal period, in (0, 0.5) "
        "(default 0.1)",
    )
    p.add_argument(
        "--periods",
        type=int,
        help="number of periods if known (e.g. from the music); the result then has exactly "
        "N periods; default: estimate",
    )
    add_period_range(p)
    p.add_argument(
        "--bpm",
        type=float,
        help="tempo of the music the dance goes with [BPM]: search periods of 1 to 8 beats "
        "(0.9-8.5, as sync --mode periods; steps to figures such as a 6-beat waltz box), "
        "shortest first; instead of --period-range",
    )
    p.add_argument(
        "--period-method",
        choices=("energy", "fft"),
        default="energy",
        help="how to estimate the period: uniform-segmentation energy (default) or FFT peak",
    )
    p.add_argument(
        "--channels",
        nargs="+",
        default=["default"],
        help="'default' (limb and spine rotations, or *_angle channels), 'all', or channel names",
    )
    p.add_argument("--variable", help="recording inside a .mat file (e.g. dance2)")
    add_position_options(p)
    p.add_argument("--out", help="write the boundaries to this .csv file")
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from .. import io
    from ..errors import ParameterError
    from ..motion import is_marker_motion, segmentation_view
    from ..segment import period_range_from_beat, segment
    from ..validation import check_bpm, time_to_frames

    period_range = tuple(args.period_range)
    if args.bpm is not None:
        if isinstance(args.period_range, list):  # given on the command line
            raise ParameterError("give either --bpm or --period-range, not both")
        if args.periods is not None:
            raise ParameterError(
                "--bpm sets the period range for estimating the count; with --periods "
                "the count is given, so leave out --bpm"
            )
        period_range = period_range_from_beat(60.0 / check_bpm(args.bpm, name="--bpm"))
    fb = feedback(args)
    outs = Outputs(inputs=[args.motion])
    out = outs.add(args.out, option="--out", text="a CSV table of boundaries") if args.out else None
    with fb.step("reading motion"):
        motion = io.read_motion(
            args.motion, fps=args.fps, variable=args.variable, **position_options(args)
        )
    converted = is_marker_motion(motion)
    positions = None if motion.position_info is None else motion.position_info.describe()
    motion = segmentation_view(motion)  # markers -> joint angles, as in batch and sync
    chan = args.channels[0] if args.channels in (["default"], ["all"]) else args.channels
    with fb.step("segmenting periods"):
        seg = segment(
            motion,
            alpha=args.alpha,
            n_periods=args.periods,
            period_range=period_range,
            period_method="given" if args.periods is not None else args.period_method,
            channels=chan,
        )
    frames = time_to_frames(seg.boundaries, fps=seg.fps)
    if out is not None:
        with outs:
            io.write_csv(
                outs.path(out),
                pd.DataFrame(
                    {"boundary": range(frames.size), "time_s": seg.boundaries, "frame": frames}
                ),
            )
    result = {
        "motion": str(args.motion),
        "fps": seg.fps,
        "n_periods": seg.n_periods,
        "mean_period_s": seg.mean_period,
        "boundaries_s": seg.boundaries,
        "boundary_frames": frames,
        "energy": seg.energy,
        "normalised_energy": seg.normalised_energy,
        "period_method": seg.period_method,
        "alpha": args.alpha,
        "period_range_s": list(period_range),
        "channels": list(seg.channels),
        "marker_angles": converted,
        "positions": positions,
        "search_decimation": seg.search_decimation,
        "out": str(out) if out is not None else None,
    }
    text = "\n".join(
        [
            f"{seg.n_periods} periods, mean period {seg.mean_period:.4f} s "
            f"({60.0 / seg.mean_period:.1f} per minute), method {seg.period_method}, "
            f"{len(seg.channels)} channels",
            "boundaries [s]: " + " ".join(f"{t:.4f}" for t in seg.boundaries),
            *([f"joint positions: {positions}"] if positions else []),
        ]
        + ([f"wrote {out}"] if out is not None else [])
    )
    return emit(result, text, args)
