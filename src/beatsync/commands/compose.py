"""``beatsync compose``: compose a dance for a song from a motion library (paper B).

Built motion graphs are cached (:mod:`beatsync.graph.cache`) in ``$BEATSYNC_CACHE_DIR``,
else ``~/.cache/beatsync``; ``--no-cache`` neither reads nor writes it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from . import COMMAND_HELP
from ._common import (
    Outputs,
    add_music_beat_options,
    add_output_flags,
    beats_end_early,
    emit,
    feedback,
    tempo_options,
)

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "compose",
        help=COMMAND_HELP["compose"],
        description=(
            "Compose a dance for a song from a library of BVH clips (paper B): the clips' "
            "beat frames form a weighted motion graph (cached on disk), a dynamic programme "
            "picks the path whose motion intensity follows the music's, and every motion "
            "beat is time-warped onto a music beat. Writes BVH (the library's skeleton). "
            "The graph is cached in $BEATSYNC_CACHE_DIR (default ~/.cache/beatsync), keyed "
            "by the clips, the graph parameters and the graph code; --no-cache bypasses it. "
            "Example: beatsync compose song.wav --library a.bvh b.bvh -o dance.bvh"
        ),
    )
    p.add_argument(
        "audio",
        nargs="?",
        help="music file (.wav, .flac, .ogg, .mp3); may also follow --library",
    )
    p.add_argument(
        "--library",
        nargs="+",
        action="extend",
        required=True,
        metavar="PATH",
        help="BVH clips or folders of BVH clips (one skeleton)",
    )
    p.add_argument("-o", "--output", required=True, help="output motion (.bvh)")
    p.add_argument(
        "--fps",
        type=float,
        help="frame rate of the library clips [Hz]: overrides the BVH headers",
    )
    p.add_argument(
        "--th",
        type=float,
        default=3.0,
        help="transition threshold TH on the scale-free pose distance rd (default 3.0)",
    )
    p.add_argument(
        "--weight-rule",
        choices=("paper", "rd"),
        default="paper",
        help="transition weight: 'paper' w2 = max(rd, 2) (eq. 2), or 'rd'",
    )
    p.add_argument(
        "--method",
        choices=("dp", "conventional", "random"),
        default="dp",
        help="search: dp (paper B), conventional (multi-stage baseline), random walk",
    )
    add_music_beat_options(p)
    p.add_argument(
        "--tempo-weight",
        type=float,
        default=0.0,
        help="weight of a tempo term against strong time warps (0 = paper B, intensity only)",
    )
    p.add_argument(
        "--scale-bound",
        type=float,
        nargs=2,
        default=[0.8, 1.25],
        metavar=("LO", "HI"),
        help="bound on every interval's time-scale factor, music duration / natural "
        "duration (default 0.8 1.25: at most 25%% faster or slower than captured)",
    )
    p.add_argument(
        "--no-scale-bound",
        action="store_true",
        help="no bound: any interval may be warped onto any beat (paper B as written)",
    )
    p.add_argument(
        "--multiplicity",
        default="auto",
        metavar="M[,M...]",
        help="music beats one motion-beat interval may cover, e.g. 1,2 or 0.5,1 "
        "(default auto: chosen from the library's and the song's tempo)",
    )
    p.add_argument(
        "--all-clips",
        action="store_true",
        help="use every clip, not only the tempo group that suits the song",
    )
    p.add_argument(
        "--blend", type=float, default=1.0 / 3.0, help="transition blend length [s] (default 1/3)"
    )
    p.add_argument(
        "--video",
        metavar="OUT.mp4",
        help="also write a stick-figure video with the music as soundtrack",
    )
    p.add_argument("--report", metavar="FILE.json", help="write the report as JSON")
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="neither read nor write the graph cache (folder: $BEATSYNC_CACHE_DIR, "
        "default ~/.cache/beatsync)",
    )
    add_output_flags(p)
    p.set_defaults(func=run)


def _library_files(entries: list[str]) -> list[Path]:
    files: list[Path] = []
    for e in entries:
        p = Path(e)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.suffix.lower() == ".bvh")
            if not found:
                raise ParameterError(f"library folder {e!r} contains no .bvh clip")
            files.extend(found)
        elif p.is_file():
            if p.suffix.lower() != ".bvh":
                raise ParameterError(
                    f"library clip {e!r} is not a .bvh file (the graph needs skeletal clips)"
                )
            files.append(p)
        else:
            raise ParameterError(f"library clip {e!r} does not exist")
    if not files:
        raise ParameterError("the motion library is empty: give at least one BVH clip")
    return files


def _check_inputs(
    args: argparse.Namespace,
) -> tuple[str, list[Path], float, Outputs, tuple[Path, Path | None, Path | None]]:
    """The audio, the library's files, ``--th``, and the outputs with their paths
    (motion, video, report), all checked before any work."""
    from ..graph.build import check_th
    from ..io import AUDIO_SUFFIXES, check_input_file

    entries = list(args.library or [])
    audio = args.audio
    if audio is None:
        # argparse lets --library swallow the audio file that follows it
        moved = [e for e in entries if Path(e).suffix.lower() in AUDIO_SUFFIXES]
        if len(moved) == 1:
            audio = moved[0]
            entries.remove(audio)
        else:
            raise ParameterError("give the music file (AUDIO), e.g. beatsync compose song.wav ...")
    th = check_th(args.th, name="--th")
    tempo_options(args)  # a bad tempo or range, or --beats with --bpm: before any work
    check_input_file(audio, "audio")
    if args.beats is not None:
        check_input_file(args.beats, "beats")
    files = _library_files(entries)
    if Path(args.output).suffix.lower() != ".bvh":
        raise ParameterError(f"output {args.output!r} must end in .bvh")
    outs = Outputs(inputs=(audio, args.beats, *files))
    out = outs.add(args.output, option="-o/--output")
    video = outs.add(args.video, option="--video", suffixes=[".mp4"]) if args.video else None
    report = outs.add(args.report, option="--report", suffixes=[".json"]) if args.report else None
    return audio, files, th, outs, (out, video, report)


def run(args: argparse.Namespace) -> int:
    from .. import io
    from ..graph.compose import check_music_beats, compose_music

    if not (np.isfinite(args.tempo_weight) and args.tempo_weight >= 0):
        raise ParameterError(f"--tempo-weight {args.tempo_weight!r} must be >= 0")
    if not (np.isfinite(args.blend) and 0 <= args.blend <= 5):
        raise ParameterError(f"--blend {args.blend!r} must be a duration in [0, 5] s")
    # files after the options: cheapest first
    audio, files, th, outs, (out, video_path, report) = _check_inputs(args)
    fb = feedback(args)
    from ..graph.timescale import check_multiplicity, check_scale_bound

    bound = (
        None if args.no_scale_bound else check_scale_bound(args.scale_bound, name="--scale-bound")
    )
    mult = args.multiplicity
    mult = check_multiplicity(mult if mult == "auto" else mult.split(","))
    t_read = time.perf_counter()
    with fb.noted() as read_notes:  # e.g. the MP3 decoder's
        y, sr = io.read_audio(audio)
    beats, beat_notes = None, []
    if args.beats is not None:  # cheap checks first: the beats file before the clips
        try:
            beats = check_music_beats(io.read_beats(args.beats), duration=y.size / float(sr))
        except ParameterError as exc:
            raise ParameterError(f"beats file {args.beats!r}: {exc}") from None
        then = "the dance holds its last pose from there"
        early = beats_end_early(beats, y.size / float(sr), args.beats, then)
        if early:
            beat_notes.append(early)
            fb.warn(early)
    with fb.step("reading the library", total=len(files)) as progress:
        clips = []
        for f in files:
            clips.append(io.read_bvh(f, fps=args.fps))
            progress(len(clips))
    read_s = time.perf_counter() - t_read
    from ..graph import check_library
    from ..graph.cache import load_or_build
    from ..music import track_music_beats

    check_library(clips)
    notes: list[str] = [*read_notes, *beat_notes]
    if beats is None:
        with fb.noted() as tracked, fb.step("tracking beats"):
            beats = track_music_beats(y, sr, **tempo_options(args))
        notes += tracked
    params = {"th": th, "weight_rule": args.weight_rule, "fps": args.fps}
    t0 = time.perf_counter()
    with fb.step("building the motion graph"):
        graph, cached, cache_path = load_or_build(files, clips, params, use_cache=not args.no_cache)
    build_s = time.perf_counter() - t0
    kw = {"tempo_weight": args.tempo_weight} if args.method == "dp" and args.tempo_weight else {}
    with fb.noted() as composed, fb.step("composing"):
        comp = compose_music(
            graph,
            y,
            sr,
            beats=beats,
            method=args.method,
            blend=args.blend,
            scale_bound=bound,
            multiplicity=mult,
            tempo_select=not args.all_clips,
            **kw,
        )
    notes += composed
    result = {
        "output": str(out),
        "video": str(video_path) if video_path else None,
        "library": [str(f) for f in files],
        "method": args.method,
        "n_transitions": comp.n_transitions,
        "n_music_beats": int(comp.music_beats.size),
        "path": comp.search.path,
        "tempo_bpm": float(60.0 / np.median(np.diff(comp.music_beats))),
        "graph": graph.summary(),
        "graph_cached": cached,
        "graph_cache_file": str(cache_path) if cache_path else None,
        "graph_build_time_s": build_s,
        "search_time_s": comp.search.search_time,
        "synthesis_time_s": comp.timings["synthesis_s"],
        "read_time_s": read_s,
        "cost": comp.search.cost,
        "duration_s": (comp.motion.n_frames - 1) / comp.motion.fps,  # the last frame
        "n_frames": comp.motion.n_frames,
        "fps": comp.motion.fps,
        "transition_times_s": comp.synthesis.transition_times,
        "tempo": comp.tempo.report(),
        "multiplicity_used": comp.multiplicity_used(),
        "plausibility": comp.plausibility,
        "warnings": notes,
    }
    with outs:  # the dance, video and report are all written, or none of them
        io.write_bvh(outs.path(out), comp.motion)
        if video_path is not None:
            video_path = outs.write_video(
                video_path, comp.motion, audio=(y, sr), beats=comp.music_beats, progress=fb.bars
            )
            result["video"] = str(video_path)
        if report is not None:
            io.write_json(outs.path(report), result)
    g = graph.summary()
    text = (
        f"wrote {out} ({comp.motion.n_frames} frames at {comp.motion.fps:g} fps, "
        f"{result['duration_s']:.2f} s)\n"
        f"library: {g['n_clips']} clip(s), {g['n_nodes']} beat frames, "
        f"{g['n_transitions']} transition edges at TH={g['th']:g}"
        f"{' (graph from cache)' if cached else ''}\n"
        f"music: {comp.music_beats.size} beats (~{result['tempo_bpm']:.1f} BPM)\n"
        f"path: {comp.search.path.size} intervals, {comp.n_transitions} transition(s); "
        f"graph build {build_s:.3f} s, search ({args.method}) {comp.search.search_time:.4f} s\n"
        + _tempo_text(comp)
    )
    if video_path:
        text += f"\nvideo: {video_path}"
    if report is not None:
        text += f"\nreport: {report}"
    return emit(result, text, args)


def _tempo_text(comp: Any) -> str:
    """Eligible clips, multiplicities and plausibility, for the terminal."""
    plan = comp.tempo
    p = comp.plausibility
    bound = "none" if plan.bound is None else f"{plan.bound[0]:g}-{plan.bound[1]:g}"
    used = ", ".join(f"{k} beat(s) x{v}" for k, v in comp.multiplicity_used().items())
    lines = [
        f"tempo: song {plan.song_bpm:.0f} BPM, library {plan.library_bpm:.0f} BPM; "
        f"time-scale bound {bound}; intervals covering {used}"
    ]
    for row in plan.clip_table:
        mark = "used" if row["eligible"] else "not used"
        lines.append(f"  {row['clip']}: {mark}: {row['reason']}")
    lines.append(
        f"speed: root p99 {p['root_speed_p99']:.3g} ({p['root_speed_ratio']:.2f}x the fastest "
        f"clip), joint rotation p99 {p['rotation_speed_p99']:.0f} deg/s "
        f"({p['rotation_speed_ratio']:.2f}x); time-scale {p['scale_min']:.2f}-{p['scale_max']:.2f}"
    )
    return "\n".join(lines)
