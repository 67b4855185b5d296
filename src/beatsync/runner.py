"""Run the study's notebooks with papermill from a parameter file.

A parameter file (``params/paper.yaml`` for the full study, ``params/ci.yaml`` for a
quick run) maps each notebook name (file stem in ``notebooks/``) to the parameters
it receives::

    paper_a_fig02_segmentation:
      n_trials: 20
      results_dir: ../results

Unlike papermill, which only warns, the runner refuses a parameter that the
notebook's ``parameters`` cell does not declare, a notebook that is missing, and a
notebook in ``notebooks/`` that the file does not list. Notebooks run with their own
folder as working directory. A manifest (``run_manifest.json``) records the
parameters, package version and time of every notebook.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import ParameterError

__all__ = ["load_params", "check_params", "planned_outputs", "run_notebooks", "NotebookRun"]

MANIFEST = "run_manifest.json"


@dataclass(frozen=True)
class NotebookRun:
    name: str
    output: Path
    parameters: dict[str, Any]
    seconds: float


def load_params(params_file: str | Path) -> dict[str, dict[str, Any]]:
    """Read a parameter file: a YAML mapping ``{notebook: {param: value}}``."""
    import yaml

    p = Path(params_file)
    if not p.is_file():
        raise ParameterError(f"parameter file {str(p)!r} does not exist")
    try:
        data = yaml.safe_load(p.read_text()) or {}
    except yaml.YAMLError as exc:
        raise ParameterError(f"parameter file {str(p)!r} is not valid YAML: {exc}") from None
    if not isinstance(data, dict) or not all(
        isinstance(v, dict) or v is None for v in data.values()
    ):
        raise ParameterError(
            f"parameter file {str(p)!r} must map notebook names to parameter mappings"
        )
    return {str(k): dict(v or {}) for k, v in data.items()}


def declared_parameters(notebook: Path) -> dict[str, Any]:
    """Parameters declared in the notebook's ``parameters`` cell (papermill's inspection)."""
    import papermill as pm

    try:
        return dict(pm.inspect_notebook(str(notebook)))
    except Exception as exc:
        raise ParameterError(f"cannot inspect notebook {str(notebook)!r}: {exc}") from None


def check_params(
    params: dict[str, dict[str, Any]], notebooks_dir: str | Path, *, only: list[str] | None = None
) -> dict[str, Path]:
    """Check the parameter mapping against the notebooks; return ``{name: path}`` to run.

    Raises
    ------
    ParameterError
        A listed notebook that does not exist, a notebook not listed, or a parameter
        a notebook does not declare.
    """
    nb_dir = Path(notebooks_dir)
    present = {p.stem: p for p in sorted(nb_dir.glob("*.ipynb"))}
    missing = sorted(set(params) - set(present))
    if missing:
        raise ParameterError(f"parameter file lists notebooks that do not exist: {missing}")
    unlisted = sorted(set(present) - set(params))
    if unlisted:
        raise ParameterError(
            f"notebooks {unlisted} are not listed in the parameter file; add them "
            "(with an empty mapping if they need no parameters)"
        )
    names = list(params)
    if only:
        unknown = sorted(set(only) - set(present))
        if unknown:
            raise ParameterError(f"unknown notebook(s) {unknown}; choose from {sorted(present)}")
        names = [n for n in names if n in only]
    for name in names:
        declared = declared_parameters(present[name])
        extra = sorted(set(params[name]) - set(declared))
        if extra:
            raise ParameterError(
                f"notebook {name!r} does not declare parameter(s) {extra}; it declares "
                f"{sorted(declared)} (check the spelling in the parameter file)"
            )
    return {n: present[n] for n in names}


def planned_outputs(
    todo: dict[str, Path], *, output_dir: str | Path | None = "results/notebooks", in_place: bool
) -> dict[str, Path]:
    """Where :func:`run_notebooks` writes each notebook of ``todo``, and its manifest.

    Returns ``{name: path}`` with the key ``MANIFEST`` for the manifest (not written
    ``in_place``).
    """
    if in_place:
        return dict(todo)
    out_dir = Path(output_dir or "results/notebooks")
    planned = {name: out_dir / path.name for name, path in todo.items()}
    planned[MANIFEST] = out_dir / MANIFEST
    return planned


def run_notebooks(
    params_file: str | Path,
    *,
    notebooks_dir: str | Path = "notebooks",
    output_dir: str | Path | None = "results/notebooks",
    only: list[str] | None = None,
    in_place: bool = False,
    progress: Callable[[str], None] | None = None,
    write_to: Callable[[Path], Path] | None = None,
) -> list[NotebookRun]:
    """Execute notebooks with papermill.

    Parameters
    ----------
    params_file : path
    notebooks_dir : path
    output_dir : path
        Where executed copies go (ignored with ``in_place``); created if missing.
    only : list of str, optional
        Run only these notebooks.
    in_place : bool
        Overwrite the notebooks themselves with their executed versions (used to
        refresh the committed, CI-parameter notebooks).
    progress : callable, optional
        Called with a line of text before and after each notebook.
    write_to : callable, optional
        Maps each destination of :func:`planned_outputs` to the file actually written
        (a command writing all-or-nothing passes its staging paths); default: the
        destination itself. A notebook that fails is kept, with its traceback cells,
        as ``<name>.failed.ipynb`` next to its destination.
    """
    import nbformat
    import papermill as pm

    from . import __version__
    from .io import atomic_write, write_json

    params = load_params(params_file)
    todo = check_params(params, notebooks_dir, only=only)
    nb_dir = Path(notebooks_dir).resolve()
    planned = planned_outputs(todo, output_dir=output_dir, in_place=in_place)
    if not in_place:
        Path(output_dir or "results/notebooks").mkdir(parents=True, exist_ok=True)
    target = write_to or (lambda p: p)
    runs: list[NotebookRun] = []
    for name, path in todo.items():
        dest = planned[name].resolve()
        if progress:
            progress(f"running {name} ...")
        start = time.perf_counter()
        tmp = dest.with_name(f".{dest.name}.running.ipynb")
        try:
            pm.execute_notebook(
                str(path),
                str(tmp),
                parameters=params[name],
                cwd=str(nb_dir),
                progress_bar=False,
                report_mode=False,
            )
        except Exception:
            # keep the executed notebook with its traceback cells for the user to read
            failed = dest.with_name(f"{dest.stem}.failed.ipynb")
            if tmp.exists():
                os.replace(tmp, failed)
                if progress:
                    progress(f"  {name} FAILED; executed notebook kept in {failed}")
            raise
        except BaseException:  # Ctrl-C, SIGTERM: leave nothing behind
            tmp.unlink(missing_ok=True)
            raise
        executed = nbformat.read(tmp, as_version=4)
        executed.metadata.setdefault("papermill", {})["output_path"] = dest.name
        with atomic_write(target(planned[name])) as fh:
            nbformat.write(executed, fh)
        tmp.unlink(missing_ok=True)
        seconds = time.perf_counter() - start
        runs.append(NotebookRun(name, planned[name], params[name], seconds))
        if progress:
            progress(f"  {name} done in {seconds:.1f} s -> {planned[name]}")
    if MANIFEST in planned:
        write_json(
            target(planned[MANIFEST]),
            {
                "beatsync_version": __version__,
                "params_file": str(params_file),
                "notebooks": [
                    {"name": r.name, "parameters": r.parameters, "seconds": round(r.seconds, 1)}
                    for r in runs
                ],
            },
        )
    return runs
