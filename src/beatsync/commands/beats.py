"""``beatsync beats``: track the beats of a piece of music (paper A, section 4); with
``--json`` also the tempo curve and the meter estimate (``beats_per_bar``)."""

from __future__ import annotations

from typing import Any

from ..errors import ParameterError
from . import COMMAND_HELP
from ._common import Outputs, add_output_flags, add_tempo_range, emit, feedback, tempo_options

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "beats",
        help=COMMAND_HELP["beats"],
        description=(
            "Track music beats with the phase-slope (group delay) onset detector, the "
            "metrical model of Klapuri et al. (2006) and a tempo/phase HMM (paper A, "
            "section 4), or with librosa's beat tracker. "
            "Prints beat times in seconds, one per line."
        ),
    )
    p.add_argument("audio", help="music file: .wav, .flac, .ogg, .mp3")
    p.add_argument(
        "--method",
        choices=("psf", "librosa"),
        default="psf",
        help="psf: phase-slope onsets + tempo/phase HMM (default); "
        "librosa: librosa.beat.beat_track",
    )
    p.add_argument(
        "--bpm",
        type=float,
        help="known tempo [BPM]: skip tempo estimation, only find the phase",
    )
    add_tempo_range(p)
    p.add_argument(
        "--out",
        metavar="FILE.beats",
        help="write the beat times [s] to this file, one per line",
    )
    p.add_argument(
        "--click",
        metavar="OUT.wav",
        help="write the audio with a click on every beat (.wav or .flac)",
    )
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: Any) -> int:
    # imported here, not at module level: building the parser must stay cheap
    from .. import io
    from ..beats import mix_clicks, track_beats

    # cheap checks first, so that nothing is read or written on bad options
    tempo = tempo_options(args)
    fb = feedback(args)
    with Outputs(inputs=[args.audio]) as outs:  # both files are written, or neither
        out = click = None
        if args.out is not None:
            out = outs.add(args.out, option="--out", text="beat times")
        if args.click is not None:
            click = outs.add(args.click, option="--click", suffixes=(".wav", ".flac"))
        with fb.noted() as notes:  # the decoder's and the tracker's
            with fb.step("reading audio"):
                y, sr = io.read_audio(args.audio)
            with fb.step("tracking beats"):
                track = track_beats(y, sr, method=args.method, **tempo)
        if track.beats.size == 0:
            raise ParameterError(
                f"no beats found in {args.audio!r} (no onsets: no attack in any band, e.g. near "
                "silence?); nothing written"
            )
        written = []
        if out is not None:
            io.write_beats(outs.path(out), track.beats)
            written.append(str(out))
        if click is not None:
            io.write_audio(outs.path(click), mix_clicks(y, sr, track.beats), sr)
            written.append(str(click))
    result = {
        "audio": args.audio,
        "method": track.method,
        "tempo_bpm": track.tempo,
        "n_beats": int(track.beats.size),
        "beats": track.beats,
        "tempo_times": track.tempo_times,
        "tempo_curve_bpm": track.tempo_curve,
        "beats_per_bar": track.beats_per_bar,
        "written": written,
        "warnings": notes,
    }
    text = "".join(f"{t:.6f}\n" for t in track.beats)
    return emit(result, text, args)
