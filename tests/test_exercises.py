"""The tutorials' exercises are proved both ways: every skeleton fails its check, every
solution passes it, and every check names a registered exercise.

A tutorial (``notebooks/tutorials/NN_*.ipynb``) pairs each code cell tagged ``exercise``
(a skeleton defining one name) with the next code cell, tagged ``check``, which is exactly
``learn.check("block.name", name)``. Its solutions are ``notebooks/tutorials/solutions/<stem>.py``.
"""

import ast
import functools
import re
from pathlib import Path

import nbformat
import pytest

from beatsync import learn

TUTORIALS = Path(__file__).resolve().parents[1] / "notebooks" / "tutorials"
CHECK = re.compile(r'learn\.check\("([a-z_]+\.[a-z0-9_]+)", ([A-Za-z_][A-Za-z0-9_]*)\)')


def _pairs(path):
    """(exercise source, exercise name, answer name) for each exercise cell of a tutorial."""
    cells = [c for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"]
    pairs = []
    for i, cell in enumerate(cells):
        if "exercise" not in cell.metadata.get("tags", []):
            continue
        after = cells[i + 1] if i + 1 < len(cells) else None
        assert after is not None and "check" in after.metadata.get("tags", []), (
            f"{path.name}: the exercise cell {i} is not followed by a cell tagged check"
        )
        m = CHECK.fullmatch(after.source.strip())
        assert m, f"{path.name}: not learn.check('block.name', name): {after.source!r}"
        pairs.append((cell.source, m.group(1), m.group(2)))
    return pairs


CASES = [
    pytest.param(path, src, name, answer, id=f"{path.stem}:{name}")
    for path in sorted(TUTORIALS.glob("*.ipynb"))
    for src, name, answer in _pairs(path)
]


@functools.cache
def _solutions(stem):
    solution = TUTORIALS / "solutions" / f"{stem}.py"
    ns = {"__name__": "solutions"}
    exec(compile(solution.read_text(), str(solution), "exec"), ns)
    return ns


def _defined(source):
    names = set()
    for node in ast.parse(source).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return names


def test_every_tutorial_has_exercises():
    for path in sorted(TUTORIALS.glob("*.ipynb")):
        assert _pairs(path), f"{path.name} has no exercise"
        solutions = TUTORIALS / "solutions" / f"{path.stem}.py"
        assert solutions.is_file(), f"{path.name} has no solutions"


@pytest.mark.parametrize(("path", "source", "name", "answer"), CASES)
def test_check_names_a_registered_exercise(path, source, name, answer):
    assert name in learn.exercises()
    assert _defined(source) == {answer}, "the exercise cell defines exactly the name checked"


@pytest.mark.parametrize(("path", "source", "name", "answer"), CASES)
def test_skeleton_fails_its_check(path, source, name, answer):
    ns = {}
    exec(compile(source, f"{path.name}:{name}", "exec"), ns)  # the cell alone, as a student gets it
    verdict = learn.check(name, ns[answer])
    assert not verdict and verdict.hint


@pytest.mark.parametrize(("path", "source", "name", "answer"), CASES)
def test_solution_passes_its_check(path, source, name, answer):
    verdict = learn.check(name, _solutions(path.stem)[answer])
    assert verdict, str(verdict)
