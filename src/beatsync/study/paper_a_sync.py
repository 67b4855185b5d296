"""Paper A, section 5 (beat-synchronous resampling): the study behind Table 1 and Figure 3.

The notebooks call these functions, one per step; everything that runs the pipeline
(segmentation, beat tracking, :func:`beatsync.sync.synchronize`, kinematic beats)
for the paper's tables lives here, the scores themselves in
:mod:`beatsync.evaluate.alignment` (metrics on arrays).

- Inputs: :func:`crop`, :func:`load_clips` (CMU salsa BVH, MoCap Toolbox markers,
  synthetic clips sized like the paper's), :func:`clip_table`, :func:`make_songs`
  (two synthetic songs of different tempo and the real 808 loop, beats tracked),
  :func:`drum_song`, :func:`segment_clip`.
- Table 1: :func:`evaluate_sync` (one clip on one song: frames, residuals, both
  alignment scores before/after synchronisation, the random-offset control, and the
  dancer's accents put on the beat), :func:`sync_table` (every clip on every song),
  :func:`frame_count_view`, :func:`alignment_view`, :func:`alignment_summary`.
- Figure 3: :func:`residual_table`, :func:`figure3`, :func:`animation_video`.
- Real dancers re-synchronised to other songs: :mod:`.paper_a_dancers`.
- Artefacts: :func:`beatsync.study.artifacts.write_artifacts`.

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
    """The first ``seconds`` of a motion (all of it if shorter).

    Parameters
    ----------
    motion : Motion
    seconds : float > 0 [s]

    Returns
    -------
    Motion
        ``min(n_frames, round(seconds * fps))`` frames.
    """
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
    """The motion clips of Table 1 (stand-ins for paper A's, which are not available).

    Parameters
    ----------
    salsa_clips : list of str
        CMU salsa takes (60 fps BVH), e.g. ``["60_01", "61_01"]``.
    toolbox_clips : list of str
        MoCap Toolbox demo dances (60 Hz markers): gaps filled, segmented on joint
        angles derived from the markers (:func:`beatsync.motion.marker_angles`).
    synthetic_frames : list of int
        Lengths [frames] of synthetic 29-angle clips (the paper's clip sizes).
    synthetic_fps : float [Hz]
    synthetic_period : float [s]
        Nominal period of the synthetic clips (about one per this many seconds).
    max_clip_seconds : float [s]
        Real clips are cropped to this length.
    seed : int
        Seed of the first synthetic clip (the next ones count up).

    Returns
    -------
    dict
        ``name -> {"motion", "segment_input" (or absent), "data"}``, as
        :func:`sync_table` takes it.
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
    """The songs of Table 1 and their beats (stand-ins for paper A's songs).

    Song A is a synthetic drum pattern at ``song_bpms[0]``, song B a click track at
    ``song_bpms[1]`` (beats from 0.4 s), song C the real 808 kick loop (BeatNet test
    data, 120 BPM, 10 s) if ``use_808``. Beats are tracked by
    :func:`beatsync.beats.track_beats` (paper A, section 4) or, with
    ``beat_source="truth"``, taken from the synthetic songs' ground truth.

    Returns
    -------
    songs : dict
        ``name -> {"beats", "bpm", "data"}``, as :func:`sync_table` takes it.
    table : pandas.DataFrame
        Per song: data, BPM, beats used, tracked tempo, largest distance of a tracked
        beat from the true beats [ms] (``"n/a"`` without ground truth).

    Raises
    ------
    ParameterError
        Fewer than two tempi, or an unknown ``beat_source``.
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
        f"A: drums {a:g} BPM": (
            drum_pattern(truth[a], sr=sr, duration=song_seconds),
            sr,
            truth[a],
            a,
            "synthetic drum pattern",
        ),
        f"B: clicks {b:g} BPM": (
            click_track(truth[b], sr=sr, duration=song_seconds),
            sr,
            truth[b],
            b,
            "synthetic click track",
        ),
    }
    if use_808:
        y, rate = datasets.load_click_808()
        audio["C: 808 loop 120 BPM"] = (y, rate, None, 120.0, "real 808 kick loop (BeatNet), 10 s")
    songs, rows = {}, []
    for name, (y, rate, true, bpm, data) in audio.items():
        track = track_beats(y, rate)
        beats = track.beats if (beat_source == "track" or true is None) else true
        songs[name] = {"beats": beats, "bpm": bpm, "data": data}
        err = (
            round(1000 * float(nearest_distance(track.beats, true).max()), 1)
            if true is not None
            else "n/a"
        )
        rows.append(
            {
                "song": name,
                "data": data,
                "BPM": bpm,
                "beats used": len(beats),
                "tracked tempo [BPM]": round(float(track.tempo), 2),
                "max |tracked - true| [ms]": err,
            }
        )
    return songs, pd.DataFrame(rows)


def drum_song(
    bpm: float, *, song_seconds: float = 8.0, sr: int = 22050, start: float = 0.3
) -> tuple[np.ndarray, int, np.ndarray, dict[str, Any]]:
    """A synthetic drum pattern and its tracked beats (Figure 3's song).

    Returns
    -------
    y : np.ndarray [shape=(n,)]
    sr : int [Hz]
    beats : np.ndarray [s]
        Tracked by :func:`beatsync.beats.track_beats`.
    summary : dict
        ``beats``, ``tempo [BPM]`` (tracked), ``max |tracked - true| [ms]``.
    """
    from ..beats import track_beats
    from ..synth.audio import beat_times, drum_pattern

    true = beat_times(bpm, duration=song_seconds, start=start)
    y = drum_pattern(true, sr=sr, duration=song_seconds)
    track = track_beats(y, sr)
    summary = {
        "beats": len(track.beats),
        "tempo [BPM]": round(float(track.tempo), 2),
        "max |tracked - true| [ms]": round(
            1000 * float(nearest_distance(track.beats, true).max()), 1
        ),
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
    boundaries: Any = None,
    segment_input: Motion | None = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    sigma: float = DEFAULT_SIGMA,
    n_control: int = 100,
    seed: int = 0,
    **sync_kwargs: Any,
) -> dict[str, Any]:
    """Synchronise a motion to music beats and score it: one row of Table 1.

    Runs :func:`beatsync.segment.segment` (unless ``boundaries`` are given) and
    :func:`beatsync.sync.synchronize`, then scores the kinematic beats against the
    music beats with both published alignment scores and the phase consistency
    *before* (the original clip played from music time 0) and *after*
    synchronisation, the random-offset control of the synchronised motion
    (:func:`beatsync.evaluate.alignment.offset_control`), and ``aligned_*``: the
    motion synchronised with ``land="accents"`` so that the dancer's accents, not
    the segmentation's boundaries, land on the beats. Motions without positions
    (plain joint-angle tables) get NaN alignment scores.

    Parameters
    ----------
    motion : Motion
    beats : np.ndarray [s]
        Music beats.
    boundaries : np.ndarray [s], optional
        Period boundaries; default from ``segment(segment_input or motion)``.
    segment_input : Motion, optional
        What to segment if different from ``motion`` (e.g. ``marker_angles(markers)``).
    period_range : (float, float) [s]
        Passed to ``segment``.
    sigma : float > 0 [s]
        Gaussian width of the alignment scores.
    n_control, seed : int
        Random-offset control trials and seed.
    **sync_kwargs
        Passed to :func:`~beatsync.sync.synchronize` (``beats_per_period``, ``out_fps``...).

    Returns
    -------
    dict
        ``input_frames``, ``input_fps``, ``output_frames``, ``periods_available``,
        ``periods_used``, ``beats_per_period``, ``mean_period_s``, ``beat_period_s``,
        ``speed_min``, ``speed_max``, ``max_residual_ms``, ``max_residual_frames``;
        ``before_/after_/aligned_/control_`` + ``motion``/``music`` scores,
        ``before_/after_phase``, ``phase_offset_s``; and ``result`` (the
        :class:`~beatsync.sync.SyncResult`).
    """
    from ..sync import synchronize
    from ..validation import check_times

    yb = check_times(beats, name="beats")
    n_periods = None
    if boundaries is None:
        from ..segment import segment

        seg = segment(motion if segment_input is None else segment_input, period_range=period_range)
        boundaries = seg.boundaries
        n_periods = int(seg.n_periods)
    res = synchronize(motion, boundaries, yb, **sync_kwargs)
    rep = res.report
    row: dict[str, Any] = {
        "input_frames": rep["input_frames"],
        "input_fps": rep["input_fps"],
        "output_frames": rep["output_frames"],
        "periods_available": rep["periods_available"] if n_periods is None else n_periods,
        "periods_used": rep["periods_used"],
        "beats_per_period": rep["beats_per_period"],
        "mean_period_s": rep["mean_motion_period_s"],
        "beat_period_s": rep["beat_period_s"],
        "speed_min": rep["tempo_ratio_range"][0],
        "speed_max": rep["tempo_ratio_range"][1],
        "max_residual_ms": rep["max_abs_residual_ms"],
        "max_residual_frames": rep["max_abs_residual_frames"],
    }
    keys = (
        "before_motion",
        "before_music",
        "before_phase",
        "after_motion",
        "after_music",
        "after_phase",
        "control_motion",
        "control_music",
        "phase_offset_s",
        "aligned_motion",
        "aligned_music",
    )
    try:
        mb_before = kinematic_beats(motion)
        mb_after = kinematic_beats(res.motion)
    except ParameterError:  # no positions: a plain joint-angle table
        row.update({k: float("nan") for k in keys})
        row["result"] = res
        return row
    before = alignment_scores(
        mb_before, yb, sigma=sigma, span=(0.0, min(float(motion.duration), yb[-1]))
    )
    after = alignment_scores(
        mb_after, yb, sigma=sigma, span=(0.0, min(float(res.motion.duration), yb[-1]))
    )
    ctrl = offset_control(
        mb_after, yb[yb <= float(res.motion.duration)], sigma=sigma, n_trials=n_control, seed=seed
    )
    res_al = synchronize(motion, boundaries, yb, land="accents", **sync_kwargs)
    aligned = alignment_scores(
        kinematic_beats(res_al.motion),
        yb,
        sigma=sigma,
        span=(0.0, min(float(res_al.motion.duration), yb[-1])),
    )
    row.update(
        {
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
        }
    )
    row["result"] = res
    return row


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
    """Synchronise every clip to every song; one row per pair (paper A, Table 1).

    Parameters
    ----------
    clips : dict
        ``name -> {"motion": Motion, "segment_input": Motion or None, "data": str}``
        (:func:`load_clips`); each clip is segmented once.
    songs : dict
        ``name -> {"beats": np.ndarray [s], "bpm": float, "data": str}`` (:func:`make_songs`).
    period_range : (float, float) [s]
    sigma : float [s]
    n_control, seed : int
        Random-offset control (see :func:`beatsync.evaluate.alignment.offset_control`).
    paper_frames : dict, optional
        ``(clip, song) -> the paper's number of output frames``; missing pairs are
        reported as ``"n/a"`` (not available), never invented.

    Returns
    -------
    pandas.DataFrame
        Columns: clip, clip data, fps, input frames, song, song data, BPM, periods,
        periods used, beats/period, output frames, paper output frames, max residual
        [frames], alignment before/after/control/aligned (``_motion`` and ``_music``),
        phase consistency before/after, phase offset [s], and ``note`` (why a clip has
        no result, e.g. segmentation refused it as not periodic).
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
            for sname, song in songs.items():
                rows.append(
                    {
                        "clip": cname,
                        "clip data": clip.get("data", ""),
                        "fps": float(motion.fps),
                        "input frames": int(motion.n_frames),
                        "song": sname,
                        "song data": song.get("data", ""),
                        "BPM": song.get("bpm", float("nan")),
                        "paper output frames": paper_frames.get((cname, sname), "n/a"),
                        "note": f"segmentation refused: {str(exc)[:60]}...",
                    }
                )
            continue
        for sname, song in songs.items():
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
                    "clip": cname,
                    "clip data": clip.get("data", ""),
                    "fps": r["input_fps"],
                    "input frames": r["input_frames"],
                    "song": sname,
                    "song data": song.get("data", ""),
                    "BPM": song.get("bpm", float("nan")),
                    "periods": int(seg.n_periods),
                    "periods used": r["periods_used"],
                    "beats/period": r["beats_per_period"],
                    "output frames": r["output_frames"],
                    "paper output frames": paper_frames.get((cname, sname), "n/a"),
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
    """Every boundary of a :class:`~beatsync.sync.SyncResult`, its beat and residuals.

    Parameters
    ----------
    decimals : int, optional
        Round the table for display (a value that rounds to zero shows as 0, not -0).

    Returns
    -------
    counts : dict
        ``input_frames``, ``output_frames``, ``periods_used``, ``beats_per_period``.
    table : pandas.DataFrame
        boundary [s], beat [s], residual warp [ms], residual nearest frame [ms].
    """
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
    """Figure 3: poses of the synchronised animation over a few beats, and a timeline.

    Top: skeleton poses over ``strip_beats`` beats from ``strip_start`` [s],
    ``poses_per_beat`` per beat (poses on a beat in red). Bottom: mean joint speed of
    the synchronised motion with the music beats, the warped period boundaries
    (dashed) and the kinematic beats (dots), up to ``xlim`` [s].

    Returns
    -------
    matplotlib Figure
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
    """The first ``seconds`` of the synchronised dance as a video with the song.

    The folder of ``path`` is created if missing.
    Written by :func:`beatsync.render.write_video` (an MP4 with the ffmpeg bundled
    with ``imageio-ffmpeg``; without ffmpeg a GIF plus a WAV, and a warning).

    Returns
    -------
    Path
        The file written.
    """
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
