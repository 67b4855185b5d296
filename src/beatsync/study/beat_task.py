"""One track of a dataset run read, tracked and scored, on a Dask worker.

:func:`evaluate_tracks` (:func:`evaluate_track` on a group of tracks) is the task of
:func:`beatsync.study.beat_dataset.evaluate_dataset` (``beatsync evaluate beats``);
:func:`evaluate_track` is re-exported there. It lives apart from that module, whose
tables need pandas, so that a worker imports only what a track needs: pandas took
0.6 s of each worker's first track.
"""

from __future__ import annotations

import hashlib
import os
import time
import warnings
from typing import Any

import numpy as np

from .. import io, peers
from ..errors import ParameterError, collect_warnings
from ..evaluate.beats import evaluate, tempo_octave

__all__ = ["evaluate_track", "evaluate_tracks", "failed_row", "reference_digest"]


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
    """Track one audio file and score it; a failure becomes the row's ``error``.

    Run by :func:`evaluate_tracks`, the task of :func:`~.beat_dataset.evaluate_dataset`
    (on a Dask worker); never raises for a bad track (unreadable, silent, too short),
    so one track cannot stop a run.

    Parameters
    ----------
    audio : str
        Audio file path (valid on the worker).
    reference : np.ndarray [s]
        Annotated beats (:func:`~.beat_tracks.read_annotation`).
    method : str
        A name of :data:`beatsync.peers.PEERS`.
    min_beat_time : float >= 0 [s]
    name : str
        The track's key (:attr:`~.beat_tracks.Track.key`), recorded as ``key``.
    group : str
        The track's folder (:attr:`~.beat_tracks.Track.group`).
    min_bpm, max_bpm : float, optional [BPM]
        The tempo range searched (:func:`beatsync.peers.check_tempo_range`); ``None``:
        the method's default. Recorded as checked (a bound equal to the default as
        ``None``); a range the method refuses is the row's ``error``.

    Returns
    -------
    dict
        ``key, group, audio, audio_bytes`` (its size, None if unreadable),
        ``reference_digest`` (:func:`reference_digest`), ``method, min_beat_time,
        min_bpm, max_bpm, status`` (``"ok"`` or ``"error"``), ``error``, ``warning``
        (the tracker's or scorer's warnings),
        ``n_ref, n_est, tempo_ref, tempo_est, octave``, every metric of
        :data:`~beatsync.evaluate.beats.METRICS`, ``seconds`` (reading and tracking
        time), ``audio_seconds`` and ``beats`` (the estimated times).
    """
    row = failed_row(
        audio, reference, "", method=method, min_beat_time=min_beat_time, name=name,
        group=group, min_bpm=min_bpm, max_bpm=max_bpm,
    )  # fmt: skip
    t0 = time.perf_counter()
    try:
        tempo = peers.check_tempo_range(method, min_bpm, max_bpm)
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
            est = peers.track(method, y, sr, **tempo)
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


def failed_row(
    audio: str | os.PathLike[str],
    reference: np.ndarray,
    error: str,
    *,
    method: str,
    min_beat_time: float,
    name: str,
    group: str,
    min_bpm: float | None,
    max_bpm: float | None,
) -> dict[str, Any]:
    """A track's row with its inputs and settings, ``status`` "error" and ``error``:
    where :func:`evaluate_track` starts, and the row of a task that failed outside it."""
    return {
        "key": name,
        "group": group,
        "audio": str(audio),
        "audio_bytes": _audio_bytes(audio),
        "reference_digest": reference_digest(reference),
        "method": method,
        "min_beat_time": float(min_beat_time),
        "min_bpm": min_bpm,
        "max_bpm": max_bpm,
        "status": "error",
        "error": error,
        "warning": "",
    }


def evaluate_tracks(
    items: list[tuple[str, np.ndarray, str, str]], **settings: Any
) -> list[dict[str, Any]]:
    """:func:`evaluate_track` on each ``(audio, reference, name, group)`` in turn: one
    task for several short tracks (see :func:`~.beat_dataset.evaluate_dataset`)."""
    return [
        evaluate_track(audio, reference, name=name, group=group, **settings)
        for audio, reference, name, group in items
    ]


def _dataset_hint(message: str) -> str:
    """A tracker's warning with the advice a dataset run can follow (it has no --bpm)."""
    from ..beats.tracker import KNOWN_TEMPO_HINT

    return message.replace(
        KNOWN_TEMPO_HINT, "a tempo range (--min-bpm, --max-bpm) narrows the search"
    )


def reference_digest(reference: np.ndarray) -> str:
    """A short digest of an annotation's beat times (a row records the one it was scored
    against; a resume re-runs a track whose annotation changed since)."""
    data = np.ascontiguousarray(np.asarray(reference, dtype=np.float64)).tobytes()
    return hashlib.sha256(data).hexdigest()[:16]


def _audio_bytes(path: str | os.PathLike[str]) -> int | None:
    try:
        return os.stat(path).st_size
    except OSError:
        return None
