"""Helpers shared by the subcommands: output, paths, progress."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..io import to_jsonable

__all__ = [
    "emit",
    "add_json_flag",
    "add_period_range",
    "add_position_options",
    "position_options",
    "check_output_path",
    "check_side_outputs",
    "to_jsonable",
]


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--json", action="store_true", help="print a machine-readable JSON object instead of text"
    )


def add_period_range(parser: argparse.ArgumentParser) -> None:
    """The ``--period-range LO HI`` option [s] shared by the commands that segment motion."""
    parser.add_argument(
        "--period-range",
        nargs=2,
        type=float,
        default=(0.25, 1.25),
        metavar=("LO", "HI"),
        help="shortest and longest motion period searched [s] (default 0.25 1.25, the "
        "paper's range; real dance cycles can be longer)",
    )


def emit(result: dict[str, Any], text: str, args: argparse.Namespace) -> int:
    """Print ``result`` as JSON if ``--json`` was given, else ``text``; return exit code 0."""
    if getattr(args, "json", False):
        json.dump(to_jsonable(result), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(text.rstrip("\n") + "\n")
    return 0


def check_output_path(out: str | Path, *inputs: str | Path | None) -> Path:
    """Refuse an output path equal to an input path, or in a missing/unwritable folder."""
    out_p = Path(out)
    for inp in inputs:
        if inp is None:
            continue
        in_p = Path(inp)
        if in_p.exists() and out_p.exists() and out_p.resolve() == in_p.resolve():
            raise ParameterError(
                f"output path {str(out)!r} is the same file as input {str(inp)!r}; "
                "beatsync never overwrites its input: choose another output name"
            )
        if out_p.resolve() == in_p.resolve():
            raise ParameterError(
                f"output path {str(out)!r} is the same as input {str(inp)!r}; choose another name"
            )
    from ..io import check_output_folder

    check_output_folder(out_p)
    return out_p


def check_side_outputs(
    video: str | Path | None,
    report: str | Path | None,
    inputs: tuple[str | Path | None, ...],
    out: Path,
) -> tuple[Path | None, Path | None]:
    """Check the optional ``--video`` (.mp4) and ``--report`` (.json) outputs of a command.

    Neither may equal an input or the main output, nor each other.
    """
    video_p = report_p = None
    if video is not None:
        video_p = check_output_path(video, *inputs, out)
        if video_p.suffix.lower() != ".mp4":
            raise ParameterError(f"--video {str(video)!r} must end in .mp4")
    if report is not None:
        report_p = check_output_path(report, *inputs, out, video)
        if report_p.suffix.lower() != ".json":
            raise ParameterError(f"--report {str(report)!r} must end in .json")
    return video_p, report_p


def add_position_options(parser: argparse.ArgumentParser) -> None:
    """``--up``, ``--units``, ``--max-gap`` for commands that read joint-position motion.

    Pass them on with ``io.read_motion(path, fps=args.fps, variable=args.variable,
    **position_options(args))``; ``--fps`` stays each command's own option (required
    for .json and .npy joint positions; a C3D file's own rate may not be contradicted).
    """
    parser.add_argument(
        "--up",
        choices=("y", "z"),
        default=None,
        help="vertical axis of joint positions (.json/.npy/.npz/.c3d); default detected",
    )
    parser.add_argument(
        "--units",
        choices=("m", "cm", "mm"),
        default=None,
        help="length unit of joint positions; default detected from the body's size",
    )
    parser.add_argument(
        "--max-gap",
        type=float,
        default=0.25,
        metavar="SECONDS",
        help="longest run of missing (NaN) joint values filled by interpolation [s] "
        "(default 0.25); a longer gap is refused with the joint named",
    )


def position_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of ``io.read_motion`` given by :func:`add_position_options`."""
    return {"up": args.up, "units": args.units, "max_gap": args.max_gap}
