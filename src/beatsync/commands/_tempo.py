"""The music options of the commands that track beats: a known beat list or tempo, and
the tempo range searched (``beats``, ``sync``, ``compose``, ``batch``).

Like :mod:`._common`, it imports nothing heavy at import time.
"""

from __future__ import annotations

import argparse

from ..errors import ParameterError

__all__ = ["add_music_beat_options", "add_tempo_range", "tempo_options"]


def add_music_beat_options(parser: argparse.ArgumentParser) -> None:
    """``--beats FILE`` (known beat times: no tracking), ``--bpm`` (known tempo) and the
    tempo range searched (:func:`add_tempo_range`)."""
    parser.add_argument(
        "--beats",
        default=None,
        metavar="FILE",
        help="music beat times [s], one per line (first column): skip beat tracking",
    )
    parser.add_argument(
        "--bpm",
        type=float,
        default=None,
        help="known tempo of the music [BPM]: the tracker only finds the phase",
    )
    add_tempo_range(parser)


def add_tempo_range(parser: argparse.ArgumentParser) -> None:
    """``--min-bpm`` and ``--max-bpm``: the tempo range the beat tracker searches."""
    parser.add_argument(
        "--min-bpm",
        type=float,
        default=None,
        help="slowest tempo the beat tracker considers [BPM] (default 40); with --max-bpm, "
        "a range that keeps the tracker off a metrical level you know is wrong",
    )
    parser.add_argument(
        "--max-bpm",
        type=float,
        default=None,
        help="fastest tempo the beat tracker considers [BPM] (default 240)",
    )


def tempo_options(args: argparse.Namespace) -> dict[str, float]:
    """The beat tracker's tempo keywords (``bpm``, ``min_bpm``, ``max_bpm``) from the
    options, checked before any work and named as options in the errors.

    Raises
    ------
    ParameterError
        ``--beats`` with ``--bpm``, a range given with either (the tempo is then not
        searched), a tempo outside 20-400 BPM, or ``--min-bpm`` not below ``--max-bpm``.
    """
    from ..beats.tracker import DEFAULT_MAX_BPM, DEFAULT_MIN_BPM  # noqa: PLC0415 (numpy)
    from ..units import check_bpm  # noqa: PLC0415

    if getattr(args, "beats", None) is not None and args.bpm is not None:
        raise ParameterError(
            "--beats and --bpm conflict: give beat times (--beats FILE) or a tempo (--bpm), "
            "not both"
        )
    bounds = {"--min-bpm": args.min_bpm, "--max-bpm": args.max_bpm}
    given = [name for name, value in bounds.items() if value is not None]
    fixed = "--bpm" if args.bpm is not None else None
    if getattr(args, "beats", None) is not None:
        fixed = "--beats"
    if given and fixed is not None:
        raise ParameterError(
            f"{' and '.join(given)} {'bound' if len(given) == 2 else 'bounds'} the tempo that "
            "the beat tracker searches, and "
            f"{fixed} means that it searches none: give one or the other"
        )
    if args.bpm is not None:
        return {"bpm": check_bpm(args.bpm, name="--bpm")}
    lo = DEFAULT_MIN_BPM if args.min_bpm is None else check_bpm(args.min_bpm, name="--min-bpm")
    hi = DEFAULT_MAX_BPM if args.max_bpm is None else check_bpm(args.max_bpm, name="--max-bpm")
    if not lo < hi:
        raise ParameterError(
            f"--min-bpm {lo:g} must be smaller than --max-bpm {hi:g}"
            + ("" if len(given) == 2 else " (the other bound is its default)")
        )
    return {"min_bpm": lo, "max_bpm": hi}
