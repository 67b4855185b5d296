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
parameter file, parameters, package version and time of every notebook in the output
folder: a run of some notebooks (``only``) keeps the entries of the others.

Every kernel runs with one BLAS/OpenMP thread (unless the caller set
``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` or ``MKL_NUM_THREADS``): a threaded BLAS
sums in an order that depends on the thread count, and one result of the study (a
composition's search) moved in its third digit between one and two threads. So the
artefacts do not depend on the machine's core count. With ``jobs`` > 1 the notebooks
run side by side, each in a worker process of its own (``python -m beatsync.runner``),
the longest first (by the previous manifest's times); the notebooks write separate
artefact folders, so the order changes nothing but the wall time. A failing notebook
stops the others; an interruption (Ctrl-C, SIGTERM) is passed on to the workers, which
shut their kernels down and delete their partial output.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import ParameterError

__all__ = [
    "load_params",
    "check_params",
    "planned_outputs",
    "run_notebooks",
    "default_jobs",
    "usable_cpus",
    "kernel_env",
    "NotebookRun",
    "NotebookFailed",
]

MANIFEST = "run_manifest.json"

#: Longest Unix socket path, in bytes, on every system we run on (``sun_path`` holds
#: 108 bytes on Linux, 104 on macOS and the BSDs, with the closing NUL).
MAX_SOCKET_PATH = 103


#: Environment variables that set the BLAS/OpenMP thread count of a kernel.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


class NotebookFailed(RuntimeError):
    """A notebook raised an error in one of its cells (its message is kept)."""


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


def usable_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def default_jobs(n_notebooks: int | None = None) -> int:
    """Notebooks to run at once by default: the usable CPUs, at most 4 (and ``n_notebooks``)."""
    jobs = max(1, min(usable_cpus(), 4))
    return min(jobs, n_notebooks) if n_notebooks else jobs


def _check_jobs(jobs: Any) -> int:
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ParameterError(
            f"jobs={jobs!r}: the number of notebooks run at once must be a whole number >= 1"
        )
    return jobs


def _execute(
    path: Path, parameters: dict[str, Any], nb_dir: Path, dest: Path, write_to: Path
) -> None:
    """Run one notebook into ``write_to``; a failed run is kept as ``<dest>.failed.ipynb``."""
    import nbformat
    import papermill as pm

    from .io import atomic_write

    tmp = _running_copy(dest)
    try:  # Ctrl-C, SIGTERM at any point: the running copy is removed (finally)
        try:
            with _kernel_transport() as transport:
                pm.execute_notebook(
                    str(path),
                    str(tmp),
                    parameters=parameters,
                    cwd=str(nb_dir),
                    progress_bar=False,
                    report_mode=False,
                    **transport,
                )
        except Exception:
            # keep the executed notebook with its traceback cells for the user to read
            if tmp.exists():
                os.replace(tmp, dest.with_name(f"{dest.stem}.failed.ipynb"))
            raise
        executed = nbformat.read(tmp, as_version=4)
        executed.metadata.setdefault("papermill", {})["output_path"] = dest.name
        with atomic_write(write_to) as fh:
            nbformat.write(executed, fh)
    finally:
        tmp.unlink(missing_ok=True)


def _running_copy(dest: Path) -> Path:
    """Where papermill writes a notebook while it runs (hidden, beside ``dest``)."""
    return dest.with_name(f".{dest.name}.running.ipynb")


@contextlib.contextmanager
def _kernel_transport() -> Iterator[dict[str, Any]]:
    """Papermill options for a kernel that talks to the runner over Unix sockets.

    Over TCP, every kernel warns on stderr that it runs without encryption, and any
    local process could reach its ports (the messages are signed, not hidden). The
    sockets are made in a private temporary folder of this kernel's own (Jupyter's
    default, ``kernel-ipc`` in the working folder, is shared by notebooks run side by
    side, whose kernels then answer each other), removed afterwards. TCP where that is
    not possible: on Windows (no Unix sockets), and under a temporary folder
    (``TMPDIR``) too long for a socket path (:data:`MAX_SOCKET_PATH`).
    """
    if os.name != "posix":
        yield {}
        return
    import shutil

    from traitlets.config import Config

    folder = tempfile.mkdtemp(prefix="beatsync-kernel-")  # mode 0700
    try:
        ip = os.path.join(folder, "kernel")
        if len(os.fsencode(ip)) + len("-65535") > MAX_SOCKET_PATH:
            yield {}
        else:
            yield {"config": Config({"KernelManager": {"transport": "ipc", "ip": ip}})}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _previous_entries(output_dir: Path | None) -> list[dict[str, Any]]:
    """The notebook entries of the previous manifest of ``output_dir`` (none if there is
    no readable manifest; an entry without a name or time is dropped). An entry without
    its own parameter file or version (written before entries had them) gets the
    manifest's."""
    if output_dir is None:
        return []
    try:
        data = json.loads((output_dir / MANIFEST).read_text())
        entries = [dict(n) for n in data["notebooks"]]
        shared = {k: data[k] for k in ("params_file", "beatsync_version") if k in data}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return []
    out = []
    for n in entries:
        try:
            n["name"], n["seconds"] = str(n["name"]), float(n["seconds"])
        except (KeyError, TypeError, ValueError):
            continue
        out.append({"name": n["name"], **shared, **n})
    return out


def _previous_seconds(output_dir: Path | None) -> dict[str, float]:
    """Each notebook's time in the previous manifest of ``output_dir`` (empty if none)."""
    return {n["name"]: n["seconds"] for n in _previous_entries(output_dir)}


def _manifest_entries(
    runs: list[NotebookRun], params: dict[str, Any], params_file: str, output_dir: Path
) -> list[dict[str, Any]]:
    """This run's notebooks, and the previous manifest's entries of the notebooks it did
    not run whose executed copy is still in ``output_dir`` (``--only``): the manifest
    describes every notebook there. Each entry names its parameter file and version."""
    from . import __version__

    mine = {
        r.name: {
            "name": r.name,
            "params_file": params_file,
            "beatsync_version": __version__,
            "parameters": r.parameters,
            "seconds": round(r.seconds, 1),
        }
        for r in runs
    }
    kept = {
        n["name"]: n
        for n in _previous_entries(output_dir)
        if n["name"] not in mine and (output_dir / f"{n['name']}.ipynb").is_file()
    }
    both = {**kept, **mine}
    order = [name for name in params if name in both]  # the parameter file's order
    order += [name for name in kept if name not in order]
    return [both[name] for name in order]


def kernel_env() -> dict[str, str]:
    """The environment notebook kernels run with: ours, one BLAS thread unless set."""
    env = dict(os.environ)
    for var in THREAD_VARIABLES:
        env.setdefault(var, "1")
    return env


@contextlib.contextmanager
def _environment(env: dict[str, str]) -> Iterator[None]:
    """Set ``os.environ`` to ``env`` while the block runs (kernels inherit it)."""
    saved = dict(os.environ)
    os.environ.update(env)
    try:
        yield
    finally:
        for key in set(os.environ) - set(saved):
            del os.environ[key]
        os.environ.update(saved)


def _run_parallel(
    todo: dict[str, Path],
    params: dict[str, dict[str, Any]],
    nb_dir: Path,
    dests: dict[str, Path],
    targets: dict[str, Path],
    jobs: int,
    order: list[str],
    progress: Callable[[str], None] | None,
) -> dict[str, float]:
    """Run the notebooks of ``todo`` in up to ``jobs`` worker processes; return their times."""
    seconds: dict[str, float] = {}
    pending = list(order)
    running: dict[str, tuple[subprocess.Popen[bytes], float, Path, Any]] = {}
    env = kernel_env()
    with tempfile.TemporaryDirectory(prefix="beatsync-runner-") as scratch:
        try:
            while pending or running:
                while pending and len(running) < jobs:
                    name = pending.pop(0)
                    spec = {
                        "name": name,
                        "notebook": str(todo[name].resolve()),
                        "parameters": params[name],
                        "cwd": str(nb_dir),
                        "dest": str(dests[name]),
                        "write_to": str(targets[name].resolve()),
                    }
                    result = Path(scratch) / f"{name}.result.json"
                    log = open(Path(scratch) / f"{name}.log", "wb")  # noqa: SIM115
                    proc = subprocess.Popen(
                        [sys.executable, "-m", "beatsync.runner", json.dumps(spec), str(result)],
                        stdin=subprocess.DEVNULL,
                        stdout=log,
                        stderr=subprocess.STDOUT,
                        env=env,
                    )
                    running[name] = (proc, time.perf_counter(), result, log)
                    if progress:
                        progress(f"running {name} ...")
                time.sleep(0.1)
                for name, (proc, start, result, log) in list(running.items()):
                    if proc.poll() is None:
                        continue
                    del running[name]
                    log.close()
                    if proc.returncode != 0:
                        raise NotebookFailed(_failure_text(name, result, Path(log.name)))
                    seconds[name] = time.perf_counter() - start
                    if progress:
                        progress(f"  {name} done in {seconds[name]:.1f} s -> {dests[name]}")
        finally:
            _stop_workers([(p, lg) for p, _, _, lg in running.values()])
            for name in running:  # a worker killed after the grace time could not clean up
                _running_copy(dests[name]).unlink(missing_ok=True)
    return seconds


def _failure_text(name: str, result: Path, log: Path) -> str:
    try:
        return f"notebook {name!r} failed:\n{json.loads(result.read_text())['error'].strip()}"
    except (OSError, ValueError, KeyError):
        tail = log.read_text(errors="replace").strip().splitlines()[-20:]
        return f"notebook {name!r} failed; its worker printed:\n" + "\n".join(tail)


def _stop_workers(workers: list[tuple[subprocess.Popen[bytes], Any]]) -> None:
    """Ask the running workers to stop (they shut their kernels down), then make sure."""
    for proc, _ in workers:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + 20.0
    for proc, log in workers:
        try:
            proc.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


def _run_in_process(
    todo: dict[str, Path],
    params: dict[str, dict[str, Any]],
    nb_dir: Path,
    dests: dict[str, Path],
    planned: dict[str, Path],
    target: Callable[[Path], Path],
    progress: Callable[[str], None] | None,
) -> dict[str, float]:
    """Run the notebooks of ``todo`` one after the other in this process; their times."""
    seconds: dict[str, float] = {}
    for name, path in todo.items():
        if progress:
            progress(f"running {name} ...")
        start = time.perf_counter()
        try:
            _execute(path, params[name], nb_dir, dests[name], target(planned[name]))
        except Exception:
            if progress:
                progress(f"  {name} FAILED; executed notebook kept next to {dests[name]}")
            raise
        seconds[name] = time.perf_counter() - start
        if progress:
            progress(f"  {name} done in {seconds[name]:.1f} s -> {planned[name]}")
    return seconds


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
    jobs : int
        Notebooks run at once (1: one after the other, in this process; more: in
        worker processes, see the module docstring; :func:`default_jobs` suggests one).
    progress : callable, optional
        Called with a line of text before and after each notebook.
    write_to : callable, optional
        Maps each destination of :func:`planned_outputs` to the file actually written
        (a command writing all-or-nothing passes its staging paths); default: the
        destination itself. A notebook that fails is kept, with its traceback cells,
        as ``<name>.failed.ipynb`` next to its destination.

    Raises
    ------
    NotebookFailed
        With ``jobs`` > 1, a notebook that raised (with ``jobs`` = 1 papermill's own
        error is raised).
    """
    from . import __version__
    from .io import write_json

    jobs = _check_jobs(jobs)
    params = load_params(params_file)
    todo = check_params(params, notebooks_dir, only=only)
    nb_dir = Path(notebooks_dir).resolve()
    planned = planned_outputs(todo, output_dir=output_dir, in_place=in_place)
    out_dir = None if in_place else Path(output_dir or "results/notebooks")
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    target = write_to or (lambda p: p)
    dests = {name: planned[name].resolve() for name in todo}
    if jobs > 1 and len(todo) > 1:
        before = _previous_seconds(out_dir)
        order = sorted(todo, key=lambda n: -before.get(n, 0.0))  # longest first (stable)
        targets = {name: target(planned[name]) for name in todo}
        seconds = _run_parallel(todo, params, nb_dir, dests, targets, jobs, order, progress)
    else:
        with _environment(kernel_env()):
            seconds = _run_in_process(todo, params, nb_dir, dests, planned, target, progress)
    runs = [NotebookRun(n, planned[n], params[n], seconds[n]) for n in todo]
    if MANIFEST in planned:
        assert out_dir is not None
        write_json(
            target(planned[MANIFEST]),
            {
                "beatsync_version": __version__,
                "params_file": str(params_file),
                "notebooks": _manifest_entries(runs, params, str(params_file), out_dir),
            },
        )
    return runs


def _worker_main(argv: list[str]) -> int:
    """``python -m beatsync.runner SPEC_JSON RESULT_FILE``: run one notebook (a worker).

    SIGTERM and SIGHUP become KeyboardInterrupt, so papermill shuts the kernel down
    and the partial output is deleted. The error of a failed notebook is written to
    ``RESULT_FILE`` as ``{"error": text}``.
    """

    def stop(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, stop)
    spec, result = json.loads(argv[0]), Path(argv[1])
    try:
        _execute(
            Path(spec["notebook"]),
            spec["parameters"],
            Path(spec["cwd"]),
            Path(spec["dest"]),
            Path(spec["write_to"]),
        )
    except Exception as exc:
        result.write_text(json.dumps({"error": str(exc) or type(exc).__name__}))
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(_worker_main(sys.argv[1:]))
