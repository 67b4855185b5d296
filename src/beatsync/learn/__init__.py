"""Exercises that check themselves, for the tutorials in ``notebooks/tutorials/``.

A tutorial's exercise cell holds a skeleton for the student to fill in; the next cell
calls :func:`check` with the exercise's name and the answer. Each judge, registered
with :func:`exercise` in this package's module of its tutorial block, computes the
expected answer with the package itself and returns a hint that names the mismatch
(a shape, a unit, an index), never the solution.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["Verdict", "check", "exercise", "exercises"]

#: the modules that register exercises, one per tutorial block
_BLOCKS = ("segmentation", "beats", "resampling", "graphs", "dancers")

_REGISTRY: dict[str, Callable[[Any], str | None]] = {}


@dataclass(frozen=True)
class Verdict:
    """The outcome of one check: ``bool(verdict)`` is whether the answer is right."""

    name: str
    right: bool
    hint: str = ""

    def __bool__(self) -> bool:
        return self.right

    def __str__(self) -> str:
        if self.right:
            return f"{self.name}: right."
        return f"{self.name}: not yet. {self.hint}"

    def _repr_html_(self) -> str:
        colour = "#1a7f37" if self.right else "#b35900"
        mark = "&#10003;" if self.right else "&#10007;"
        return f'<p style="color:{colour}"><b>{mark}</b> {self}</p>'


def exercise(name: str) -> Callable[[Callable[[Any], str | None]], Callable[[Any], str | None]]:
    """Register ``judge(answer) -> None | hint`` as the check of exercise ``name``: None
    when the answer is right; an exception from the student's code becomes the hint."""

    def register(judge: Callable[[Any], str | None]) -> Callable[[Any], str | None]:
        _REGISTRY[name] = judge
        return judge

    return register


def exercises() -> list[str]:
    """The names of every registered exercise, sorted."""
    _load()
    return sorted(_REGISTRY)


def check(name: str, answer: Any) -> Verdict:
    """Judge ``answer`` to exercise ``name``; display the returned :class:`Verdict`."""
    _load()
    if name not in _REGISTRY:
        raise KeyError(f"no exercise named {name!r}; known: {', '.join(sorted(_REGISTRY))}")
    try:
        hint = _REGISTRY[name](answer)
    except NotImplementedError:
        hint = "the skeleton is not filled in yet."
    except Exception as exc:  # the student's code failed: say how, as the hint
        hint = f"your code raised {type(exc).__name__}: {exc}"
    return Verdict(name, hint is None, hint or "")


def _load() -> None:
    for block in _BLOCKS:
        try:
            importlib.import_module(f"{__name__}.{block}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{block}":
                raise
