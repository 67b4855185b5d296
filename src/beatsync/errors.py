"""Exceptions and warnings of beatsync.

Every check of user input raises :class:`ParameterError`, a :class:`ValueError`
whose message names the offending value and the likely mistake (wrong units,
frames instead of seconds, an unreadable file, silence, a clip too short).

Every :class:`BeatsyncWarning` is issued through :func:`warn`, so that
:func:`collect_warnings` can keep one thread's warnings apart from another's (the
threads of a Dask worker run several tracks at once; :func:`warnings.catch_warnings`
swaps process-wide state, and a warning could land on another track's record or be
lost).
"""

from __future__ import annotations

import contextlib
import threading
import warnings
from collections.abc import Iterator

__all__ = [
    "ParameterError",
    "NotPeriodicError",
    "BeatsyncWarning",
    "warn",
    "collect_warnings",
    "silenced",
]


class ParameterError(ValueError):
    """Malformed or unusable input: the message says which value and why."""


class NotPeriodicError(ParameterError):
    """The motion was not shown to be periodic: the periodicity test refused it, the clip
    is too short to tell, or its periods cannot be searched while its joints move (no
    joint angles to test). Its own motion beats can still sync it (``mode="beats"``, and
    ``mode="auto"`` falls back to them); other errors (bad settings, a dancer who does
    not move) cannot be helped that way."""


class BeatsyncWarning(UserWarning):
    """Degenerate but legal input (e.g. no beats to score): a defined result is returned."""


_local = threading.local()


def warn(message: str, *, stacklevel: int = 1) -> None:
    """Issue a :class:`BeatsyncWarning`, or record it if this thread collects them.

    ``stacklevel`` as for :func:`warnings.warn` called where this is called.
    """
    if getattr(_local, "silent", 0):
        return
    collected = getattr(_local, "collected", None)
    if collected is not None:
        collected.append(str(message))
        return
    warnings.warn(message, BeatsyncWarning, stacklevel=stacklevel + 1)


@contextlib.contextmanager
def collect_warnings() -> Iterator[list[str]]:
    """Record the messages of the :class:`BeatsyncWarning` this thread issues inside the
    block, in order, instead of issuing them (thread-safe; blocks may nest).

    Every one is recorded, whatever the :mod:`warnings` filters say: they are
    process-wide, and another thread's filters must not decide this thread's record.
    Code that expects a warning and has nothing to say about it drops it with
    :func:`silenced` (this thread's too), and then it is not recorded.
    """
    outer = getattr(_local, "collected", None)
    _local.collected = []
    try:
        yield _local.collected
    finally:
        _local.collected = outer


@contextlib.contextmanager
def silenced() -> Iterator[None]:
    """Drop the :class:`BeatsyncWarning` this thread issues inside the block: neither
    issued nor recorded by :func:`collect_warnings` (thread-safe; blocks may nest).

    For a step whose warning says nothing to its caller (no motion beats to count, a
    constant intensity to standardise). Unlike :func:`warnings.catch_warnings`, it
    leaves other threads' warnings alone.
    """
    depth = getattr(_local, "silent", 0)
    _local.silent = depth + 1
    try:
        yield
    finally:
        _local.silent = depth
