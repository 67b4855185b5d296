"""Run the study's notebooks with papermill from a parameter file (``beatsync reproduce``).

A parameter file (``params/paper.yaml``, or ``params/ci.yaml`` for a quick run) maps each
notebook name (file stem in ``notebooks/``) to its parameters, e.g.
``paper_a_fig02_segmentation: {n_trials: 20}``. Unlike papermill, which only warns, the
runner refuses an undeclared parameter, a missing notebook and an unlisted one. Each
notebook runs in its own folder with one BLAS/OpenMP thread unless the caller set one
(a threaded BLAS sums in an order that depends on the thread count, and the artefacts
must not depend on the machine), in a process of its own (``python -m beatsync.runner``),
``jobs`` at a time, the longest first (by the previous manifest, ``run_manifest.json``,
which records each notebook's parameter file, parameters and time).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import ParameterError

__all__ = ["load_params", "check_params", "planned_outputs", "run_notebooks", "default_jobs"]

MANIFEST = "run_manifest.json"

#: Environment variables that set the BLAS/OpenMP thread count of a kernel.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


class NotebookFailed(RuntimeError):
    """A notebook raised an error in one of its cells (its name and message are kept)."""


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
    if not isinstance(data, dict) or not all(isinstance(v, dict | None) for v in data.values()):
        raise ParameterError(f"parameter file {str(p)!r} must map notebook names to mappings")
    return {str(k): dict(v or {}) for k, v in data.items()}


def check_params(
    params: dict[str, dict[str, Any]], notebooks_dir: str | Path, *, only: list[str] | None = None
) -> dict[str, Path]:
    """Check the parameter mapping against the notebooks (each listed, present and
    declaring its parameters); return ``{name: path}`` to run."""
    import papermill as pm

    present = {p.stem: p for p in sorted(Path(notebooks_dir).glob("*.ipynb"))}
    missing, unlisted = sorted(set(params) - set(present)), sorted(set(present) - set(params))
    if missing:
        raise ParameterError(f"parameter file lists notebooks that do not exist: {missing}")
    if unlisted:
        raise ParameterError(
            f"notebooks {unlisted} are not listed in the parameter file; add them "
            "(with an empty mapping if they need no parameters)"
        )
    unknown = sorted(set(only or ()) - set(present))
    if unknown:
        raise ParameterError(f"unknown notebook(s) {unknown}; choose from {sorted(present)}")
    names = [n for n in params if not only or n in only]
    for name in names:
        try:
            declared = pm.inspect_notebook(str(present[name]))
        except Exception as exc:  # not a notebook (JSON, nbformat)
            raise ParameterError(f"cannot read notebook {str(present[name])!r}: {exc}") from None
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
    """Where :func:`run_notebooks` writes each notebook (and, not ``in_place``, the
    manifest)."""
    if in_place:
        return dict(todo)
    out_dir = Path(output_dir or "results/notebooks")
    return {**{n: out_dir / p.name for n, p in todo.items()}, MANIFEST: out_dir / MANIFEST}


def default_jobs(n_notebooks: int | None = None) -> int:
    """Notebooks run at once by default: the usable CPUs, at most 4 (and ``n_notebooks``)."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, min(cpus or 1, 4, n_notebooks or 4))


def run_notebooks(
    params_file: str | Path,
    *,
    notebooks_dir: str | Path = "notebooks",
    output_dir: str | Path | None = "results/notebooks",
    only: list[str] | None = None,
    in_place: bool = False,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
    write_to: Callable[[Path], Path] | None = None,
) -> list[NotebookRun]:
    """Execute the notebooks of ``params_file`` with papermill into ``output_dir``
    (created if missing, with the manifest), or ``in_place``.

    ``progress`` gets a line of text before and after each notebook; ``write_to`` maps
    each destination of :func:`planned_outputs` to the file actually written (a command's
    staging paths). A notebook that fails is kept as ``<name>.failed.ipynb`` beside its
    destination (for its traceback cells) and raises :class:`NotebookFailed`.
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ParameterError(f"jobs={jobs!r}: run a whole number >= 1 of notebooks at once")
    params = load_params(params_file)
    todo = check_params(params, notebooks_dir, only=only)
    planned = planned_outputs(todo, output_dir=output_dir, in_place=in_place)
    target = write_to or (lambda p: p)
    out_dir = None if in_place else planned[MANIFEST].parent
    previous = _manifest(out_dir)
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    order = sorted(todo, key=lambda n: -previous.get(n, {}).get("seconds", 0.0))
    specs = {
        name: {
            "notebook": str(todo[name].resolve()),
            "parameters": params[name],
            "dest": str(planned[name].resolve()),
            "write_to": str(target(planned[name]).resolve()),
        }
        for name in order
    }
    seconds = _run_all(specs, jobs, progress)
    runs = [NotebookRun(n, planned[n], params[n], seconds[n]) for n in todo]
    if out_dir is not None:
        from . import __version__
        from .io import write_json

        entries = {n: e for n, e in previous.items() if (out_dir / f"{n}.ipynb").is_file()}
        for r in runs:
            entries[r.name] = {
                "name": r.name,
                "params_file": str(params_file),
                "parameters": r.parameters,
                "seconds": round(r.seconds, 1),
            }
        manifest = {
            "beatsync_version": __version__,
            "params_file": str(params_file),
            "notebooks": [entries[n] for n in params if n in entries],
        }
        write_json(target(planned[MANIFEST]), manifest)
    return runs


def _manifest(out_dir: Path | None) -> dict[str, dict[str, Any]]:
    """The previous manifest's entries by notebook (none if there is no readable one)."""
    if out_dir is not None:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            entries = json.loads((out_dir / MANIFEST).read_text())["notebooks"]
            return {str(e["name"]): e for e in entries}
    return {}


def _run_all(specs: dict[str, dict[str, Any]], jobs: int, progress: Any) -> dict[str, float]:
    """Run the notebooks of ``specs`` in order, ``jobs`` at a time in worker processes
    (:func:`_worker_main`); their times [s]. A failure or an interruption stops the others."""
    say = progress or (lambda line: None)
    seconds: dict[str, float] = {}
    pending, running = list(specs), {}
    try:
        while pending or running:
            while pending and len(running) < jobs:
                name = pending.pop(0)
                log = tempfile.TemporaryFile()  # noqa: SIM115 (closed below)
                command = [sys.executable, "-m", "beatsync.runner", name, json.dumps(specs[name])]
                env = {**dict.fromkeys(THREAD_VARIABLES, "1"), **os.environ}  # one unless set
                proc = subprocess.Popen(command, stdout=log, stderr=log, env=env)
                running[name] = (proc, log, time.perf_counter())
                say(f"running {name} ...")
            time.sleep(0.1)
            for name, (proc, log, start) in list(running.items()):
                if proc.poll() is None:
                    continue
                del running[name]
                log.seek(0)
                text = log.read().decode(errors="replace").strip()
                log.close()
                if proc.returncode:  # its message comes after what the kernel printed
                    found = text.find(f"notebook {name!r} failed")
                    tail = text[found:] if found >= 0 else f"failed:\n{text[-2000:]}"
                    raise NotebookFailed(tail if found >= 0 else f"notebook {name!r} {tail}")
                seconds[name] = time.perf_counter() - start
                say(f"  {name} done in {seconds[name]:.1f} s -> {specs[name]['dest']}")
    finally:
        for proc, _, _ in running.values():
            proc.send_signal(signal.SIGTERM)
        for proc, log, _ in running.values():
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()  # it could not delete its running copy
                proc.wait()
            log.close()
        for name in running:
            _running_copy(Path(specs[name]["dest"])).unlink(missing_ok=True)
    return seconds


def _running_copy(dest: Path) -> Path:
    """Where papermill writes a notebook while it runs (hidden, beside ``dest``)."""
    return dest.with_name(f".{dest.name}.running.ipynb")


def _execute(name: str, notebook: str, parameters: dict, dest: str, write_to: str) -> None:
    """Run one notebook into ``write_to`` (a failed run kept as ``<dest>.failed.ipynb``).

    The kernel talks over Unix sockets in a private folder (over TCP any local process
    could reach it); TCP on Windows and where that path is too long for a socket.
    """
    import nbformat
    import papermill as pm
    from traitlets.config import Config

    from .io import atomic_write

    tmp = _running_copy(Path(dest))
    folder = tempfile.mkdtemp(prefix="beatsync-kernel-")  # mode 0700
    ip = os.path.join(folder, "kernel")
    ipc = os.name == "posix" and len(os.fsencode(ip)) + len("-65535") < 104  # sun_path
    try:  # Ctrl-C, SIGTERM at any point: the running copy is removed (finally)
        try:
            pm.execute_notebook(
                notebook,
                str(tmp),
                parameters=parameters,
                cwd=str(Path(notebook).parent),
                progress_bar=False,
                **(
                    {"config": Config({"KernelManager": {"transport": "ipc", "ip": ip}})}
                    if ipc
                    else {}
                ),
            )
        except Exception as exc:
            if tmp.exists():  # kept for its traceback cells
                os.replace(tmp, Path(dest).with_name(f"{Path(dest).stem}.failed.ipynb"))
            raise NotebookFailed(f"notebook {name!r} failed:\n{str(exc).strip()}") from None
        executed = nbformat.read(tmp, as_version=4)
        meta = executed.metadata.setdefault("papermill", {})
        # paths relative to the repository, not this machine's
        meta["input_path"] = f"{Path(notebook).parent.name}/{Path(notebook).name}"
        meta["output_path"] = Path(dest).name
        with atomic_write(write_to) as fh:
            nbformat.write(executed, fh)
    finally:
        tmp.unlink(missing_ok=True)
        shutil.rmtree(folder, ignore_errors=True)


def _worker_main(argv: list[str]) -> int:
    """``python -m beatsync.runner NAME SPEC_JSON``: run one notebook (a worker); SIGTERM
    and SIGHUP become KeyboardInterrupt, so that papermill shuts the kernel down."""

    def stop(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, stop)
    try:
        _execute(argv[0], **json.loads(argv[1]))
    except NotebookFailed as exc:
        print(exc, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(_worker_main(sys.argv[1:]))
