"""``beatsync sync``: make a dance follow a song (paper A, section 5, and real dances).

Reads a motion and a song, finds the music's beats (or reads them) and calls
:func:`beatsync.sync.synchronize` with ``boundaries=None`` in the ``--mode`` and ``--fill``
chosen; writes the motion in its input's kind, optionally a video and the report.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError, warn
from . import COMMAND_HELP
from ._common import (
    Feedback,
    Outputs,
    add_mode,
    add_music_beat_options,
    add_output_flags,
    add_position_options,
    beats_end_early,
    emit,
    feedback,
    position_options,
    tempo_options,
)

__all__ = ["register", "run"]

#: shortest song the beat tracker is asked about [s]
MIN_MUSIC_S = 1.0


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "sync",
        help=COMMAND_HELP["sync"],
        description=(
            "Make a dance follow a song: find the motion's periods (or, for a dance "
            "that is not strictly periodic, its own motion beats) and the music's beats, "
            "then resample the motion (quaternion slerp for rotations, linear for joint "
            "positions) so that every period boundary (or motion beat) lands on a beat. "
            "Writes BVH with the input skeleton, joint positions in the input's layout, "
            "or CSV for marker/table input; optionally an MP4 with the music; and prints "
            "a report (frames, periods, beats per period, tempo ratios, boundary "
            "residuals in ms). The output's time 0 is the music's time 0."
        ),
    )
    p.add_argument(
        "motion",
        help="motion file: .bvh, .mat (MoCap Toolbox), .csv or .npy angle tables, or joint "
        "positions (.json, (frames, joints, 3) .npy/.npz, .c3d)",
    )
    p.add_argument("audio", help="music file: .wav, .flac, .ogg, .mp3")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="output motion: .bvh (needs a skeleton), .csv, or for joint positions "
        ".json/.npy/.npz/.c3d",
    )
    p.add_argument(
        "--fps",
        type=float,
        help="input frame rate [Hz]: overrides the BVH header; required for csv/npy",
    )
    p.add_argument("--out-fps", type=float, help="output frame rate [Hz] (default: the input's)")
    p.add_argument("--variable", help="recording inside a .mat file (e.g. dance2)")
    add_position_options(p)
    add_music_beat_options(p)
    p.add_argument(
        "--beats-per-period",
        type=int,
        metavar="N",
        help="music beats per motion period, or per median motion beat with --mode beats "
        "(default: periods round(motion period / beat), respecting the meters; motion "
        "beats: chosen for the whole dance within the playback speed band)",
    )
    p.add_argument(
        "--first-beat",
        type=int,
        default=0,
        metavar="K",
        help="index of the beat the first period starts on (default 0)",
    )
    p.add_argument(
        "--phase-offset",
        type=float,
        default=0.0,
        metavar="S",
        help="land period boundaries S seconds after their beats (default 0)",
    )
    p.add_argument(
        "--align-accents",
        action="store_true",
        help="put the dancer's accents (kinematic beats: minima of joint speed) "
        "on the beats instead of the period boundaries",
    )
    add_mode(p, default="auto")
    p.add_argument(
        "--fill",
        choices=("loop", "stop"),
        default="loop",
        help="'loop' (default): repeat whole periods, with blended joins, until the dance "
        "covers the song to its end (dancing on after the last beat); 'stop': end with the "
        "clip's last period",
    )
    p.add_argument(
        "--beats-per-bar",
        type=int,
        metavar="N",
        help="the music's meter (3 for a waltz; default: estimated by the beat tracker); "
        "beats per period then respect it",
    )
    p.add_argument(
        "--dance-beats",
        type=int,
        metavar="N",
        help="the dance's meter: beats of one period of the dance (3 for a waltz step, 6 for "
        "a waltz box); with periods, beats per period are then a multiple of it (a warning "
        "says so when the song's meter does not fit); with motion beats, every N motion "
        "beats start on a bar line of the song where the speed allows (default: the "
        "dance's own phrase, estimated from its period when it is clear)",
    )
    p.add_argument(
        "--period-range",
        nargs=2,
        type=float,
        metavar=("LO", "HI"),
        help="shortest and longest motion period searched [s] (default: with --mode periods "
        "one to eight beats of the song, so real dance cycles such as a 4 s waltz box are "
        "found; with --mode auto paper A's 0.25 1.25, periods for step-periodic dances)",
    )
    p.add_argument(
        "--video",
        metavar="OUT.mp4",
        help="also write a stick-figure video with the music as soundtrack",
    )
    p.add_argument(
        "--video-fps", type=float, default=30.0, help="frame rate of the video [Hz] (default 30)"
    )
    p.add_argument("--report", metavar="FILE.json", help="write the report as JSON")
    add_output_flags(p)
    p.set_defaults(func=run)


def _check_inputs(args: argparse.Namespace) -> tuple[Outputs, Path, Path | None, Path | None]:
    from ..io import MOTION_OUTPUT_SUFFIXES, check_input_file
    from ..validation import check_motion_fps

    if args.align_accents and args.phase_offset != 0.0:
        raise ParameterError(
            "--align-accents measures the phase offset itself; do not also give --phase-offset"
        )
    if args.beats_per_bar is not None and args.beats_per_bar < 1:
        raise ParameterError(
            f"--beats-per-bar {args.beats_per_bar} must be a whole number of beats >= 1 "
            "(3 for a waltz, 4 for most pop)"
        )
    if args.dance_beats is not None and args.dance_beats < 1:
        raise ParameterError(
            f"--dance-beats {args.dance_beats} must be a whole number of beats >= 1 "
            "(3 for a waltz step)"
        )
    if args.period_range is not None and not 0 < args.period_range[0] < args.period_range[1]:
        raise ParameterError(
            f"--period-range {args.period_range[0]:g} {args.period_range[1]:g} must be "
            "LO HI with 0 < LO < HI [s]"
        )
    tempo_options(args)  # a bad tempo or range, or --beats with --bpm: before any work
    if Path(args.output).suffix.lower() not in MOTION_OUTPUT_SUFFIXES:
        raise ParameterError(
            f"output {args.output!r} must end in .bvh or .csv, or for joint positions .json, "
            ".npy, .npz or .c3d (the motion is written there)"
        )
    for inp, what in ((args.motion, "motion"), (args.audio, "audio"), (args.beats, "beats")):
        if inp is not None:
            check_input_file(inp, what)
    if args.video:
        check_motion_fps(args.video_fps, name="--video-fps")  # before minutes of work
    outs = Outputs(inputs=(args.motion, args.audio, args.beats))
    out = outs.add(args.output, option="-o/--output")
    video = outs.add(args.video, option="--video", suffixes=[".mp4"]) if args.video else None
    report = outs.add(args.report, option="--report", suffixes=[".json"]) if args.report else None
    return outs, out, video, report


def run(args: argparse.Namespace) -> int:
    from .. import io

    outs, out, video, report_path = _check_inputs(args)
    fb = feedback(args)
    with outs:  # the motion, video and report are all written, or none of them
        with fb.noted() as notes:
            result = _pipeline(args, outs, out, video, fb)
        result["warnings"] = notes
        if report_path is not None:
            io.write_json(outs.path(report_path), result)
            result["outputs"]["report"] = str(report_path)
    return emit(result, _text(result), args)


def _pipeline(
    args: argparse.Namespace, outs: Outputs, out: Path, video: Path | None, fb: Feedback
) -> dict[str, Any]:
    from .. import io
    from ..sync import synchronize

    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    with fb.step("reading motion"):
        t0 = time.perf_counter()
        motion = io.read_motion(
            args.motion, fps=args.fps, variable=args.variable, **position_options(args)
        )
        io.check_motion_output(motion, out.suffix.lower(), out)
        y, sr = io.read_audio(args.audio)
        timings["read_s"] = time.perf_counter() - t0

    music_s = y.size / sr
    meter = (args.beats_per_bar, "--beats-per-bar" if args.beats_per_bar else "unknown")
    with fb.step("finding beats"):
        t0 = time.perf_counter()
        if args.beats is not None:
            from ..validation import check_times

            # beats after the music's end are a unit mistake (ms, frames), and would make
            # the dance run on for hours: refused before any work
            beats = check_times(
                io.read_beats(args.beats), name=f"beat times in {args.beats!r}", duration=music_s
            )
            if beats.size < 2:
                raise ParameterError(
                    f"the beats file {args.beats!r} holds {beats.size} beat time(s); at least "
                    "two are needed to sync a dance"
                )
            beat_source = f"file {args.beats}"
            then = "the dance goes on from there at its last speed, on no beat"
            early = beats_end_early(beats, music_s, args.beats, then)
            if early:
                warn(early)
        else:
            from ..beats import track_beats

            if music_s < MIN_MUSIC_S:
                raise ParameterError(
                    f"the music ({music_s:.2f} s) is shorter than {MIN_MUSIC_S:g} s: too short "
                    "to find beats in; use a longer song"
                )
            tempo = tempo_options(args)
            track = track_beats(y, sr, **tempo)
            beats = np.asarray(track.beats, dtype=np.float64)
            if args.beats_per_bar is None and getattr(track, "beats_per_bar", 0) > 0:
                meter = (int(track.beats_per_bar), "estimated by track_beats")
            told = ((k, getattr(args, k)) for k in ("bpm", "min_bpm", "max_bpm"))
            beat_source = (
                "track_beats(method='psf'"
                + "".join(f", {k}={v:g}" for k, v in told if v is not None)
                + ")"
            )
            if beats.size < 2:
                raise ParameterError(
                    f"no detectable beats in {args.audio!r} ({beats.size} found): is it silent "
                    "or without rhythm? give --bpm or --beats FILE"
                )
        timings["beats_s"] = time.perf_counter() - t0

    with fb.step("synchronising motion"):
        t0 = time.perf_counter()
        res = synchronize(
            motion,
            None,
            beats,
            mode=args.mode,
            land="accents" if args.align_accents else "boundaries",
            fill=args.fill,
            beats_per_period=args.beats_per_period,
            beats_per_bar=meter[0],
            dance_beats_per_period=args.dance_beats,
            first_beat=args.first_beat,
            out_fps=args.out_fps,
            phase_offset=args.phase_offset,
            period_range=None if args.period_range is None else tuple(args.period_range),
            song_end=music_s,
        )
        timings["sync_s"] = time.perf_counter() - t0

    written: dict[str, str] = {}
    if video is not None:
        t0 = time.perf_counter()
        vid = outs.write_video(
            video,
            res.motion,
            audio=(y, sr),
            fps=args.video_fps,
            beats=beats,
            progress=fb.bars,
            duration=music_s if args.fill == "loop" else None,
        )
        written["video"] = str(vid)
        timings["video_s"] = time.perf_counter() - t0

    with fb.step("writing motion"):
        io.write_motion(outs.path(out), res.motion)
        written["motion"] = str(out)

    timings["total_s"] = time.perf_counter() - t_start
    rep = dict(res.report)
    result: dict[str, Any] = {
        "motion": str(args.motion),
        "positions": None if motion.position_info is None else motion.position_info.describe(),
        "audio": str(args.audio),
        "beats_source": beat_source,
        "n_music_beats": int(beats.size),
        "beats_per_bar": meter[0],
        "beats_per_bar_source": meter[1],
        "music_duration_s": music_s,
        # the events: paper A's periods, or the dancer's own motion beats
        "segmentation": (
            {
                "mode": "beats",
                "n_motion_beats": int(rep["periods_available"]) + 1,
                "median_interval_s": float(rep["mean_motion_period_s"]),
            }
            if rep["mode"] == "beats"
            else {
                "mode": "periods",
                "n_periods": int(rep["periods_available"]),
                "mean_period_s": float(rep["mean_motion_period_s"]),
            }
        ),
        "report": rep,
        "outputs": written,
        "timings": timings,
    }
    return result


def _text(result: dict[str, Any]) -> str:
    r = result["report"]
    res = np.abs(np.asarray(r["residual_ms"]))
    near = np.abs(np.asarray(r["residual_nearest_frame_ms"]))
    unit = "periods" if r["mode"] == "periods" else "motion beats"
    meter = ""
    if r.get("meter_fit") is False:
        meter = " (meters do not fit)"
    # the report counts intervals: periods, or the gaps between consecutive motion beats
    beats_mode = r["mode"] == "beats"
    n_avail, n_used = r["periods_available"] + beats_mode, r["periods_used"] + beats_mode
    span = r["mean_motion_period_s"]
    lines = [
        f"motion   {result['motion']}: {r['input_frames']} frames at {r['input_fps']:g} fps, "
        + (
            f"{n_avail} motion beats, {span:.3f} s apart (median)"
            if beats_mode
            else f"{n_avail} periods of {span:.3f} s (mean)"
        ),
        *([f"         {result['positions']}"] if result.get("positions") else []),
        f"music    {result['audio']}: {result['music_duration_s']:.2f} s, "
        f"{result['n_music_beats']} beats ({result['beats_source']}), "
        f"beat period {r['beat_period_s']:.3f} s",
        f"mode     {r['mode']}"
        + (" (auto: not periodic, fell back to motion beats)" if r["mode_note"] else "")
        + (" (auto: periodic)" if r["mode_requested"] == "auto" and not r["mode_note"] else "")
        + f"; fill {r['fill']}, {r['repetitions']} repetition(s) of the clip",
        f"mapping  {n_used} {unit} {'landed' if beats_mode else 'placed'} ({n_avail} in the clip), "
        f"first on beat {r['first_beat']}" + _offset_text(r["phase_offset_s"]),
        f"beats    per {unit[:-1]} used: {_counts_text(r['beats_per_motion_beat_used'])} "
        f"({r['beats_per_period_rule']}){meter}"
        + (
            f"; {r['n_merged_intervals']} merged with a neighbour"
            if r["n_merged_intervals"]
            else ""
        )
        + (f"; {r['n_half_beat_landings']} on a half beat" if r["n_half_beat_landings"] else ""),
        *(
            [
                f"dance    phrases of {r['dance_beats_per_period']} motion beats "
                f"({r['dance_meter_rule']}) start on bar lines where the speed allows"
            ]
            if r.get("dance_meter_rule") and r["mode"] == "beats"
            else []
        ),
        *_seen_lines(r.get("landings_seen")),
        *_speed_lines(r),
        f"output   {r['output_frames']} frames at {r['output_fps']:g} fps "
        f"({r['output_duration_s']:.2f} s{_held_text(r)}, "
        f"the last landing at {r['target_beats_s'][-1]:.2f} s)",
        f"residual warp max {res.max():.3f} ms; nearest frame max {near.max():.2f} ms "
        f"({r['max_abs_residual_frames']:.2f} frame)",
    ]
    for k, v in result["outputs"].items():
        lines.append(f"wrote    {k}: {v}")
    return "\n".join(lines)


def _counts_text(used: dict[str, int]) -> str:
    """``{"1": 6, "2": 8}`` as ``1 x6, 2 x8``."""
    return ", ".join(f"{k} x{v}" for k, v in sorted(used.items(), key=lambda kv: float(kv[0])))


def _share(x: float) -> str:
    """A share as a percentage, never rounded up to 100 % (99.6 % is not all)."""
    return "100%" if x >= 1.0 else f"{np.floor(x * 1000) / 10:.1f}%"


def _held_text(r: dict[str, Any]) -> str:
    """The first pose held before the first landing, when it is for more than a frame."""
    held = r["playback_speed"]["held_lead_in_s"]
    return f", the first pose held for {held:.2f} s" if held * r["output_fps"] > 1.5 else ""


def _offset_text(offset: float) -> str:
    """A phase offset [s] as the text report says it: after the beat, or before it."""
    if not offset:
        return ""
    return f", {abs(offset) * 1000:.0f} ms {'after' if offset > 0 else 'before'} it"


def _seen_lines(seen: dict[str, Any] | None) -> list[str]:
    """How many landed motion beats the output shows on their beat's frame (beats mode)."""
    if not seen:
        return []
    from ..sync.quality import SEEN_REACH

    missing = f"; {seen['not_found']} not seen within {SEEN_REACH:g} s" if seen["not_found"] else ""
    return [
        f"seen     {seen['on_their_frame']} of {seen['landings']} landings show their speed "
        f"minimum on their frame; {seen['median_ms']:.0f} ms off (median), "
        f"{seen['max_ms']:.0f} ms at most{missing}"
    ]


def _speed_lines(r: dict[str, Any]) -> list[str]:
    """Playback speed, joint kinematics and the loop joins, computed from the output."""
    sp = r["playback_speed"]
    lo, hi = sp["band"]
    lines = []
    for what, key in (("instant.", "instantaneous"), ("interval", "per_interval")):
        x = sp[key]
        if x is not None:
            lines.append(
                f"speed    {what} x{x['min']:.2f} .. x{x['median']:.2f} (median) .. "
                f"x{x['max']:.2f}; {_share(x['in_band'])} of the output within x{lo:g}-x{hi:g}"
            )
    k = r.get("kinematics")
    if k is not None:
        i, o = k["input"], k["output"]
        lines.append(
            f"joints   p99 speed {o['p99_joint_speed']:.2f} (input {i['p99_joint_speed']:.2f}), "
            f"p99 acceleration {o['p99_joint_accel']:.1f} (input {i['p99_joint_accel']:.1f}), "
            f"peak speed {o['peak_joint_speed']:.2f} (input {i['peak_joint_speed']:.2f}) "
            "[position unit/s, /s^2]"
        )
    if r.get("loop"):
        lp = r["loop"]
        joins = ", ".join(
            f"{j['time_s']:.1f} s"
            + (f" (peak {j['peak_joint_speed']:.2f})" if "peak_joint_speed" in j else "")
            for j in r["joins"]
        )
        lines.append(
            f"loop     clip {lp['start_s']:.2f}-{lp['end_s']:.2f} s repeated, turned "
            f"{lp['turn_deg']:+.0f} deg per pass, blended over {lp['blend_s']:.1f} s; joins at "
            f"{joins or 'none inside the song'}"
        )
    if r.get("speed_warning"):
        lines.append(f"warning  {r['speed_warning']}")
    return lines
