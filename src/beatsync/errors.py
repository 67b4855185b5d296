"""Exceptions and warnings of beatsync.

Every check of user input raises :class:`ParameterError` (a :class:`ValueError` naming the
offending value and the likely mistake). Every :class:`BeatsyncWarning` goes through
:func:`warn`, so that :func:`collect_warnings` keeps one thread's warnings apart from
another's (a Dask worker's threads run several tracks at once; :mod:`warnings`' state is
process-wide).
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
    """The motion was not shown to be periodic (refused by the test, too short to tell, or
    no joint angles to test); its own motion beats can still sync it (``mode="beats"``,
    and ``mode="auto"`` falls back to them)."""


class BeatsyncWarning(UserWarning):
    """Degenerate but legal input (e.g. no beats to score): a defined result is returned."""


_local = threading.local()


def warn(message: str, *, stacklevel: int = 1) -> None:
    """Issue a :class:`BeatsyncWarning` (``stacklevel`` as for :func:`warnings.warn` called
    here), or record it if this thread collects them."""
    if getattr(_local, "silent", 0):
        return
    collected = getattr(_local, "collected", None)
    if collected is not None:
        collected.append(str(message))
        return
    warnings.warn(message, BeatsyncWarning, stacklevel=stacklevel + 1)


@contextlib.contextmanager
def collect_warnings() -> Iterator[list[str]]:
    """Record, in order, the :class:`BeatsyncWarning` messages this thread issues inside the
    block instead of issuing them, whatever the (process-wide) :mod:`warnings` filters say;
    blocks may nest. Only :func:`silenced` keeps one out of the record.
    """
    outer = getattr(_local, "collected", None)
    _local.collected = []
    try:
        yield _local.collected
    finally:
        _local.collected = outer


@contextlib.contextmanager
def silenced() -> Iterator[None]:
    """Drop the :class:`BeatsyncWarning` this thread issues inside the block (neither issued
    nor recorded; blocks may nest), for a step whose warning says nothing to its caller.
    """
    depth = getattr(_local, "silent", 0)
    _local.silent = depth + 1
    try:
        yield
    finally:
        _local.silent = depth
