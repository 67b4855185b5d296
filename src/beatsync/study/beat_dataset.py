"""Beat trackers run and scored over a dataset of audio files, on Dask.

``beatsync evaluate beats`` calls this module. :func:`find_tracks`
(:mod:`beatsync.study.beat_tracks`, re-exported here) pairs every audio file with the
annotation of the same stem (``.beats``: one time [s] per line, an optional second
column such as the beat in the bar is ignored);
:func:`evaluate_dataset` tracks and scores every pair on Dask
(:func:`beatsync.cluster.dask_client`), in groups of tracks (:func:`_groups`), and
records one row per track as soon as its group finishes in ``OUT/tracks.jsonl``
(append-only: a crash or Ctrl-C loses at most the groups in flight; a rerun skips the
tracks already scored), then writes
``OUT/tracks.csv`` and ``OUT/summary.csv`` (means per method and folder) atomically.
A track that fails (unreadable, silent, too short) is recorded with its error.

Methods are named as in :data:`beatsync.peers.PEERS` (``psf`` is ours); scores are
:func:`beatsync.evaluate.beats.evaluate`. Every time is in seconds, every tempo in BPM.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import uuid
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .. import io, peers
from ..errors import ParameterError
from ..evaluate.beats import METRICS, count_octave_errors, count_other_tempo
from . import beat_task
from .beat_task import _audio_bytes, evaluate_track, reference_digest
from .beat_tracks import ANNOTATION_SUFFIX, Track, TrackList, find_tracks, read_annotation

__all__ = [
    "Track",
    "TrackList",
    "find_tracks",
    "read_annotation",
    "evaluate_track",
    "TrackLog",
    "DatasetRun",
    "evaluate_dataset",
    "summarize_dataset",
    "ANNOTATION_SUFFIX",
    "RESULT_FILES",
]


#: Files a run writes in its output folder.
RESULT_FILES = ("tracks.jsonl", "tracks.csv", "summary.csv")


class TrackLog:
    """The append-only JSON-lines record of a dataset run (``OUT/tracks.jsonl``).

    Each :meth:`append` writes its rows' lines at once and flushes them to disk, so a
    crash loses at most the lines being written; :meth:`rows` skips a torn line.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)

    def rows(self) -> list[dict[str, Any]]:
        """Every complete row, in the order written."""
        return [r for r in io.read_jsonl(self.path) if "key" in r and "method" in r]

    def latest(self) -> dict[tuple[str, str], dict[str, Any]]:
        """The last row of each ``(method, key)``."""
        return {(r["method"], r["key"]): r for r in self.rows()}

    def rewrite(self, rows: Sequence[dict[str, Any]]) -> None:
        """Replace the record with ``rows`` (atomic)."""
        io.write_jsonl(self.path, rows)

    def append(self, *rows: dict[str, Any]) -> None:
        """Append rows (one line each, in one write) and flush them to disk."""
        io.append_jsonl(self.path, *rows)


#: Columns of ``summary.csv`` after the keys (means of the metrics over ``ok`` tracks).
SUMMARY_METRICS = METRICS


#: The settings a row records besides the method: one value per method in a folder.
SETTINGS = ("min_beat_time", "min_bpm", "max_bpm")


def _setting(rows: pd.DataFrame, key: str) -> float:
    """The one value of ``key`` in ``rows`` (NaN if none, absent, not a number (a
    refused bound, recorded as given) or they differ)."""
    if key not in rows:
        return float("nan")
    values = set()
    for v in rows[key]:
        try:
            values.add(None if v is None or v != v else float(v))
        except (TypeError, ValueError):
            return float("nan")
    one = values.pop() if len(values) == 1 else None
    return float("nan") if one is None else one


def summarize_dataset(rows: Sequence[dict[str, Any]]) -> pd.DataFrame:
    """Means per method and folder (and over all folders) of a dataset run's rows.

    Returns
    -------
    pandas.DataFrame
        Columns ``method, group`` (``"all"`` for every folder together), the settings
        the scored rows were scored with (``min_beat_time``, ``min_bpm``, ``max_bpm``:
        empty for the default range, or if the rows differ; those of the failed rows if
        none scored), ``tracks``, ``failed``, the mean of every metric over the scored
        tracks, ``octave errors`` and ``other tempo`` (counts).
    """
    table = pd.DataFrame(list(rows))
    if table.empty:
        return pd.DataFrame(columns=["method", "group", "tracks", "failed", *METRICS])
    parts = []
    for group_by_folder in (True, False):
        t = table if group_by_folder else table.assign(group="all")
        for (method, group), sub in t.groupby(["method", "group"], sort=True):
            ok = sub[sub["status"] == "ok"]
            rec: dict[str, Any] = {
                "method": method,
                "group": group,
                # the scored rows' settings (failed rows are re-run with today's)
                **{key: _setting(ok if len(ok) else sub, key) for key in SETTINGS},
                "tracks": len(sub),
                "failed": int((sub["status"] != "ok").sum()),
            }
            for m in METRICS:
                rec[m] = float(ok[m].mean()) if len(ok) and m in ok else float("nan")
            octave = ok["octave"] if "octave" in ok else pd.Series(dtype=object)
            rec["octave errors"] = count_octave_errors(octave)
            rec["other tempo"] = count_other_tempo(octave)
            parts.append(rec)
    out = pd.DataFrame(parts)
    if out["group"].nunique() == 2 and set(out["group"]) == {".", "all"}:
        out = out[out["group"] == "all"]  # one folder: the per-folder rows repeat "all"
    return out.reset_index(drop=True)


@dataclass(frozen=True)
class DatasetRun:
    """Output of :func:`evaluate_dataset`.

    Attributes
    ----------
    tracks : pandas.DataFrame
        The latest row of every track of this method (without the beat lists).
    summary : pandas.DataFrame
        :func:`summarize_dataset` of every method recorded in the output folder.
    scored, skipped : int
        Tracks run now, and tracks already recorded by an earlier run.
    changed : int
        Tracks run now although scored before: their audio file (path or size) or
        annotation changed since.
    files : dict of str -> Path
        ``log`` (``tracks.jsonl``), ``tracks`` (CSV) and ``summary`` (CSV).
    """

    tracks: pd.DataFrame
    summary: pd.DataFrame
    scored: int
    skipped: int
    files: dict[str, Path]
    changed: int = 0


def _table(rows: Sequence[dict[str, Any]]) -> pd.DataFrame:
    table = pd.DataFrame([{k: v for k, v in r.items() if k != "beats"} for r in rows])
    return table.sort_values(["method", "key"]).reset_index(drop=True) if len(table) else table


def _output_folder(out_dir: str | os.PathLike[str]) -> Path:
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"output folder {str(out)!r} is a file; give a folder for the results")
    if not out.exists():
        io.check_output_folder(out)  # its parent must exist and be writable
    elif not os.access(out, os.W_OK):
        raise ParameterError(f"output folder {str(out)!r} is not writable")
    return out


def evaluate_dataset(
    tracks: Sequence[Track],
    out_dir: str | os.PathLike[str],
    *,
    method: str = "psf",
    min_beat_time: float = 0.0,
    min_bpm: float | None = None,
    max_bpm: float | None = None,
    force: bool = False,
    scheduler: str | None = None,
    n_workers: int | None = None,
    processes: bool = True,
    progress: Callable[..., None] | None = None,
) -> DatasetRun:
    """Track and score every track on Dask; record each row as soon as its group finishes.

    Parameters
    ----------
    tracks : sequence of Track
        From :func:`find_tracks`.
    out_dir : path
        Results folder (created if missing; its parent must exist): ``tracks.jsonl``
        (one row per finished track, appended), ``tracks.csv``, ``summary.csv``.
    method : str
        A name of :data:`beatsync.peers.PEERS`.
    min_beat_time : float >= 0 [s]
        Beats before this time are not scored (mir_eval/MIREX use 5 s; 0 scores all).
    min_bpm, max_bpm : float, optional [BPM]
        The tempo range the method searches on every track; a bound not given keeps the
        method's default (:func:`beatsync.peers.check_tempo_range`). Recorded in each
        row.
    force : bool
        Re-run these tracks although recorded for ``method`` (default: skip those
        scored). The new rows are appended; once the run completes, the record keeps
        the latest row of every track, and drops rows of this method for tracks outside
        this run that were scored with other settings. Tracks recorded with an error,
        and tracks whose audio file (path or size) or annotation changed since they were
        scored, are always re-run.
    scheduler, n_workers, processes
        See :func:`beatsync.cluster.dask_client`. Workers of an existing cluster must
        see the audio files at the same paths.
    progress : callable ``progress(done, total=None)``, optional
        Called as groups of tracks finish, with the number of tracks done (e.g. a
        command's progress bar).

    Raises
    ------
    ParameterError
        An unknown or unavailable method; an annotation that is not beat times in
        seconds; an output folder that is a file; results in ``out_dir`` scored with
        another ``min_beat_time`` or tempo range (without ``force``; failed rows do not
        count, they are re-run); a tempo range the method does not accept (for librosa,
        one holding none of its tempi at a track's sample rate); a bad worker count or
        an unreachable scheduler (:func:`~beatsync.cluster.dask_client`).
    """
    from ..cluster import check_cluster_options, dask_client
    from ..units import check_positive

    peers.get(method)
    mbt = check_positive(min_beat_time, name="min_beat_time", unit="s", allow_zero=True)
    tempo = peers.check_tempo_range(method, min_bpm, max_bpm)
    bpm_range = (tempo.get("min_bpm"), tempo.get("max_bpm"))
    check_cluster_options(scheduler, n_workers)
    if not tracks:
        raise ParameterError("no tracks to evaluate; see find_tracks")
    keys = [t.key for t in tracks]
    if len(set(keys)) != len(keys):
        raise ParameterError("tracks must have distinct keys (relative audio paths)")
    out = _output_folder(out_dir)
    refs = {t.key: read_annotation(t.annotation) for t in tracks}
    log = TrackLog(out / "tracks.jsonl")
    previous = {k: r for (m, k), r in log.latest().items() if m == method}
    if not force:
        # only scored rows bind a resume: failed ones are re-run with today's settings
        scored = [r for r in previous.values() if r.get("status") == "ok"]
        other = sorted({r["min_beat_time"] for r in scored} - {mbt})
        if other:
            raise ParameterError(
                f"{str(log.path)!r} holds {method} results scored with --min-beat-time "
                f"{other[0]:g} s, not {mbt:g} s; use --force to re-run them or another --out"
            )
        stored = {(r.get("min_bpm"), r.get("max_bpm")) for r in scored}
        ranges = {_recorded_range(method, bounds) for bounds in stored}
        other_range = sorted(ranges - {bpm_range}, key=str)
        if other_range:
            raise ParameterError(
                f"{str(log.path)!r} holds {method} results tracked with "
                f"{_range_text(other_range[0])}, not {_range_text(bpm_range)}; use --force "
                "to re-run them or another --out"
            )
    done = set()
    changed = 0
    if not force:
        for t in tracks:
            row = previous.get(t.key)
            if row is None or row.get("status") != "ok":
                continue
            if _same_inputs(row, t, refs[t.key]):
                done.add(t.key)
            else:
                changed += 1
    todo = [t for t in tracks if t.key not in done]
    if method == "librosa" and tempo:
        _check_librosa_rates(todo, tempo)
    created = not out.exists()
    try:
        with contextlib.ExitStack() as stack:
            # the tracks silence other packages' warnings with warnings.catch_warnings,
            # whose filters are process-wide: tracks on the threads of this process
            # (processes=False) could leave them changed; restored when the run ends
            stack.enter_context(warnings.catch_warnings())
            if todo:  # connect first: an unreachable scheduler changes nothing on disk
                client = stack.enter_context(
                    dask_client(scheduler=scheduler, n_workers=n_workers, processes=processes)
                )
            out.mkdir(exist_ok=True)
            if todo:
                _run(
                    client, todo, refs, log, method=method, mbt=mbt, tempo=tempo,
                    progress=progress,
                )  # fmt: skip
    except BaseException:
        with contextlib.suppress(OSError):  # never hide the interrupt behind this
            if created and out.is_dir() and not any(out.iterdir()):
                out.rmdir()  # interrupted before any track finished: no empty folder left
        raise
    if force and previous:
        # appended, not replaced up front: an interrupted --force keeps the earlier rows
        # of the tracks it did not reach, and tracks outside this run keep theirs unless
        # they were scored with other settings (those would bind every later resume)
        mine_now = (mbt, *bpm_range)
        log.rewrite(
            [
                r
                for (m, k), r in log.latest().items()
                if m != method or k in refs or _row_settings(method, r) == mine_now
            ]
        )
    latest = log.latest()
    mine = [latest[(method, k)] for k in keys if (method, k) in latest]
    files = {"log": log.path, "tracks": out / "tracks.csv", "summary": out / "summary.csv"}
    summary = summarize_dataset(list(latest.values()))
    io.write_csv(files["tracks"], _table(list(latest.values())))
    io.write_csv(files["summary"], summary)
    return DatasetRun(_table(mine), summary, len(todo), len(tracks) - len(todo), files, changed)


def _same_inputs(row: dict[str, Any], track: Track, reference: np.ndarray) -> bool:
    """Was ``row`` scored on this track's audio file and annotation? Rows written before
    the digest and size were recorded are taken as they are."""
    stored = row.get("audio")
    if stored is not None and os.path.realpath(stored) != os.path.realpath(track.audio):
        return False  # (the same file given through another path is the same file)
    size = row.get("audio_bytes")
    if size is not None and size != _audio_bytes(track.audio):
        return False
    digest = row.get("reference_digest")
    return digest is None or digest == reference_digest(reference)


def _row_settings(method: str, row: dict[str, Any]) -> tuple[Any, ...]:
    bounds = _recorded_range(method, (row.get("min_bpm"), row.get("max_bpm")))
    return (row.get("min_beat_time"), *bounds)


def _check_librosa_rates(tracks: Sequence[Track], tempo: dict[str, float]) -> None:
    """Refuse, before any work, a tempo range librosa cannot search at a track's rate.

    librosa's tempi are lags of an onset autocorrelation, so which exist depends on the
    sample rate (:func:`beatsync.beats.tracker.librosa_tempo_prior`). A file the client
    cannot open (e.g. a path valid only on the workers) or with an implausible rate is
    left to its task, which records why it fails.
    """
    import soundfile as sf

    from ..beats.tracker import librosa_tempo_prior
    from ..units import check_sample_rate

    first: dict[float, str] = {}
    for t in tracks:
        try:
            rate = check_sample_rate(sf.info(str(t.audio)).samplerate)
        except Exception:  # unreadable or implausible here: the track's own row says why
            continue
        first.setdefault(rate, t.key)
    refused = []
    for rate, key in sorted(first.items()):
        try:
            librosa_tempo_prior(**tempo, sr=rate)
        except ParameterError as exc:
            refused.append(f"{key!r} (and any other track at {rate:g} Hz): {exc}")
    if refused:
        raise ParameterError("; ".join(refused) + "; nothing was run")


def _recorded_range(method: str, bounds: tuple[Any, Any]) -> tuple[float | None, float | None]:
    """A stored row's tempo range ``bounds``, as :func:`check_tempo_range` would record
    it today (a bound equal to the default as ``None``: rows written before that rule
    resume)."""
    try:
        tempo = peers.check_tempo_range(method, *bounds)
    except ParameterError:
        return bounds
    return (tempo.get("min_bpm"), tempo.get("max_bpm"))


def _range_text(bounds: tuple[float | None, float | None]) -> str:
    """``(None, None)`` -> "the default tempo range"; ``(60, None)`` -> "--min-bpm 60"."""
    names = ("--min-bpm", "--max-bpm")
    given = [f"{k} {v:g}" for k, v in zip(names, bounds, strict=True) if v is not None]
    return " and ".join(given) if given else "the default tempo range"


def _prepare_workers(client, method: str) -> None:
    """:func:`beatsync.peers.prepare` on each worker in turn, never on two at once.

    A fresh install's workers would otherwise compile librosa's numba cache together,
    which can crash them (see :func:`~beatsync.peers.prepare`). A worker that fails here
    is left to record the error with its first track.
    """
    if method != "librosa":
        return
    for address in client.nthreads():  # every worker (scheduler_info held 5 in some versions)
        with contextlib.suppress(Exception):
            client.run(peers.prepare, method, workers=[address])


#: The most tracks one task reads, tracks and scores in turn (:func:`_groups`).
GROUP_TRACKS = 8


def _groups(todo: Sequence[Track], n_threads: int) -> list[list[Track]]:
    """The tracks in order, in groups of decreasing size: one task each.

    Dask spends a few milliseconds on every task, in the worker and in this process
    (which, on a machine of two cores, takes them from the workers), and a 30 s excerpt
    takes about 30 ms to track here: with one track a task, 2 workers gave 1.62-1.67x
    the throughput of 1 (``benchmarks/bench_evaluate.py``). Dask's best practices
    counsel fewer, larger tasks when each is short. Each group holds the remaining
    tracks over the worker threads, at most :data:`GROUP_TRACKS` (guided
    self-scheduling, Polychronopoulos & Kuck 1987), so the last groups hold one track
    and the workers finish together. A group's rows are recorded when it finishes: a
    crash or Ctrl-C loses at most the groups in flight.
    """
    groups, i = [], 0
    while i < len(todo):
        size = min(GROUP_TRACKS, -(-(len(todo) - i) // max(1, n_threads)))
        groups.append(list(todo[i : i + size]))
        i += size
    return groups


def _longest_first(todo: Sequence[Track]) -> list[Track]:
    """The tracks by audio file size, largest first (their order otherwise): the longest
    go out in the first, largest groups and the shortest last, so the workers finish
    together (longest processing time first; a file's size stands for its length).

    Measured on 42 copies of the three bundled annotated recordings (2.8-56 s; a scratch
    run of ``benchmarks/bench_evaluate.py``'s Dask path, 12 pairs alternating): 0.94x
    the time of the tracks in key order with 1 worker and 0.95x with 2; the 2-worker
    ratio stayed the same (1.69x against 1.68x).
    """
    return sorted(todo, key=lambda t: -(_audio_bytes(t.audio) or 0))


def _failed_row(t: Track, ref: np.ndarray, exc: Exception, *, method, mbt, tempo) -> dict:
    """The row of a track whose task failed outside :func:`evaluate_track` (its worker
    died, e.g. out of memory, or the task was cancelled)."""
    return beat_task.failed_row(
        t.audio, ref, f"{type(exc).__name__}: {exc}", method=method, min_beat_time=mbt,
        name=t.key, group=t.group, min_bpm=tempo.get("min_bpm"), max_bpm=tempo.get("max_bpm"),
    )  # fmt: skip


def _run(client, todo, refs, log, *, method, mbt, tempo, progress) -> None:
    from concurrent.futures import CancelledError

    from dask.distributed import KilledWorker, as_completed

    _prepare_workers(client, method)

    run = uuid.uuid4().hex
    numbers = itertools.count()

    def submit(groups: list[list[Track]]) -> list:
        # in one call, so that the scheduler sees the run's tasks as one group and can
        # queue them (worker-saturation; Dask queues a group of more tasks than twice the
        # threads) instead of handing the first ones out at once; it runs them in this
        # order. One key prefix for the run: Dask groups tasks by it, and a track's name
        # in it made a group of each task
        return client.map(
            beat_task.evaluate_tracks,
            [[(str(t.audio), refs[t.key], t.key, t.group) for t in group] for group in groups],
            key=[f"evaluate-{method}-{run}-{next(numbers):06d}" for _ in groups],
            method=method,
            min_beat_time=mbt,
            **tempo,
        )

    def resubmit(groups: list[list[Track]]) -> None:
        for fut, group in zip(submit(groups), groups, strict=True):
            futures[fut] = group
            queue.add(fut)

    groups = _groups(_longest_first(todo), sum(client.nthreads().values()))
    futures = dict(zip(submit(groups), groups, strict=True))
    again: set[str] = set()  # tracks run alone a second time
    if progress is not None:
        progress(0, total=len(todo))
    done = 0
    try:
        queue = as_completed(futures)
        for fut in queue:
            # released once read: a finished task's result would stay on its worker,
            # and Dask computes it again if that worker dies
            group = futures.pop(fut)
            try:
                rows = fut.result()
            except CancelledError as exc:  # cancelled outside the run, or the scheduler lost
                rows = [_failed_row(t, refs[t.key], exc, method=method, mbt=mbt, tempo=tempo)
                        for t in group]  # fmt: skip
            except Exception as exc:  # a worker died (e.g. out of memory)
                if len(group) > 1:  # one track may be the cause: each alone, again
                    resubmit([[t] for t in group])
                    continue
                t = group[0]
                if not isinstance(exc, KilledWorker) and t.key not in again:
                    # not its own fault: it finished on a worker that another track then
                    # killed before its result was fetched (Dask raised RuntimeError "...
                    # bound to a different event loop"); once more
                    again.add(t.key)
                    resubmit([[t]])
                    continue
                rows = [_failed_row(t, refs[t.key], exc, method=method, mbt=mbt, tempo=tempo)]
            log.append(*rows)  # in one write: an interrupt keeps the group or not at all
            done += len(rows)
            if progress is not None:
                progress(done)
    finally:
        # an interrupted run: the tracks still queued or in flight stop (one message)
        pending = [fut for fut in futures if not fut.done()]
        if pending:
            client.cancel(pending)
