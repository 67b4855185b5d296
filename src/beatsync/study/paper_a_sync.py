"""Paper A, section 5 (beat-synchronous resampling): the study behind Table 1 and Figure 3.

The notebooks call these functions, one per step; the scores themselves are
:mod:`beatsync.evaluate.alignment`'s. Inputs: :func:`load_clips` (CMU salsa BVH, MoCap
Toolbox markers, synthetic clips sized like the paper's), :func:`make_songs`,
:func:`drum_song`. Table 1: :func:`evaluate_sync` (one clip on one song),
:func:`sync_table` (every clip on every song) and its views. Figure 3:
:func:`residual_table`, :func:`figure3`, :func:`animation_video`. Real dancers
re-synchronised to other songs: :mod:`.paper_a_dancers`.

Notebooks: ``notebooks/paper_a_tab01_frame_counts.ipynb``,
``notebooks/paper_a_fig03_animation_frames.ipynb``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..evaluate.alignment import (
    DEFAULT_SIGMA,
    alignment_scores,
    beat_phase_consistency,
    nearest_distance,
    offset_control,
)
from ..motion import Motion
from ..motion_beats import kinematic_beats
from ..validation import check_positive, frames_to_time, time_to_frames
from .artifacts import write_artifacts

__all__ = [
    "crop",
    "load_clips",
    "clip_table",
    "make_songs",
    "drum_song",
    "segment_clip",
    "evaluate_sync",
    "sync_table",
    "frame_count_view",
    "alignment_view",
    "alignment_summary",
    "residual_table",
    "figure3",
    "animation_video",
    "write_artifacts",
    "FRAME_COUNT_COLUMNS",
    "ALIGNMENT_COLUMNS",
]

#: Columns of Table 1 as the notebook shows it.
FRAME_COUNT_COLUMNS = [
    "clip", "fps", "input frames", "song", "periods", "periods used", "beats/period",
    "output frames", "paper output frames", "max residual [frames]", "note",
]  # fmt: skip
#: Alignment columns (``_motion``: averaged over motion beats, Li et al. 2021;
#: ``_music``: averaged over music beats, Siyao et al. 2022).
ALIGNMENT_COLUMNS = [
    "clip", "song", "before_motion", "after_motion", "aligned_motion", "control_motion",
    "before_music", "after_music", "aligned_music", "control_music", "before_phase",
    "after_phase",
]  # fmt: skip

# score columns in the order of the published CSV
_TABLE_SCORES = [
    "before_motion", "after_motion", "control_motion", "before_music", "after_music",
    "control_music", "before_phase", "after_phase", "aligned_motion", "aligned_music",
]  # fmt: skip


# ------------------------------------------------------------------------ inputs


def crop(motion: Motion, seconds: float) -> Motion:
    """The first ``seconds`` [s] of a motion (all of it if shorter)."""
    seconds = check_positive(seconds, name="seconds", unit="s")
    n = min(motion.n_frames, int(time_to_frames(seconds, fps=motion.fps)))
    return motion.slice_frames(0, max(n, 1))


def load_clips(
    salsa_clips: list[str],
    toolbox_clips: list[str],
    synthetic_frames: list[int],
    *,
    synthetic_fps: float = 25.0,
    synthetic_period: float = 1.0,
    max_clip_seconds: float = 40.0,
    seed: int = 0,
) -> dict[str, dict[str, Any]]:
    """The motion clips of Table 1 (stand-ins for paper A's, which are not available):
    ``name -> {"motion", "segment_input" (or absent), "data"}``, as :func:`sync_table`
    takes them.

    MoCap Toolbox markers have their gaps filled and are segmented on the joint angles
    derived from them (:func:`beatsync.motion.marker_angles`); real clips are cropped
    to ``max_clip_seconds``. Synthetic 29-angle clips of ``synthetic_frames`` frames
    (the paper's sizes) have a period of about ``synthetic_period`` [s], and seeds
    counting up from ``seed``.
    """
    from .. import datasets
    from ..motion import fill_gaps, marker_angles
    from ..synth.motion import periodic_motion

    clips: dict[str, dict[str, Any]] = {}
    for take in salsa_clips:
        clips[f"salsa {take}"] = {
            "motion": crop(datasets.load_salsa(take), max_clip_seconds),
            "data": "CMU salsa BVH, 60 fps",
        }
    for var in toolbox_clips:
        m = crop(fill_gaps(datasets.load_mocap_toolbox(var)), max_clip_seconds)
        clips[f"toolbox {var}"] = {
            "motion": m,
            "segment_input": marker_angles(m),
            "data": "MoCap Toolbox markers, 60 Hz",
        }
    for i, n in enumerate(synthetic_frames):
        seconds = float(frames_to_time(n - 1, fps=synthetic_fps))
        m = periodic_motion(
            n_frames=n,
            fps=synthetic_fps,
            seed=seed + i,
            n_periods=max(2, round(seconds / synthetic_period)),
        ).motion
        clips[f"synthetic {n}"] = {"motion": m, "data": "synthetic 29 angles, 25 Hz (paper size)"}
    return clips


def clip_table(clips: dict[str, dict[str, Any]]) -> Any:
    """One row per clip: frames, frame rate, seconds and data source (a DataFrame)."""
    import pandas as pd

    return pd.DataFrame(
        [
            {
                "clip": k,
                "frames": c["motion"].n_frames,
                "fps": c["motion"].fps,
                "seconds": round(c["motion"].n_frames / c["motion"].fps, 2),
                "data": c["data"],
            }
            for k, c in clips.items()
        ]
    )


def make_songs(
    song_bpms: list[float],
    *,
    song_seconds: float = 60.0,
    use_808: bool = True,
    beat_source: str = "track",
    sr: int = 22050,
) -> tuple[dict[str, dict[str, Any]], Any]:
    """The songs of Table 1 (stand-ins for paper A's): ``(songs, table)``.

    Song A is a synthetic drum pattern at ``song_bpms[0]``, song B a click track at
    ``song_bpms[1]`` (beats from 0.4 s), song C the real 808 kick loop (BeatNet test
    data, 120 BPM, 10 s) if ``use_808``. Beats are tracked by
    :func:`beatsync.beats.track_beats` or, with ``beat_source="truth"``, the synthetic
    songs' ground truth. ``songs``: ``name -> {"beats", "bpm", "data"}``, as
    :func:`sync_table` takes them; ``table``: one row per song, with the tracked tempo
    and the largest distance of a tracked beat from the true ones [ms].
    """
    import pandas as pd

    from .. import datasets
    from ..beats import track_beats
    from ..synth.audio import beat_times, click_track, drum_pattern

    if beat_source not in ("track", "truth"):
        raise ParameterError(f"beat_source={beat_source!r} must be 'track' or 'truth'")
    if len(song_bpms) < 2:
        raise ParameterError(f"song_bpms={song_bpms!r} needs two tempi [BPM] (songs A and B)")
    truth = {bpm: beat_times(bpm, duration=song_seconds, start=0.4) for bpm in song_bpms[:2]}
    a, b = song_bpms[0], song_bpms[1]
    audio = {
        name: (synth(truth[bpm], sr=sr, duration=song_seconds), sr, truth[bpm], bpm, data)
        for name, synth, bpm, data in (
            (f"A: drums {a:g} BPM", drum_pattern, a, "synthetic drum pattern"),
            (f"B: clicks {b:g} BPM", click_track, b, "synthetic click track"),
        )
    }
    if use_808:
        y, rate = datasets.load_click_808()
        audio["C: 808 loop 120 BPM"] = (y, rate, None, 120.0, "real 808 kick loop (BeatNet), 10 s")
    songs, rows = {}, []
    for name, (y, rate, true, bpm, data) in audio.items():
        track = track_beats(y, rate)
        beats = track.beats if (beat_source == "track" or true is None) else true
        songs[name] = {"beats": beats, "bpm": bpm, "data": data}
        rows.append(
            {
                "song": name,
                "data": data,
                "BPM": bpm,
                "beats used": len(beats),
                "tracked tempo [BPM]": round(float(track.tempo), 2),
                "max |tracked - true| [ms]": _max_error_ms(track.beats, true),
            }
        )
    return songs, pd.DataFrame(rows)


def _max_error_ms(tracked: np.ndarray, true: np.ndarray | None) -> float | str:
    """The largest distance of a tracked beat from the true beats [ms], "n/a" without."""
    return "n/a" if true is None else round(1000 * float(nearest_distance(tracked, true).max()), 1)


def drum_song(
    bpm: float, *, song_seconds: float = 8.0, sr: int = 22050, start: float = 0.3
) -> tuple[np.ndarray, int, np.ndarray, dict[str, Any]]:
    """Figure 3's song, a synthetic drum pattern: ``(y, sr, beats, summary)``, the beats
    [s] tracked by :func:`beatsync.beats.track_beats` and summarised against the truth."""
    from ..beats import track_beats
    from ..synth.audio import beat_times, drum_pattern

    true = beat_times(bpm, duration=song_seconds, start=start)
    y = drum_pattern(true, sr=sr, duration=song_seconds)
    track = track_beats(y, sr)
    summary = {
        "beats": len(track.beats),
        "tempo [BPM]": round(float(track.tempo), 2),
        "max |tracked - true| [ms]": _max_error_ms(track.beats, true),
    }
    return y, sr, track.beats, summary


def segment_clip(
    motion: Motion, *, period_range: tuple[float, float] = (0.25, 1.25)
) -> tuple[Any, dict[str, Any]]:
    """Segment a clip into its periods (paper A, section 3): ``(segmentation, summary)``.

    ``summary``: frames, fps, periods, mean period [s] (rounded to ms).
    """
    from ..motion import segmentation_view
    from ..segment import segment

    seg = segment(segmentation_view(motion), period_range=period_range)
    summary = {
        "frames": motion.n_frames,
        "fps": motion.fps,
        "periods": seg.n_periods,
        "mean period [s]": round(float(seg.mean_period), 3),
    }
    return seg, summary


# ------------------------------------------------------------------------ Table 1


def evaluate_sync(
    motion: Motion,
    beats: Any,
    *,
    boundaries: Any,
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
) -> dict[str, Any]:
    """Synchronise a motion's periods (``boundaries`` [s]) to music ``beats`` [s] and
    score it: one row of Table 1.

    The kinematic beats are scored against the music beats with both published
    alignment scores (Gaussian width ``sigma`` [s]) and the phase consistency *before*
    (the clip played from music time 0) and *after* :func:`beatsync.sync.synchronize`;
    ``control_*`` is the random-offset control of the synchronised motion (``n_control``
    trials, :func:`beatsync.evaluate.alignment.offset_control`), ``aligned_*`` the motion
    synchronised with ``land="accents"``, so that the dancer's accents, not the
    boundaries, land on the beats. Motions without positions (joint-angle tables) score
    NaN. The row also holds the report's frame counts and residuals, and ``result``
    (the :class:`~beatsync.sync.SyncResult`).
    """
    from ..sync import synchronize
    from ..validation import check_times

    yb = check_times(beats, name="beats")
    res = synchronize(motion, boundaries, yb)
    rep = res.report
    row: dict[str, Any] = {
        "input_frames": rep["input_frames"],
        "input_fps": rep["input_fps"],
        "output_frames": rep["output_frames"],
        "periods_available": rep["periods_available"],
        "periods_used": rep["periods_used"],
        "beats_per_period": rep["beats_per_period"],
        "mean_period_s": rep["mean_motion_period_s"],
        "beat_period_s": rep["beat_period_s"],
        "speed_min": rep["tempo_ratio_range"][0],
        "speed_max": rep["tempo_ratio_range"][1],
        "max_residual_ms": rep["max_abs_residual_ms"],
        "max_residual_frames": rep["max_abs_residual_frames"],
    }
    try:
        mb_before, mb_after = kinematic_beats(motion), kinematic_beats(res.motion)
    except ParameterError:  # no positions: a plain joint-angle table
        nan_scores = dict.fromkeys([*_TABLE_SCORES, "phase_offset_s"], float("nan"))
        return {**row, **nan_scores, "result": res}

    def scores(motion_beats: np.ndarray, m: Motion) -> dict[str, float]:
        span = (0.0, min(float(m.duration), yb[-1]))  # the music beats within the motion
        return alignment_scores(motion_beats, yb, sigma=sigma, span=span)

    before, after = scores(mb_before, motion), scores(mb_after, res.motion)
    ctrl = offset_control(
        mb_after, yb[yb <= float(res.motion.duration)], sigma=sigma, n_trials=n_control, seed=seed
    )
    res_al = synchronize(motion, boundaries, yb, land="accents")
    aligned = scores(kinematic_beats(res_al.motion), res_al.motion)
    return {
        **row,
        "before_motion": before["alignment_motion"],
        "before_music": before["alignment_music"],
        "before_phase": beat_phase_consistency(mb_before, yb),
        "after_motion": after["alignment_motion"],
        "after_music": after["alignment_music"],
        "after_phase": beat_phase_consistency(mb_after, yb),
        "control_motion": ctrl["alignment_motion_mean"],
        "control_music": ctrl["alignment_music_mean"],
        "phase_offset_s": res_al.report["phase_offset_s"],
        "aligned_motion": aligned["alignment_motion"],
        "aligned_music": aligned["alignment_music"],
        "result": res,
    }


def sync_table(
    clips: dict[str, dict[str, Any]],
    songs: dict[str, dict[str, Any]],
    *,
    period_range: tuple[float, float] = (0.25, 1.25),
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
    paper_frames: dict[tuple[str, str], Any] | None = None,
) -> Any:
    """Synchronise every clip to every song (:func:`evaluate_sync`); one row per pair
    (paper A, Table 1).

    ``clips`` as :func:`load_clips` gives them (each segmented once, its
    ``segment_input`` if any, within ``period_range`` [s]), ``songs`` as
    :func:`make_songs`. ``paper_frames``: ``(clip, song) ->`` the paper's number of output
    frames; missing pairs show ``"n/a"``, never an invented number. A clip that has no
    result (e.g. segmentation refused it as not periodic) says why in ``note``.
    """
    import pandas as pd

    from ..segment import segment

    paper_frames = paper_frames or {}
    rows = []
    for cname, clip in clips.items():
        motion = clip["motion"]
        try:
            seg = segment(clip.get("segment_input") or motion, period_range=period_range)
        except ParameterError as exc:  # e.g. refused as not periodic: say so in the table
            seg, note = None, f"segmentation refused: {str(exc)[:60]}..."
        for sname, song in songs.items():
            row = {
                "clip": cname,
                "clip data": clip.get("data", ""),
                "fps": float(motion.fps),
                "input frames": int(motion.n_frames),
                "song": sname,
                "song data": song.get("data", ""),
                "BPM": song.get("bpm", float("nan")),
            }
            paper = paper_frames.get((cname, sname), "n/a")
            if seg is None:
                rows.append({**row, "paper output frames": paper, "note": note})
                continue
            r = evaluate_sync(
                motion,
                song["beats"],
                boundaries=seg.boundaries,
                sigma=sigma,
                n_control=n_control,
                seed=seed,
            )
            rows.append(
                {
                    **row,
                    "periods": int(seg.n_periods),
                    "periods used": r["periods_used"],
                    "beats/period": r["beats_per_period"],
                    "output frames": r["output_frames"],
                    "paper output frames": paper,
                    "max residual [frames]": r["max_residual_frames"],
                    **{k: r[k] for k in _TABLE_SCORES[:8]},
                    "phase offset [s]": r["phase_offset_s"],
                    **{k: r[k] for k in _TABLE_SCORES[8:]},
                    "note": "",
                }
            )
    return pd.DataFrame(rows)


def frame_count_view(table: Any) -> Any:
    """Table 1 as shown: frame counts and residuals, rounded to 3 decimals."""
    return table[FRAME_COUNT_COLUMNS].round(3)


def alignment_view(table: Any) -> Any:
    """The alignment columns and the measured phase offset of the clips with positions."""
    return table[ALIGNMENT_COLUMNS + ["phase offset [s]"]].dropna().round(3)


def alignment_summary(table: Any) -> Any:
    """Mean alignment per song over the clips with joint positions."""
    return table[ALIGNMENT_COLUMNS].dropna().drop(columns=["clip"]).groupby("song").mean().round(3)


# ------------------------------------------------------------------------ Figure 3


def residual_table(result: Any, decimals: int | None = None) -> tuple[dict[str, Any], Any]:
    """A :class:`~beatsync.sync.SyncResult`'s frame counts, and a table of every boundary,
    its beat and residuals, rounded to ``decimals`` if given (-0 shown as 0)."""
    import pandas as pd

    rep = result.report
    counts = {
        k: rep[k] for k in ("input_frames", "output_frames", "periods_used", "beats_per_period")
    }
    table = pd.DataFrame(
        {
            "boundary [s]": rep["boundaries_s"],
            "beat [s]": rep["target_beats_s"],
            "residual warp [ms]": rep["residual_ms"],
            "residual nearest frame [ms]": rep["residual_nearest_frame_ms"],
        }
    )
    if decimals is not None:
        table = table.round(decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
    return counts, table


def figure3(
    result: Any,
    beats: Any,
    *,
    strip_start: float = 2.0,
    strip_beats: int = 4,
    poses_per_beat: int = 3,
    azimuth: float = 90.0,
    xlim: float | None = None,
) -> Any:
    """Figure 3: poses of the synchronised animation over ``strip_beats`` beats from
    ``strip_start`` [s] (poses on a beat in red), and below them the mean joint speed
    with the music beats, the warped boundaries and the kinematic beats up to ``xlim`` [s].
    """
    import matplotlib.pyplot as plt

    from .. import render

    motion = result.motion
    strip = render.beat_strip_times(
        beats, start=strip_start, n_beats=strip_beats, per_beat=poses_per_beat
    )
    fig, axes = plt.subplots(2, 1, figsize=(11, 5.5), gridspec_kw={"height_ratios": [2.2, 1]})
    render.plot_frames(
        motion, strip, beats=beats, ax=axes[0], azimuth=azimuth, tol=0.5 / motion.fps + 1e-6
    )
    render.plot_beat_timeline(
        motion,
        beats=beats,
        boundaries=result.report["target_beats_s"],
        motion_beats=kinematic_beats(motion),
        ax=axes[1],
    )
    if xlim is not None:
        axes[1].set_xlim(0, xlim)
    fig.tight_layout()
    return fig


def animation_video(
    result: Any,
    audio: tuple[np.ndarray, int],
    beats: Any,
    path: str | Path,
    *,
    seconds: float,
    fps: float = 15.0,
    size: tuple[int, int] = (320, 240),
    azimuth: float = 90.0,
    title: str | None = None,
) -> Path:
    """The first ``seconds`` of the synchronised dance as a video with the song, in a
    folder created if missing (:func:`beatsync.render.write_video`); the file written."""

    from .. import render

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return render.write_video(
        crop(result.motion, seconds),
        path,
        audio=audio,
        fps=fps,
        beats=beats,
        size=size,
        azimuth=azimuth,
        title=title,
        preset="veryfast",  # a small file, to commit and to embed in a notebook
    )
