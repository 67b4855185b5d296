"""Exceptions and warnings of beatsync.

Every check of user input raises :class:`ParameterError`, a :class:`ValueError`
whose message names the offending value and the likely mistake (wrong units,
frames instead of seconds, an unreadable file, silence, a clip too short).
"""

from __future__ import annotations

__all__ = ["ParameterError", "BeatsyncWarning"]


class ParameterError(ValueError):
    """Malformed or unusable input: the message says which value and why."""


class BeatsyncWarning(UserWarning):
    """Degenerate but legal input (e.g. no beats to score): a defined result is returned."""
