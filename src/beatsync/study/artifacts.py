"""One artefact layout for every notebook of the study.

``results/<notebook>/`` holds the notebook's tables as CSV, its figures as PNG and a
``params.json`` with the notebook name, the package version and the parameters the
notebook ran with. CSV floats are written with :data:`CSV_FLOAT_FORMAT` (6
significant digits), so that re-running the study on another machine (other BLAS,
other library versions) rewrites the same bytes unless a result really changed;
PNG figures carry no date or version metadata (:func:`beatsync.render.save_figure`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import __version__, io
from ..render import save_figure

__all__ = ["CSV_FLOAT_FORMAT", "write_artifacts", "results_folder"]

#: printf format of every float in a study CSV (documented precision: 6 significant digits).
CSV_FLOAT_FORMAT = "%.6g"


def results_folder(results_dir: str | Path) -> Path:
    """The study's results folder ``results_dir``; a relative one is taken from the
    repository's ``notebooks/`` folder (as the notebooks' ``"../results"``), whatever the
    current folder: that of the first folder, from the current one upwards, that holds
    ``notebooks/`` and ``pyproject.toml``, else of the checkout this package runs from,
    else the current folder itself."""
    path = Path(results_dir)
    if path.is_absolute():
        return path
    here = Path.cwd().resolve()
    checkout = Path(__file__).resolve().parents[3]  # src/beatsync/study/artifacts.py
    for root in [*[here, *here.parents], checkout]:
        if (root / "notebooks").is_dir() and (root / "pyproject.toml").is_file():
            return (root / "notebooks" / path).resolve()
    return path.resolve()


def write_artifacts(
    results_dir: str | Path,
    notebook: str,
    *,
    params: dict[str, Any],
    tables: dict[str, Any] | None = None,
    figures: dict[str, Any] | None = None,
    data: dict[str, Any] | None = None,
) -> list[Path]:
    """Write a notebook's artefacts under ``results_dir/notebook/`` (a relative
    ``results_dir`` is taken from the repository's ``notebooks/``, :func:`results_folder`):
    ``tables`` as ``<name>.csv`` (no index), ``figures`` as ``<name>.png``, ``data`` as
    ``<name>.json``, and ``params.json``; returns every file written."""
    out = results_folder(results_dir) / notebook
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, df in (tables or {}).items():
        written.append(io.write_csv(out / f"{name}.csv", df, float_format=CSV_FLOAT_FORMAT))
    for name, fig in (figures or {}).items():
        written.append(save_figure(fig, out / f"{name}.png"))
    for name, obj in (data or {}).items():
        written.append(io.write_json(out / f"{name}.json", obj))
    written.append(
        io.write_json(
            out / "params.json",
            {"notebook": notebook, "beatsync_version": __version__, "parameters": params},
        )
    )
    return written
