"""Beat trackers run and scored against the annotations of a dataset, on Dask.

Scores are :func:`beatsync.evaluate.beats.evaluate`'s, methods those of
:data:`beatsync.other_trackers.TRACKERS`; times are in seconds, tempi in BPM.

:func:`find_tracks` pairs every audio file with the annotation of the same stem
(``.beats``: one time [s] per line, an optional second column such as the beat in the
bar is ignored). :func:`evaluate_dataset` (``beatsync evaluate beats``) runs the
tracks on Dask in groups, appends each row to ``OUT/tracks.jsonl`` as soon as its
group finishes (a crash or Ctrl-C loses at most the groups in flight; a rerun skips
the tracks already scored), then writes ``OUT/tracks.csv`` and ``OUT/summary.csv``.

pandas is imported by the table functions only: a worker imports this module to run
:func:`evaluate_tracks` and needs none of it.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import os
import time
import uuid
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import io, other_trackers
from ..errors import ParameterError, collect_warnings
from ..evaluate.beats import (
    METRICS,
    count_octave_errors,
    count_other_tempo,
    evaluate,
    not_seconds_detail,
    tempo_octave,
)
from ..validation import MAX_BPM

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ANNOTATION_SUFFIX",
    "Track",
    "TrackList",
    "find_tracks",
    "read_annotation",
    "evaluate_track",
    "evaluate_tracks",
    "TrackLog",
    "DatasetRun",
    "evaluate_dataset",
    "summarize_dataset",
    "RESULT_FILES",
]


# ------------------------------------------------------------------ tracks of a dataset

#: Suffix of beat annotation files: one time [s] per line, optionally a second column.
ANNOTATION_SUFFIX = ".beats"


@dataclass(frozen=True)
class Track:
    """One audio file and its annotation: ``key`` is the audio file's path relative to
    the audio folder without suffix (POSIX), ``group`` its folder (``"."`` at the top)."""

    key: str
    group: str
    audio: Path
    annotation: Path


@dataclass(frozen=True)
class TrackList:
    """Output of :func:`find_tracks`: the pairs, and the audio files left without one.

    ``unmatched``: audio files with no annotation of their name. ``shared``: annotations
    found by name only that several audio files would use (``a/x.wav`` and ``b/x.wav``
    for ``x.beats``), or that another audio file has at its own relative path, with the
    audio files skipped for it (an annotation fits one recording). ``duplicates``: audio
    files skipped beside one of the same name with another suffix (``x.wav`` beside
    ``x.flac``: the first in sorted order is taken).
    """

    tracks: list[Track]
    unmatched: list[Path] = field(default_factory=list)
    shared: dict[Path, list[Path]] = field(default_factory=dict)
    duplicates: list[Path] = field(default_factory=list)


def _folder(path: str | os.PathLike[str], what: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{what} folder {str(p)!r} does not exist")
    if not p.is_dir():
        raise ParameterError(f"{what} folder {str(p)!r} is a file, not a folder")
    return p


def find_tracks(
    audio_dir: str | os.PathLike[str], annotation_dir: str | os.PathLike[str]
) -> TrackList:
    """Pair every audio file under ``audio_dir`` (:data:`beatsync.io.AUDIO_SUFFIXES`,
    recursively) with the ``.beats`` file at the same relative path (``a/x.wav`` ->
    ``a/x.beats``), else with the only one of its stem under ``annotation_dir`` (flat
    annotation folders, as in most datasets)."""
    a_dir = _folder(audio_dir, "audio")
    b_dir = _folder(annotation_dir, "annotation")
    audio = sorted(
        p for p in a_dir.rglob("*") if p.suffix.lower() in io.AUDIO_SUFFIXES and p.is_file()
    )
    if not audio:
        raise ParameterError(
            f"audio folder {str(a_dir)!r} holds no audio file ({', '.join(io.AUDIO_SUFFIXES)})"
        )
    notes = sorted(p for p in b_dir.rglob(f"*{ANNOTATION_SUFFIX}") if p.is_file())
    if not notes:
        raise ParameterError(
            f"annotation folder {str(b_dir)!r} holds no {ANNOTATION_SUFFIX} file "
            "(one beat time [s] per line)"
        )
    by_rel = {p.relative_to(b_dir).with_suffix("").as_posix(): p for p in notes}
    by_stem: dict[str, list[Path]] = {}
    for p in notes:
        by_stem.setdefault(p.stem, []).append(p)
    tracks, unmatched, duplicates = [], [], []
    by_name: dict[Path, list[Path]] = {}  # annotations found by name only, and their users
    by_path: set[Path] = set()  # annotations found at their audio file's relative path
    seen: set[str] = set()
    for p in audio:
        rel = p.relative_to(a_dir)
        key = rel.with_suffix("").as_posix()
        if key in seen:  # x.wav beside x.flac
            duplicates.append(p)
            continue
        note = by_rel.get(key)
        if note is not None:
            by_path.add(note)
        elif len(by_stem.get(p.stem, [])) == 1:
            note = by_stem[p.stem][0]
            by_name.setdefault(note, []).append(p)
        if note is None:
            unmatched.append(p)
            continue
        seen.add(key)
        tracks.append(Track(key, rel.parent.as_posix(), p, note))
    # an annotation found by name that another audio file uses by its path, or that
    # several use by name, fits one recording at most
    shared = {note: users for note, users in by_name.items() if len(users) > 1 or note in by_path}
    taken = {p for users in shared.values() for p in users}
    tracks = [t for t in tracks if t.audio not in taken]
    if not tracks:
        raise ParameterError(
            f"none of the {len(audio)} audio files under {str(a_dir)!r} has an annotation "
            f"of the same name ({ANNOTATION_SUFFIX}) under {str(b_dir)!r}, e.g. "
            f"{audio[0].stem}{ANNOTATION_SUFFIX}"
        )
    return TrackList(tracks, unmatched, shared, duplicates)


def read_annotation(path: str | os.PathLike[str]) -> np.ndarray:
    """Beat times [s] of an annotation file (:func:`beatsync.io.read_beats`), refused if
    they look like frame indices, milliseconds, minutes or onsets instead."""
    times = io.read_beats(path)
    detail = not_seconds_detail(times)
    if detail is not None:
        raise ParameterError(
            f"annotation {str(path)!r} is not beat times in seconds: it ends at {detail}"
        )
    if times.size >= 3:
        step = float(np.median(np.diff(times)))
        if step < 60.0 / MAX_BPM:
            raise ParameterError(
                f"annotation {str(path)!r} is not beat times in seconds: its times are a "
                f"median {step:.4g} apart ({60.0 / step:.0f} BPM read as seconds, faster "
                f"than any beat, over {MAX_BPM:g} BPM): minutes, or onsets rather than beats?"
            )
    return times


# ------------------------------------------------------------------- one track's row


def evaluate_track(
    audio: str,
    reference: np.ndarray,
    *,
    method: str,
    min_beat_time: float,
    name: str,
    group: str = ".",
    min_bpm: float | None = None,
    max_bpm: float | None = None,
) -> dict[str, Any]:
    """Track one audio file and score it against ``reference`` [s]: the row of one track.

    A Dask task of :func:`evaluate_dataset`: a bad track (unreadable, silent, too short,
    a tempo range the method refuses) is a row with its ``error``, never an exception,
    so that one track cannot stop a run. ``name`` and ``group`` are the track's
    :attr:`Track.key` and :attr:`Track.group`; ``min_bpm``, ``max_bpm`` [BPM] the tempo
    range (:func:`beatsync.other_trackers.check_tempo_range`, recorded as checked).
    The row: ``key, group, audio, audio_bytes, reference_digest, method, min_beat_time,
    min_bpm, max_bpm, status`` (``"ok"`` or ``"error"``), ``error``, ``warning``,
    ``n_ref, n_est, tempo_ref, tempo_est, octave``, every metric of
    :data:`~beatsync.evaluate.beats.METRICS`, ``seconds`` (reading and tracking),
    ``audio_seconds`` and ``beats`` (the estimated times).
    """
    row = _failed_row(
        audio, reference, "", method=method, min_beat_time=min_beat_time, name=name,
        group=group, min_bpm=min_bpm, max_bpm=max_bpm,
    )  # fmt: skip
    t0 = time.perf_counter()
    try:
        tempo = other_trackers.check_tempo_range(method, min_bpm, max_bpm)
        row.update(min_bpm=tempo.get("min_bpm"), max_bpm=tempo.get("max_bpm"))
        # ours collected per thread (several tracks may share a worker's threads); any
        # other package's warnings are not the row's
        with collect_warnings() as caught, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            y, sr = io.read_audio(audio)
            if reference.size and reference[0] >= y.size / sr:
                raise ParameterError(
                    f"no annotated beat falls inside the audio: the first is at "
                    f"{reference[0]:.3f} s and the audio ends at {y.size / sr:.3f} s; the "
                    "annotation of another recording?"
                )
            est = other_trackers.track(method, y, sr, **tempo)
            seconds = time.perf_counter() - t0
            scores = evaluate(reference, est, min_beat_time=min_beat_time)
    except ParameterError as exc:
        row["error"] = str(exc)
        return row
    except Exception as exc:  # one broken track must not stop a run over thousands
        row["error"] = f"{type(exc).__name__}: {exc}"
        return row
    row.update(
        status="ok",
        warning="; ".join(dict.fromkeys(_dataset_hint(message) for message in caught)),
        n_ref=int(reference.size),
        n_est=int(est.size),
        **tempo_octave(reference, est),
        **scores,
        seconds=seconds,
        audio_seconds=y.size / sr,
        beats=[round(float(b), 6) for b in est],
    )
    return row


def evaluate_tracks(
    items: list[tuple[str, np.ndarray, str, str]], **settings: Any
) -> list[dict[str, Any]]:
    """:func:`evaluate_track` on each ``(audio, reference, name, group)`` in turn: the
    task of :func:`evaluate_dataset` (one task for several short tracks)."""
    return [
        evaluate_track(audio, reference, name=name, group=group, **settings)
        for audio, reference, name, group in items
    ]


def _failed_row(
    audio: str | os.PathLike[str], reference: np.ndarray, error: str, *, method: str,
    min_beat_time: float, name: str, group: str, min_bpm: float | None, max_bpm: float | None,
) -> dict[str, Any]:  # fmt: skip
    """A track's row with its inputs and settings, ``status`` "error" and ``error``:
    where :func:`evaluate_track` starts, and the row of a task that failed outside it."""
    return {
        "key": name,
        "group": group,
        "audio": str(audio),
        "audio_bytes": _audio_bytes(audio),
        "reference_digest": _reference_digest(reference),
        "method": method,
        "min_beat_time": float(min_beat_time),
        "min_bpm": min_bpm,
        "max_bpm": max_bpm,
        "status": "error",
        "error": error,
        "warning": "",
    }


def _dataset_hint(message: str) -> str:
    """A tracker's warning with the advice a dataset run can follow (it has no --bpm)."""
    from ..beats.tracker import KNOWN_TEMPO_HINT

    return message.replace(
        KNOWN_TEMPO_HINT, "a tempo range (--min-bpm, --max-bpm) narrows the search"
    )


def _reference_digest(reference: np.ndarray) -> str:
    """A short digest of an annotation's beat times: a row records the one it was scored
    against, and a resume re-runs a track whose annotation changed since."""
    data = np.ascontiguousarray(np.asarray(reference, dtype=np.float64)).tobytes()
    return hashlib.sha256(data).hexdigest()[:16]


def _audio_bytes(path: str | os.PathLike[str]) -> int | None:
    try:
        return os.stat(path).st_size
    except OSError:
        return None


# --------------------------------------------------------------------- a dataset run

#: Files a run writes in its output folder.
RESULT_FILES = ("tracks.jsonl", "tracks.csv", "summary.csv")

#: The settings a row records besides the method: one value per method in a folder.
SETTINGS = ("min_beat_time", "min_bpm", "max_bpm")

#: The most tracks one task reads, tracks and scores in turn (:func:`_groups`).
GROUP_TRACKS = 8


class TrackLog:
    """The append-only JSON-lines record of a dataset run (``OUT/tracks.jsonl``): a
    crash loses at most the lines being appended, and :meth:`rows` skips a torn line."""

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
    """Means per method and folder (``group`` ``"all"``: every folder together) of a
    dataset run's rows: the settings the scored rows share (empty for the default range
    or if they differ; the failed rows' if none scored), ``tracks``, ``failed``, each
    metric's mean over the scored tracks, ``octave errors`` and ``other tempo``."""
    import pandas as pd

    table = pd.DataFrame(list(rows))
    if table.empty:
        return pd.DataFrame(columns=["method", "group", "tracks", "failed", *METRICS])
    parts = []
    for t in (table, table.assign(group="all")):
        for (method, group), sub in t.groupby(["method", "group"], sort=True):
            ok = sub[sub["status"] == "ok"]
            octave = ok["octave"] if "octave" in ok else pd.Series(dtype=object)
            parts.append(
                {
                    "method": method,
                    "group": group,
                    # the scored rows' settings (failed rows are re-run with today's)
                    **{key: _setting(ok if len(ok) else sub, key) for key in SETTINGS},
                    "tracks": len(sub),
                    "failed": int((sub["status"] != "ok").sum()),
                    **{
                        m: float(ok[m].mean()) if m in ok and len(ok) else float("nan")
                        for m in METRICS
                    },
                    "octave errors": count_octave_errors(octave),
                    "other tempo": count_other_tempo(octave),
                }
            )
    out = pd.DataFrame(parts)
    if set(out["group"]) == {".", "all"}:
        out = out[out["group"] == "all"]  # one folder: the per-folder rows repeat "all"
    return out.reset_index(drop=True)


@dataclass(frozen=True)
class DatasetRun:
    """Output of :func:`evaluate_dataset`: this method's latest row of every track
    (without the beats), the :func:`summarize_dataset` of every method in the folder,
    the tracks ``scored`` now and ``skipped`` (recorded before), the ``files`` (``log``,
    ``tracks``, ``summary``), and the tracks run again because their audio file or
    annotation ``changed``."""

    tracks: pd.DataFrame
    summary: pd.DataFrame
    scored: int
    skipped: int
    files: dict[str, Path]
    changed: int = 0


def _table(rows: Sequence[dict[str, Any]]) -> pd.DataFrame:
    import pandas as pd

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

    ``out_dir`` is created if missing (its parent must exist). ``min_beat_time`` [s]:
    beats before it are not scored (mir_eval/MIREX use 5 s). ``min_bpm``, ``max_bpm``
    [BPM]: the tempo range searched on every track (a bound not given keeps the
    method's default). Tracks already scored for ``method`` are skipped, unless
    ``force``; tracks recorded with an error, or whose audio file (path or size) or
    annotation changed, are always re-run. With ``force`` the new rows are appended;
    once the run completes the record keeps the latest row of every track and drops
    this method's rows of tracks outside the run that were scored with other settings.
    Without ``force``, scored results of other settings in ``out_dir`` are refused.
    ``scheduler``, ``n_workers``, ``processes``: :func:`beatsync.cluster.dask_client`
    (an existing cluster's workers must see the audio at the same paths).
    ``progress(done, total=None)`` is called as groups of tracks finish.
    """
    from ..cluster import dask_client
    from ..validation import check_cluster_options, check_positive

    other_trackers.get(method)
    mbt = check_positive(min_beat_time, name="min_beat_time", unit="s", allow_zero=True)
    tempo = other_trackers.check_tempo_range(method, min_bpm, max_bpm)
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
    done, changed = set(), 0
    if not force:
        # only scored rows bind a resume: failed ones are re-run with today's settings
        scored = [r for r in previous.values() if r.get("status") == "ok"]
        other = sorted({r["min_beat_time"] for r in scored} - {mbt})
        if other:
            raise ParameterError(
                f"{str(log.path)!r} holds {method} results scored with --min-beat-time "
                f"{other[0]:g} s, not {mbt:g} s; use --force to re-run them or another --out"
            )
        ranges = {_recorded_range(method, (r.get("min_bpm"), r.get("max_bpm"))) for r in scored}
        other_range = sorted(ranges - {bpm_range}, key=str)
        if other_range:
            raise ParameterError(
                f"{str(log.path)!r} holds {method} results tracked with "
                f"{_range_text(other_range[0])}, not {_range_text(bpm_range)}; use --force "
                "to re-run them or another --out"
            )
        ok = [t for t in tracks if previous.get(t.key, {}).get("status") == "ok"]
        done = {t.key for t in ok if _same_inputs(previous[t.key], t, refs[t.key])}
        changed = len(ok) - len(done)
    todo = [t for t in tracks if t.key not in done]
    if method == "librosa" and tempo:
        _check_librosa_rates(todo, tempo)
    created = not out.exists()
    try:
        with contextlib.ExitStack() as stack:
            # the tracks' warnings.catch_warnings filters are process-wide: tracks on this
            # process's threads (processes=False) could leave them changed; restored here
            stack.enter_context(warnings.catch_warnings())
            if todo:  # connect first: an unreachable scheduler changes nothing on disk
                client = stack.enter_context(
                    dask_client(scheduler=scheduler, n_workers=n_workers, processes=processes)
                )
            out.mkdir(exist_ok=True)
            if todo:
                _run(client, todo, refs, log, method=method, mbt=mbt, tempo=tempo,
                     progress=progress)  # fmt: skip
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
    """Was ``row`` scored on this track's audio file (path and size) and annotation?"""
    stored = row.get("audio")
    if stored is not None and os.path.realpath(stored) != os.path.realpath(track.audio):
        return False  # (the same file given through another path is the same file)
    size = row.get("audio_bytes")
    if size is not None and size != _audio_bytes(track.audio):
        return False
    digest = row.get("reference_digest")
    return digest is None or digest == _reference_digest(reference)


def _row_settings(method: str, row: dict[str, Any]) -> tuple[Any, ...]:
    bounds = _recorded_range(method, (row.get("min_bpm"), row.get("max_bpm")))
    return (row.get("min_beat_time"), *bounds)


def _recorded_range(method: str, bounds: tuple[Any, Any]) -> tuple[float | None, float | None]:
    """A stored row's tempo range ``bounds`` as :func:`check_tempo_range` records it
    today (a bound equal to the default as ``None``)."""
    try:
        tempo = other_trackers.check_tempo_range(method, *bounds)
    except ParameterError:
        return bounds
    return (tempo.get("min_bpm"), tempo.get("max_bpm"))


def _range_text(bounds: tuple[float | None, float | None]) -> str:
    """``(None, None)`` -> "the default tempo range"; ``(60, None)`` -> "--min-bpm 60"."""
    names = ("--min-bpm", "--max-bpm")
    given = [f"{k} {v:g}" for k, v in zip(names, bounds, strict=True) if v is not None]
    return " and ".join(given) if given else "the default tempo range"


def _check_librosa_rates(tracks: Sequence[Track], tempo: dict[str, float]) -> None:
    """Refuse, before any work, a tempo range librosa cannot search at a track's rate
    (its tempi are lags of an onset autocorrelation: which exist depends on the rate).
    A file the client cannot open is left to its task, which records why it fails."""
    import soundfile as sf

    from ..beats.tracker import librosa_tempo_prior
    from ..validation import check_sample_rate

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


def _prepare_workers(client, method: str) -> None:
    """:func:`beatsync.other_trackers.prepare` on each worker in turn: workers compiling
    librosa's numba cache together can crash (a failure shows in the first track)."""
    if method != "librosa":
        return
    for address in client.nthreads():  # every worker
        with contextlib.suppress(Exception):
            client.run(other_trackers.prepare, method, workers=[address])


def _groups(todo: Sequence[Track], n_threads: int) -> list[list[Track]]:
    """The tracks in order, in groups of decreasing size, one task each (a Dask task
    costs about as much as tracking a short excerpt): the remaining tracks over the
    worker threads, at most :data:`GROUP_TRACKS` (guided self-scheduling), so that the
    workers finish together."""
    groups, i = [], 0
    while i < len(todo):
        size = min(GROUP_TRACKS, -(-(len(todo) - i) // max(1, n_threads)))
        groups.append(list(todo[i : i + size]))
        i += size
    return groups


def _longest_first(todo: Sequence[Track]) -> list[Track]:
    """The tracks by audio file size (for length), largest first: longest processing
    time first, so that the workers finish together."""

    return sorted(todo, key=lambda t: -(_audio_bytes(t.audio) or 0))


def _run(client, todo, refs, log, *, method, mbt, tempo, progress) -> None:
    from concurrent.futures import CancelledError

    from dask.distributed import KilledWorker, as_completed

    _prepare_workers(client, method)
    run = uuid.uuid4().hex
    numbers = itertools.count()

    def failed(t: Track, exc: BaseException) -> dict[str, Any]:
        # a task that failed outside evaluate_track (its worker died, or it was cancelled)
        return _failed_row(
            t.audio, refs[t.key], f"{type(exc).__name__}: {exc}", method=method,
            min_beat_time=mbt, name=t.key, group=t.group, min_bpm=tempo.get("min_bpm"),
            max_bpm=tempo.get("max_bpm"),
        )  # fmt: skip

    def submit(groups: list[list[Track]]) -> None:
        # in one call and with one key prefix, so that the scheduler sees the run's tasks
        # as one group and queues them in this order (worker-saturation)
        futs = client.map(
            evaluate_tracks,
            [[(str(t.audio), refs[t.key], t.key, t.group) for t in group] for group in groups],
            key=[f"evaluate-{method}-{run}-{next(numbers):06d}" for _ in groups],
            method=method,
            min_beat_time=mbt,
            **tempo,
        )
        for fut, group in zip(futs, groups, strict=True):
            futures[fut] = group
            queue.add(fut)

    futures: dict[Any, list[Track]] = {}
    queue = as_completed(loop=client.loop)
    submit(_groups(_longest_first(todo), sum(client.nthreads().values())))
    again: set[str] = set()  # tracks run alone a second time
    if progress is not None:
        progress(0, total=len(todo))
    done = 0
    try:
        for fut in queue:
            # released once read: a finished task's result would stay on its worker,
            # and Dask computes it again if that worker dies
            group = futures.pop(fut)
            try:
                rows = fut.result()
            except CancelledError as exc:  # cancelled outside the run, or the scheduler lost
                rows = [failed(t, exc) for t in group]
            except Exception as exc:  # a worker died (e.g. out of memory)
                if len(group) > 1:  # one track may be the cause: each alone, again
                    submit([[t] for t in group])
                    continue
                t = group[0]
                if not isinstance(exc, KilledWorker) and t.key not in again:
                    # not its own fault: it finished on a worker that another track then
                    # killed before its result was fetched; once more
                    again.add(t.key)
                    submit([[t]])
                    continue
                rows = [failed(t, exc)]
            log.append(*rows)  # in one write: an interrupt keeps the group or not at all
            done += len(rows)
            if progress is not None:
                progress(done)
    finally:
        # an interrupted run: the tracks still queued or in flight stop (one message)
        pending = [fut for fut in futures if not fut.done()]
        if pending:
            client.cancel(pending)
