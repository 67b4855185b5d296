"""A study over many motion clips x songs, run on Dask (``beatsync batch``).

Each song's beats are tracked once, each clip is read and segmented once, and every
(clip, song) pair is synchronised from those results as ``beatsync sync`` does with its
defaults (:func:`beatsync.sync.synchronize`; ``mode="auto"``, looped to the song's end,
the song's estimated meter respected). A pair that fails records its error in its
row instead of stopping the study. Outputs are ``<clip>__<song>`` under ``out_dir`` in
the clip's own kind of file (:func:`output_suffix`), items named by their file name
without suffix, or by their folder where file names repeat (:func:`item_names`). The
warnings of a pair's song, clip and synchronisation are kept in its row.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .errors import NotPeriodicError, ParameterError, collect_warnings

__all__ = [
    "item_names",
    "sync_grid",
    "prepare_song",
    "prepare_clip",
    "sync_pair",
    "output_suffix",
]


def item_names(paths: Sequence[str | os.PathLike[str]], what: str) -> list[str]:
    """Names of clips or songs in outputs: the file name without suffix, or the folder's
    name for files whose names repeat (one folder per take); refused if two still match."""
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
    """The suffix a synchronised clip is written with, as ``beatsync sync`` would keep it:
    ``.bvh`` with a skeleton, joint positions in their input's layout (``.json``, ``.npy``,
    ``.npz``, ``.c3d``), anything else as a ``.csv`` table."""
    from .io.positions import POSITION_SUFFIXES  # the layouts written back as read

    if motion.skeleton is not None:
        return ".bvh"
    info = motion.position_info if motion.is_positional else None
    layout = f".{info.layout}" if info is not None else ""
    return layout if layout in POSITION_SUFFIXES else ".csv"


def output_suffixes(clip: str | os.PathLike[str]) -> tuple[str, ...]:
    """Every suffix the pairs of the clip file ``clip`` may be written with (checked
    before the clip is read)."""
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
        "duration_s": y.size / sr,
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
    """Read a motion clip and find its periods (a task of the graph): none with
    ``mode="beats"``; a clip that is not periodic gets the reason in ``note`` with
    ``"auto"``, and that is its error with ``"periods"`` (as any other error in both)."""
    from . import io
    from .sync.core import motion_periods

    motion = io.read_motion(path, fps=fps, variable=variable)
    clip = {
        "clip": Path(path).stem,
        "motion": motion,
        "boundaries": None,
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
    clip["boundaries"] = seg.boundaries
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

    row: dict[str, Any] = {"clip": clip_name, "song": song_name, "warnings": []}
    for value in (song, clip):
        if isinstance(value, dict):
            row["warnings"] += value["warnings"]
    for what, value in (("clip", clip), ("song", song)):
        if isinstance(value, BaseException):
            row.update(status="error", error=f"{what}: {value}")
            return row
    assert isinstance(clip, dict) and isinstance(song, dict)
    # as `beatsync sync` with its defaults: looped to the song's end, its meter kept
    kw = {
        "fill": "loop",
        "beats_per_bar": song.get("beats_per_bar"),
        "song_end": song.get("duration_s"),
    }
    try:
        if clip["boundaries"] is None:  # mode "beats", or "auto" on a clip that is not periodic
            res = synchronize(clip["motion"], None, song["beats"], mode="beats", **kw)
        else:
            res = synchronize(clip["motion"], clip["boundaries"], song["beats"], **kw)
    except Exception as exc:  # one broken pair must not stop a study of thousands
        row.update(status="error", error=_error_text(exc))
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
        mean_period_s=float(rep["mean_motion_period_s"]),  # beats mode: the median interval
        input_frames=rep.get("input_frames"),
        output_frames=rep.get("output_frames"),
        beats_per_period=rep.get("beats_per_period"),
        speed_in_band=rep["playback_speed"]["per_interval"]["in_band"],
        max_abs_residual_ms=rep.get("max_abs_residual_ms"),
        error="",
    )
    return row


def _error_text(exc: Exception) -> str:
    """A task's error as its rows record it: bad input by its message, else with its type."""
    return str(exc) if isinstance(exc, ParameterError) else f"{type(exc).__name__}: {exc}"


def _noting(func: Any) -> Any:
    """Wrap a task so the :class:`~beatsync.errors.BeatsyncWarning` messages it issues are
    appended to its result's ``"warnings"`` (a worker would print them raw, apart from
    their pair); other packages' warnings are dropped."""

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        with collect_warnings() as caught, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = func(*args, **kwargs)
        out["warnings"] = [*out.get("warnings", []), *caught]
        return out

    wrapped.__name__ = func.__name__
    return wrapped


def _guard(func: Any) -> Any:
    """Wrap a task so its error is returned (and recorded by the pairs), not raised."""

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except Exception as exc:
            return RuntimeError(_error_text(exc))

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
    """Synchronise every clip with every song on Dask; return a table, a row per pair.

    ``clips`` are motion files of :func:`beatsync.io.read_motion` (``fps`` and
    ``variable`` apply to each), ``songs`` audio files, ``out_dir`` an existing folder.
    ``scheduler`` is the address of an existing Dask scheduler (its workers read and
    write the paths themselves: a shared file system), else ``n_workers`` local workers,
    processes or threads (:func:`beatsync.cluster.dask_client`). ``bpm``, ``min_bpm``
    and ``max_bpm`` [BPM] fix or bound every song's tempo; ``period_range`` [s],
    ``alpha`` and ``mode`` are those of :func:`beatsync.sync.synchronize`.
    ``progress(done, total=None)`` is called as pairs finish.

    A row holds the status, output path, the mode used (and why, for a clip that
    ``"auto"`` found not periodic), tempo, frames, beats per period and largest boundary
    residual [ms], or the error, and the warnings of its song, clip and synchronisation
    (joined by ``" | "``). Bad shared settings and inputs are refused with a
    ``ParameterError`` before any work.
    """
    import pandas as pd

    from .cluster import dask_client
    from .io import check_input_file
    from .segment.checks import check_alpha, check_period_range
    from .sync import MODES
    from .validation import check_choice, check_cluster_options, check_motion_fps

    check_cluster_options(scheduler, n_workers)
    check_choice(mode, MODES, name="mode")
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
        check_input_file(p, "input")
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
                _guard(_noting(prepare_song)),
                s,
                bpm=bpm,
                min_bpm=min_bpm,
                max_bpm=max_bpm,
                pure=False,
            )
            for s in songs
        }
        clip_f = {
            c: client.submit(
                _guard(_noting(prepare_clip)),
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
                _noting(sync_pair),
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
    for row in rows:
        row["warnings"] = " | ".join(row["warnings"])
    return pd.DataFrame(rows)
