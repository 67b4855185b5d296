"""The house rules of the package layout, checked on the source (issue: one layer each).

Layers, each importing only from its own layer or below: ``errors``/``units`` -> ``io``, ``motion``,
``rotations``, ``joints`` -> stages -> ``evaluate`` -> ``study`` and ``render`` ->
``commands``/``cli``. Synthetic generators (``synth``) are used by the study, tests
and benchmarks, never by a stage.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "beatsync"

#: top-level part of the package -> its layer (higher imports lower only)
LAYER = {
    "errors": 0,
    "validation": 0,
    "io": 1,
    "motion": 1,
    "rotations": 1,
    "quaternions": 0,
    "audio_resampling": 0,
    "joints": 1,
    "segment": 2,
    "beats": 2,
    "sync": 2,
    "motion_beats": 2,
    "music": 2,
    "graph": 2,
    "other_trackers": 2,
    "evaluate": 3,
    "synth": 3,
    "render": 4,
    "study": 5,
    "learn": 6,
    "datasets": 5,
    "cluster": 5,
    "sync_grid": 6,
    "runner": 6,
    "commands": 7,
    "cli": 8,
}
STAGES = {"segment", "beats", "sync", "motion_beats", "music", "graph"}
NEVER_FROM_STAGES = {"evaluate", "study", "synth", "render", "commands", "cli", "datasets"}


def _modules() -> list[Path]:
    return sorted(p for p in SRC.rglob("*.py"))


def _part(path: Path) -> str:
    rel = path.relative_to(SRC)
    return rel.parts[0].removesuffix(".py")


def _imported_parts(path: Path) -> set[str]:
    """Top-level beatsync parts imported by a module (absolute or relative imports)."""
    tree = ast.parse(path.read_text())
    rel = path.relative_to(SRC)
    package = list(rel.parts[:-1]) if rel.name != "__init__.py" else list(rel.parts[:-1])
    parts = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if node.module and node.module.split(".")[0] == "beatsync":
                    names = node.module.split(".")[1:]
                    if names:
                        parts.add(names[0])
                    else:
                        parts.update(a.name for a in node.names)
                continue
            base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
            target = base + (node.module.split(".") if node.module else [])
            if target:
                parts.add(target[0])
            else:  # from . import x at the package root
                parts.update(a.name for a in node.names)
        elif isinstance(node, ast.Import):
            for a in node.names:
                names = a.name.split(".")
                if names[0] == "beatsync" and len(names) > 1:
                    parts.add(names[1])
    return {p for p in parts if p in LAYER}


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(SRC)))
def test_imports_only_from_below(path):
    part = _part(path)
    if part not in LAYER:  # __init__ of the package, __main__
        return
    for other in _imported_parts(path) - {part}:
        assert LAYER[other] <= LAYER[part], f"{part} imports {other} from a layer above"
        if part in STAGES:
            assert other not in NEVER_FROM_STAGES, f"stage {part} imports {other}"
        if part == "evaluate":  # metrics on arrays: never runs a stage
            assert other not in STAGES, f"evaluate imports the stage {other}"


def test_every_part_has_a_layer():
    parts = {_part(p) for p in _modules()} - {"__init__", "__main__"}
    assert parts <= set(LAYER), sorted(parts - set(LAYER))
