"""A study over many motion clips x songs, run on Dask.

Syncing every clip to every song is embarrassingly parallel. The work is a Dask
task graph: each song's beats are tracked once, each clip is read and segmented
once, and every (clip, song) pair is synchronised from those results. By default a
local cluster (one process per core) runs it; give ``scheduler`` (an address such as
``"tcp://10.0.0.5:8786"``) to use an existing cluster. A pair that fails on bad
input (a clip that is not periodic, a song without beats) records the error message
in its row instead of stopping the study. Every pair is synchronised as ``beatsync
sync`` does with its defaults: ``mode`` is that of :func:`beatsync.sync.synchronize`
(``"auto"`` by default: periods when the clip is periodic, else its motion beats, what
real dancers need; or paper A's periods, or the dancer's own motion beats), the dance
is looped to the song's last beat (``fill="loop"``) and the song's meter estimated by
the beat tracker is respected; the clip is segmented once either way.

Items are named by their file name without suffix; when file names repeat (a dataset
of one folder per take, ``DANCE_C_4/skeletons.json``, ``DANCE_R_3/skeletons.json``),
by the folder that holds them (:func:`item_names`).

Data contract: every time is in seconds; every output file is written atomically
under ``out_dir`` as ``<clip>__<song>`` in the clip's own kind of file
(:func:`output_suffix`: ``.bvh`` with a skeleton, joint positions back in their
input's layout, ``.json``, ``.npy``, ``.npz`` or ``.c3d``, else a ``.csv`` table);
inputs are never written.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .errors import NotPeriodicError, ParameterError

__all__ = [
    "item_names",
    "sync_grid",
    "prepare_song",
    "prepare_clip",
    "sync_pair",
    "output_suffix",
]


def item_names(paths: Sequence[str | os.PathLike[str]], what: str) -> list[str]:
    """Names of clips or songs in outputs (``<clip>__<song>``): the file name without
    suffix, or the folder's name for files whose names repeat (one folder per take).

    Raises
    ------
    ParameterError
        Two items still share a name.
    """
    stems = [Path(p).stem for p in paths]
    names = [
        Path(p).resolve().parent.name if stems.count(st) > 1 else st
        for p, st in zip(paths, stems, strict=True)
    ]
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        raise ParameterError(
            f"{what} names must differ (outputs are named <clip>__<song>; repeated file "
            f"names are told apart by their folder): {dup} appear more than once"
        )
    return names


def output_suffix(motion: Any) -> str:
    """The suffix a synchronised clip is written with, as ``beatsync sync`` would keep it.

    ``.bvh`` for motion with a skeleton; joint positions in their input's layout
    (Dance-with-Melody ``.json``, ``.npy``, ``.npz``, ``.c3d``; units and vertical axis
    as read, see :func:`beatsync.io.write_motion`); anything else (an angle table,
    MoCap Toolbox markers, positions made in memory) as a ``.csv`` table.
    """
    from .io.positions import POSITION_SUFFIXES  # the layouts written back as read

    if motion.skeleton is not None:
        return ".bvh"
    info = motion.position_info if motion.is_positional else None
    layout = f".{info.layout}" if info is not None else ""
    return layout if layout in POSITION_SUFFIXES else ".csv"


def output_suffixes(clip: str | os.PathLike[str]) -> tuple[str, ...]:
    """Every suffix the pairs of the clip file ``clip`` may be written with (the
    overwrite checks run before the clip is read)."""
    from .io.positions import POSITION_SUFFIXES

    own = Path(clip).suffix.lower()
    return (".bvh", ".csv") + ((own,) if own in POSITION_SUFFIXES else ())


def prepare_song(
    path: str,
    *,
    bpm: float | None = None,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
) -> dict[str, Any]:
    """Read a song and track its beats (a task of the graph); the range only if given."""
    from . import io
    from .beats import track_beats

    y, sr = io.read_audio(path)
    told = {"min_bpm": min_bpm, "max_bpm": max_bpm}
    track = track_beats(y, sr, bpm=bpm, **{k: v for k, v in told.items() if v is not None})
    bar = int(getattr(track, "beats_per_bar", 0) or 0)
    return {
        "song": Path(path).stem,
        "beats": track.beats,
        "tempo_bpm": track.tempo,
        "beats_per_bar": bar if bar > 0 else None,
    }


def prepare_clip(
    path: str,
    *,
    fps: float | None = None,
    variable: str | None = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    alpha: float = 0.1,
    mode: str = "auto",
) -> dict[str, Any]:
    """Read a motion clip and find its periods (a task of the graph).

    ``mode="beats"``: no segmentation (the pairs use the motion beats);
    ``mode="auto"``: a clip that segmentation refuses as not periodic
    (:class:`~beatsync.errors.NotPeriodicError`) gets no boundaries and the reason in
    ``note``; ``mode="periods"``: that refusal is the clip's error. Any other error
    (bad ``alpha`` or ``period_range``, no motion) is the clip's error in both.
    """
    from . import io
    from .sync.core import motion_periods

    motion = io.read_motion(path, fps=fps, variable=variable)
    clip = {
        "clip": Path(path).stem,
        "motion": motion,
        "boundaries": None,
        "mean_period_s": float("nan"),
        "note": "",
    }
    if mode == "beats":
        return clip
    try:
        seg = motion_periods(motion, alpha=alpha, period_range=period_range)
    except NotPeriodicError as exc:  # bad settings or no motion stay the clip's error
        if mode == "periods":  # a free dance, most likely: say what syncs it
            raise NotPeriodicError(
                f"{exc}; mode 'beats' (--mode beats) syncs its own motion beats instead, "
                "and 'auto' (--mode auto) falls back to them"
            ) from None
        clip["note"] = f"not periodic ({exc}): its motion beats were used"
        return clip
    clip.update(boundaries=seg.boundaries, mean_period_s=seg.mean_period)
    return clip


def sync_pair(
    clip: dict[str, Any] | BaseException,
    song: dict[str, Any] | BaseException,
    out_dir: str,
    clip_name: str,
    song_name: str,
) -> dict[str, Any]:
    """Synchronise one clip to one song and write the result; errors become a row."""
    from . import io
    from .sync import synchronize

    row: dict[str, Any] = {"clip": clip_name, "song": song_name}
    for what, value in (("clip", clip), ("song", song)):
        if isinstance(value, BaseException):
            row.update(status="error", error=f"{what}: {value}")
            return row
    assert isinstance(clip, dict) and isinstance(song, dict)
    # as `beatsync sync` with its defaults: looped to the song's last beat, its meter kept
    kw = {"fill": "loop", "beats_per_bar": song.get("beats_per_bar")}
    try:
        if clip["boundaries"] is None:  # mode "beats", or "auto" on a clip that is not periodic
            res = synchronize(clip["motion"], None, song["beats"], mode="beats", **kw)
        else:
            res = synchronize(clip["motion"], clip["boundaries"], song["beats"], **kw)
    except ParameterError as exc:
        row.update(status="error", error=str(exc))
        return row
    except Exception as exc:  # one broken pair must not stop a study of thousands
        row.update(status="error", error=f"{type(exc).__name__}: {exc}")
        return row
    out = Path(out_dir) / f"{clip_name}__{song_name}{output_suffix(res.motion)}"
    io.write_motion(out, res.motion)
    rep = res.report
    row.update(
        status="ok",
        output=str(out),
        mode=rep.get("mode"),
        note=clip["note"],
        tempo_bpm=float(song["tempo_bpm"]),
        mean_period_s=float(clip["mean_period_s"]),
        input_frames=rep.get("input_frames"),
        output_frames=rep.get("output_frames"),
        beats_per_period=rep.get("beats_per_period"),
        speed_in_band=rep["playback_speed"]["per_interval"]["in_band"],
        max_abs_residual_ms=rep.get("max_abs_residual_ms"),
        error="",
    )
    return row


def _guard(func: Any) -> Any:
    """Wrap a task so its error is returned (and recorded by the pairs), not raised."""

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except ParameterError as exc:
            return exc
        except Exception as exc:  # recorded per pair, like bad input
            return RuntimeError(f"{type(exc).__name__}: {exc}")

    wrapped.__name__ = func.__name__
    return wrapped


def sync_grid(
    clips: Sequence[str | os.PathLike[str]],
    songs: Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str],
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    processes: bool = True,
    fps: float | None = None,
    variable: str | None = None,
    bpm: float | None = None,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
    period_range: tuple[float, float] = (0.25, 1.25),
    alpha: float = 0.1,
    mode: str = "auto",
    progress: Callable[..., None] | None = None,
) -> Any:
    """Synchronise every clip with every song on Dask; return a table of reports.

    Parameters
    ----------
    clips, songs : sequence of path
        Motion files (any of :func:`beatsync.io.read_motion`: BVH, MoCap Toolbox ``.mat``,
        CSV/NPY angle tables, joint positions in ``.json``, ``.npy``, ``.npz`` or
        ``.c3d``; ``fps`` where the file has none) and audio files.
    out_dir : path
        Existing folder for the synchronised clips (``<clip>__<song>`` with the suffix
        of :func:`output_suffix`: BVH, joint positions in the input's layout, or CSV).
    scheduler : str, optional
        Address of an existing Dask scheduler; default: a local cluster. The workers
        read the inputs and write the outputs themselves, so every path must be valid
        on every worker (a shared file system). See :func:`beatsync.cluster.dask_client`
        (an unreachable scheduler is refused after a few seconds).
    n_workers : int >= 1, optional
        Workers of the local cluster (default: one per core).
    processes : bool
        Local cluster with worker processes (default) or threads.
    fps : float, optional [Hz]
        Frame-rate override for every clip (e.g. 60 for the CMU salsa files).
    variable : str, optional
        The recording inside a ``.mat`` file, or the array inside an ``.npz``, of every
        clip (e.g. ``"dance2"``).
    bpm : float, optional [BPM]
        Known tempo of every song.
    min_bpm, max_bpm : float, optional [BPM]
        Tempo range searched in every song (default: :func:`beatsync.beats.track_beats`'s).
    mode : {"auto", "periods", "beats"}
        What lands on the beats (``beatsync sync``'s default ``"auto"``): periods when
        the clip is periodic and motion beats otherwise, paper A's periods (a clip that
        is not periodic fails), or the clip's own motion beats (see
        :func:`beatsync.sync.synchronize`).
    progress : callable ``progress(done, total=None)``, optional
        Called as pairs finish (e.g. a command's progress bar).

    Returns
    -------
    pandas.DataFrame
        One row per (clip, song): status, output path, the mode used (and why, for a
        clip that ``"auto"`` found not periodic), tempo, frames, beats per period,
        maximum boundary residual [ms], or the error message.

    Raises
    ------
    ParameterError
        No clip or song, a missing input, a missing output folder, two inputs of the
        same name, an output that would overwrite an input, a worker count below 1,
        ``n_workers`` with ``scheduler``, an unreachable scheduler, a bad ``fps``,
        ``alpha`` or ``period_range`` (checked once, before any work).
    """
    import pandas as pd

    from .cluster import dask_client
    from .segment.checks import check_alpha, check_period_range
    from .sync import MODES
    from .validation import check_cluster_options, check_motion_fps

    check_cluster_options(scheduler, n_workers)
    if mode not in MODES:
        raise ParameterError(f"mode={mode!r} must be one of {', '.join(MODES)}")
    # settings shared by every clip: refused here, once, before any worker starts
    if fps is not None:
        fps = check_motion_fps(fps)
    if mode != "beats":
        alpha = check_alpha(alpha)
        period_range = check_period_range(period_range)
    clips = [str(c) for c in clips]
    songs = [str(s) for s in songs]
    if not clips or not songs:
        raise ParameterError("sync_grid needs at least one clip and one song")
    for p in clips + songs:
        if not Path(p).is_file():
            raise ParameterError(f"input file {p!r} does not exist")
    out = Path(out_dir)
    if not out.is_dir():
        raise ParameterError(f"output folder {str(out)!r} does not exist; create it first")
    clip_names = dict(zip(clips, item_names(clips, "clip"), strict=True))
    song_names = dict(zip(songs, item_names(songs, "song"), strict=True))
    inputs = {Path(p).resolve() for p in clips + songs}
    for c in clips:
        for s in songs:
            for suffix in output_suffixes(c):
                target = (out / f"{clip_names[c]}__{song_names[s]}{suffix}").resolve()
                if target in inputs:
                    raise ParameterError(
                        f"output {str(target)!r} would overwrite an input file; "
                        "choose another --out-dir"
                    )

    with dask_client(scheduler=scheduler, n_workers=n_workers, processes=processes) as client:
        song_f = {
            s: client.submit(
                _guard(prepare_song), s, bpm=bpm, min_bpm=min_bpm, max_bpm=max_bpm, pure=False
            )
            for s in songs
        }
        clip_f = {
            c: client.submit(
                _guard(prepare_clip),
                c,
                fps=fps,
                variable=variable,
                period_range=period_range,
                alpha=alpha,
                mode=mode,
                pure=False,
            )
            for c in clips
        }
        pairs = [
            client.submit(
                sync_pair,
                clip_f[c],
                song_f[s],
                str(out),
                clip_names[c],
                song_names[s],
                pure=False,
            )
            for c in clips
            for s in songs
        ]
        if progress is not None:
            from dask.distributed import as_completed

            progress(0, total=len(pairs))
            for done, _ in enumerate(as_completed(pairs), 1):
                progress(done)
        rows = client.gather(pairs)
    return pd.DataFrame(rows)
