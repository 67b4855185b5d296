"""What every subcommand shares: options, input and output checks, feedback, errors.

Outputs are all-or-nothing per command (:class:`Outputs`): every output file is
declared and checked before any work (a folder, a non-regular file, a read-only file,
an input file, a missing or unwritable folder, two options naming one file are
refused), written into a hidden staging folder next to its destination
(``.beatsync-tmp-*``) and renamed into place only when the whole command succeeded.
An error, Ctrl-C (SIGINT), SIGTERM or SIGHUP removes the staging folders, so nothing
is left behind; the files that existed before keep their content.

Feedback goes to stderr (:class:`Feedback`): a tqdm bar per step a user waits for,
only when stderr is a terminal, silenced by ``--quiet``; library code receives it as
an optional ``progress(done, total)`` callable and never imports tqdm.

This module imports nothing heavy at import time (no numpy), so that ``beatsync
--help`` and the start of every subcommand stay fast.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import stat
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, TextIO

from ..errors import ParameterError

__all__ = [
    "EXIT_OK",
    "EXIT_FAILED_ITEMS",
    "EXIT_USAGE",
    "EXIT_BAD_INPUT",
    "EXIT_OS_ERROR",
    "EXIT_INTERNAL",
    "STAGING_PREFIX",
    "ProgressCallback",
    "Interrupted",
    "Outputs",
    "Feedback",
    "add_output_flags",
    "add_json_flag",
    "add_period_range",
    "add_mode",
    "add_position_options",
    "position_options",
    "emit",
    "feedback",
    "check_output",
    "signals_as_exceptions",
    "interrupted_by",
    "error_report",
]

EXIT_OK = 0
EXIT_FAILED_ITEMS = 1  # ran, but no item done (batch, evaluate) or a checksum failed (data)
EXIT_USAGE = 2  # argparse: unknown option, missing argument, wrong type
EXIT_BAD_INPUT = 3  # ParameterError: a value, file or option combination is unusable
EXIT_OS_ERROR = 4  # the system refused: disk full, permission denied while writing
EXIT_INTERNAL = 70  # a bug in beatsync (EX_SOFTWARE): the traceback is printed
# interrupted by a signal: 128 + its number (SIGINT 130, SIGTERM 143, SIGHUP 129)

STAGING_PREFIX = ".beatsync-tmp-"

ProgressCallback = Callable[..., None]
"""``progress(done, total=None)``: ``done`` of ``total`` units of a step are finished."""

_CAUGHT_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
# Signals received while a command runs. The exception a signal raises can be lost
# (Python code called back from C, e.g. soundfile's writer, swallows it), so the
# record also stops Outputs.commit and makes the error that follows a report of it.
_RECEIVED: list[int] = []
# Set when an Outputs transaction was rolled back: the error report can then say that
# nothing was written (a command that writes incrementally, like evaluate, has none).
_ROLLED_BACK: list[bool] = []


# --------------------------------------------------------------------- options


def add_output_flags(parser: argparse.ArgumentParser) -> None:
    """``--json`` (machine-readable result and errors) and ``--quiet`` (no progress)."""
    parser.add_argument(
        "--json",
        action="store_true",
        help="print a machine-readable JSON object instead of text; errors become a JSON "
        'object {"error", "kind", "command", "exit_code"} on stderr',
    )
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress bars or progress lines on stderr (warnings and errors still shown)",
    )


add_json_flag = add_output_flags  # the name the subcommands used before --quiet existed


def add_mode(parser: argparse.ArgumentParser, *, default: str) -> None:
    """The ``--mode periods|beats|auto`` option of the commands that sync a dance."""
    parser.add_argument(
        "--mode",
        choices=("auto", "periods", "beats"),
        default=default,
        help="what lands on the beats: 'periods' (paper A: the motion's periods; a motion "
        "that is not periodic fails), 'beats' (the dancer's own motion beats, for dances "
        "that are not strictly periodic), or 'auto' (periods if the motion is periodic, "
        f"else beats, with a note); default {default}",
    )


def add_period_range(parser: argparse.ArgumentParser) -> None:
    """The ``--period-range LO HI`` option [s] shared by the commands that segment motion."""
    parser.add_argument(
        "--period-range",
        nargs=2,
        type=float,
        default=(0.25, 1.25),
        metavar=("LO", "HI"),
        help="shortest and longest motion period searched [s] (default 0.25 1.25, the "
        "paper's range; real dance cycles can be longer)",
    )


def emit(result: dict[str, Any], text: str, args: argparse.Namespace) -> int:
    """Print ``result`` as JSON if ``--json`` was given, else ``text``; return exit code 0."""
    if getattr(args, "json", False):
        from ..io import to_jsonable

        json.dump(to_jsonable(result), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(text.rstrip("\n") + "\n")
    return EXIT_OK


# --------------------------------------------------------------------- outputs


def _same_file(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _writable_folder(folder: Path) -> bool:
    return os.access(folder, os.W_OK | os.X_OK)


def check_output(
    path: str | os.PathLike[str],
    *,
    option: str = "output",
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    suffixes: Iterable[str] | None = None,
    text: str | None = None,
) -> Path:
    """Refuse an output path that cannot be written whole; return it as a ``Path``.

    Refused, in this order: a wrong suffix (if ``suffixes`` are given), the suffix of an
    audio, video or binary motion file for a text output (``text`` says what the file
    holds, e.g. ``"beat times"``: writing it would replace such a file with text), an
    existing folder, an existing file that is not a regular file (a device, a pipe), a
    read-only file, the same file as one of ``inputs`` (also through links), a missing
    or unwritable folder; an empty name, and a name ending in a path separator (a
    folder's name; ``Path`` would drop the separator and write a file). Nothing is
    touched on disk.
    """
    raw = os.fspath(path)
    p = Path(path)
    name = f"{option} {str(path)!r}"
    if not raw:
        raise ParameterError(f"{option} is an empty name; give a file name")
    seps = tuple(x for x in (os.sep, os.altsep) if x)
    ends_in_folder = raw.endswith(seps) or raw.endswith(tuple(s_ + "." for s_ in seps))
    if ends_in_folder and not p.is_dir():
        # Path() drops the slash: "out/" would be written as a file named "out"
        raise ParameterError(
            f"{name} ends in {raw.rstrip('.')[-1]!r}, which names a folder, but {option} "
            f"is a file: drop it or add a file name (e.g. {str(p / 'output')!r})"
        )
    if suffixes is not None:
        allowed = tuple(s.lower() for s in suffixes)
        if p.suffix.lower() not in allowed:
            raise ParameterError(f"{name} must end in {' or '.join(allowed)}")
    if text is not None and p.suffix.lower() in _media_suffixes():
        raise ParameterError(
            f"{name} ends in {p.suffix}, the suffix of an audio, video or motion file, but "
            f"{option} writes {text} as text: a mistaken option or argument? choose a text "
            "file name (e.g. .txt)"
        )
    if p.is_dir():
        example = p / ("output" + (p.suffix or next(iter(suffixes or ()), "")))
        raise ParameterError(
            f"{name} is an existing folder; give a file name (e.g. {str(example)!r})"
        )
    if p.exists():
        st = p.stat()
        if not stat.S_ISREG(st.st_mode):
            raise ParameterError(f"{name} exists and is not a regular file; choose a file name")
        if not st.st_mode & 0o222 or not os.access(p, os.W_OK):
            raise ParameterError(
                f"{name} is a read-only file; beatsync does not replace read-only files: "
                "make it writable (chmod u+w) or choose another name"
            )
    for inp in inputs:
        if inp is not None and _same_file(p, Path(inp)):
            raise ParameterError(
                f"{name} is the same file as the input {str(inp)!r}; beatsync never overwrites its "
                "input: choose another output name"
            )
    from ..io import check_output_folder

    try:
        check_output_folder(p)
    except ParameterError as exc:
        raise ParameterError(f"{name}: {exc}") from None
    return p


def add_position_options(parser: argparse.ArgumentParser) -> None:
    """``--up``, ``--units``, ``--max-gap`` for commands that read joint-position motion.

    Pass them on with ``io.read_motion(path, fps=args.fps, variable=args.variable,
    **position_options(args))``; ``--fps`` stays each command's own option (required
    for .json and .npy joint positions; a C3D file's own rate may not be contradicted).
    """
    parser.add_argument(
        "--up",
        choices=("y", "z"),
        default=None,
        help="vertical axis of joint positions (.json/.npy/.npz/.c3d); default detected",
    )
    parser.add_argument(
        "--units",
        choices=("m", "cm", "mm"),
        default=None,
        help="length unit of joint positions; default detected from the body's size",
    )
    parser.add_argument(
        "--max-gap",
        type=float,
        default=0.25,
        metavar="SECONDS",
        help="longest run of missing (NaN) joint values filled by interpolation [s] "
        "(default 0.25); a longer gap is refused with the joint named",
    )


def position_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of ``io.read_motion`` given by :func:`add_position_options`."""
    return {"up": args.up, "units": args.units, "max_gap": args.max_gap}


@contextlib.contextmanager
def _signals_blocked() -> Iterator[None]:
    """Hold SIGINT/SIGTERM/SIGHUP until the block ends (renames and clean-up finish)."""
    sigs = set(_CAUGHT_SIGNALS)
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _mkdtemp(folder: Path) -> Path:
    import tempfile

    return Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=folder))


def _media_suffixes() -> frozenset[str]:
    """Suffixes of the audio, video and binary motion files beatsync reads or writes."""
    from ..io import AUDIO_SUFFIXES, SOUNDFILE_SUFFIXES

    return frozenset(
        {*AUDIO_SUFFIXES, *SOUNDFILE_SUFFIXES, ".mp4", ".bvh", ".mat", ".npy", ".npz", ".c3d"}
    )


class Outputs:
    """Every output file of one command: checked up front, written all-or-nothing.

    Use it as a context manager around the command's work::

        with Outputs(inputs=[args.audio]) as outs:
            out = outs.add(args.out, option="--out", suffixes=[".beats"])
            click = outs.add(args.click, option="--click", suffixes=[".wav", ".flac"])
            ...  # the expensive work
            io.write_beats(outs.path(out), beats)
            io.write_audio(outs.path(click), mix, sr)
        # here both files are in place, or (on any error or signal) neither was touched

    :meth:`add` checks a path at once (:func:`check_output`, and no two outputs may
    name one file). :meth:`path` gives the file to write instead: same name, in a
    hidden staging folder ``.beatsync-tmp-*`` created in the destination's folder (so
    that writers choosing a format by suffix, and temporary files of their own, work
    unchanged and the final rename stays on one file system). On success the staged
    files are renamed over their destinations, with signals held until the last rename;
    on an exception (including KeyboardInterrupt and :class:`Interrupted`) the staging
    folders are removed with everything in them.
    """

    def __init__(self, inputs: Iterable[str | os.PathLike[str] | None] = ()):
        self._inputs: list[Path] = [Path(p) for p in inputs if p is not None]
        self._declared: dict[Path, tuple[Path, str]] = {}  # resolved -> (path, option)
        self._folders: dict[Path, str] = {}  # resolved output folders -> option
        self._staging: dict[Path, Path] = {}  # destination folder -> staging folder
        self._staged: dict[Path, Path] = {}  # destination -> staged file
        self.committed: list[Path] = []

    # declaring -------------------------------------------------------------
    def add_inputs(self, *paths: str | os.PathLike[str] | None) -> None:
        """More input files (known only after parsing, e.g. the clips of a folder)."""
        for p in paths:
            if p is None:
                continue
            q = Path(p)
            for out, option in self._declared.values():
                if _same_file(out, q):
                    raise ParameterError(
                        f"{option} {str(out)!r} is the same file as the input {str(p)!r}; beatsync "
                        "never overwrites its input: choose another output name"
                    )
            self._inputs.append(q)

    def add(
        self,
        path: str | os.PathLike[str],
        *,
        option: str = "output",
        suffixes: Iterable[str] | None = None,
        text: str | None = None,
    ) -> Path:
        """Declare an output file and check it now (see :func:`check_output`)."""
        p = check_output(path, option=option, inputs=self._inputs, suffixes=suffixes, text=text)
        key = p.resolve()
        if key in self._declared:
            other = self._declared[key][1]
            raise ParameterError(
                f"{option} and {other} both name {str(path)!r}; give each output its own file"
            )
        self._declared[key] = (p, option)
        return p

    def add_folder(self, folder: str | os.PathLike[str], *, option: str) -> Path:
        """Declare an existing, writable folder whose files :meth:`add` will declare."""
        d = Path(folder)
        if not d.exists():
            raise ParameterError(f"{option} {str(folder)!r} does not exist; create it first")
        if not d.is_dir():
            raise ParameterError(f"{option} {str(folder)!r} is a file, not a folder")
        if not _writable_folder(d):
            raise ParameterError(f"{option} {str(folder)!r} is not writable")
        self._folders[d.resolve()] = option
        return d

    # writing ---------------------------------------------------------------
    def path(self, final: str | os.PathLike[str]) -> Path:
        """Where to write the declared output ``final`` (a staged file of the same name)."""
        dest = Path(final)
        key = dest.resolve()
        if key not in self._declared:
            raise RuntimeError(f"output {str(final)!r} was not declared before being written")
        if key not in self._staged:
            folder = key.parent
            if folder not in self._staging:
                self._staging[folder] = _mkdtemp(folder)
            self._staged[key] = self._staging[folder] / key.name
        return self._staged[key]

    def staging_folder(self, folder: str | os.PathLike[str]) -> Path:
        """A staging folder for a folder declared with :meth:`add_folder`.

        Files written there are moved into ``folder`` by :meth:`adopt` + commit.
        """
        key = Path(folder).resolve()
        if key not in self._folders:
            raise RuntimeError(f"output folder {str(folder)!r} was not declared")
        if key not in self._staging:
            self._staging[key] = _mkdtemp(key)
        return self._staging[key]

    def final_path(self, staged: str | os.PathLike[str]) -> Path:
        """The destination of a file written into a staging folder."""
        s = Path(staged)
        for folder, stage in self._staging.items():
            if s.parent.resolve() == stage.resolve():
                for dest, (out, _) in self._declared.items():
                    if dest.parent == folder and dest.name == s.name:
                        return out
                return folder / s.name
        raise RuntimeError(f"{str(staged)!r} is not in a staging folder of this command")

    # finishing -------------------------------------------------------------
    def commit(self) -> list[Path]:
        """Rename every staged file into place; return the destinations written."""
        with _signals_blocked():
            if interrupted_by() is not None:  # a signal whose exception was swallowed
                raise Interrupted(interrupted_by())  # type: ignore[arg-type]
            moves = []
            for key, staged in self._staged.items():
                out, option = self._declared[key]
                if not staged.is_file():
                    raise RuntimeError(f"{option} {str(out)!r} was declared but not written")
                check_output(out, option=option, inputs=self._inputs)  # changed meanwhile?
                moves.append((staged, out))
            for staged, out in moves:
                with contextlib.suppress(FileNotFoundError):
                    os.chmod(staged, out.stat().st_mode & 0o777)  # keep an old file's mode
                os.replace(staged, out)
                self.committed.append(out)
            self._staged.clear()
            self._remove_staging()
        return list(self.committed)

    def rollback(self) -> None:
        """Remove every staged file and staging folder; destinations stay untouched."""
        with _signals_blocked():
            self._staged.clear()
            self._remove_staging()
            if self._declared:
                _ROLLED_BACK.append(True)

    def _remove_staging(self) -> None:
        import shutil

        for stage in self._staging.values():
            for _ in range(3):  # a child process may still be finishing a file there
                shutil.rmtree(stage, ignore_errors=True)
                if not stage.exists():
                    break
                time.sleep(0.05)
        self._staging.clear()

    def forget(self, final: str | os.PathLike[str]) -> None:
        """Withdraw a declared output (a writer chose another file, see :meth:`adopt`)."""
        key = Path(final).resolve()
        self._staged.pop(key, None)
        self._declared.pop(key, None)

    def adopt(self, staged: str | os.PathLike[str], *, option: str) -> Path:
        """Declare a file found in a staging folder (e.g. named by a worker) and stage it."""
        s = Path(staged)
        dest = self.final_path(s)
        declared = self._declared.get(dest.resolve())
        # declared by this option: staged as it is; by another: add() refuses it (never
        # overwritten); not declared yet: declared now
        mine = declared is not None and declared[1] == option
        p = dest if mine else self.add(dest, option=option)
        self._staged[p.resolve()] = s
        return p

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        if exc_type is None:
            try:
                self.commit()
            except BaseException:
                self.rollback()
                raise
        else:
            self.rollback()


# -------------------------------------------------------------------- feedback


class Feedback:
    """Progress and information on stderr for one command.

    Bars (tqdm) appear only when the stream is a terminal and not ``quiet``;
    :meth:`info` lines appear unless ``quiet``; :meth:`warn` lines always.
    """

    def __init__(self, command: str = "", *, quiet: bool = False, stream: TextIO | None = None):
        self.command = command
        self.quiet = quiet
        self.stream = sys.stderr if stream is None else stream
        try:
            tty = self.stream.isatty()
        except (AttributeError, ValueError):
            tty = False
        self.bars = tty and not quiet

    def info(self, text: str) -> None:
        if not self.quiet:
            print(text, file=self.stream, flush=True)

    def warn(self, text: str) -> None:
        print(f"beatsync {self.command}: warning: {text}", file=self.stream, flush=True)

    @contextlib.contextmanager
    def noted(self) -> Iterator[list[str]]:
        """The :class:`~beatsync.errors.BeatsyncWarning` messages issued in the block.

        Filled when the block ends (:func:`~beatsync.errors.collect_warnings`), and each
        said with :meth:`warn` then; other packages' warnings inside the block are
        dropped.
        """
        import warnings

        from ..errors import collect_warnings

        notes: list[str] = []
        with collect_warnings() as caught, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield notes
        notes += caught
        for note in notes:
            self.warn(note)

    @contextlib.contextmanager
    def step(self, desc: str, total: float | None = None) -> Iterator[ProgressCallback]:
        """A bar for one step; yields the ``progress(done, total=None)`` callable.

        The elapsed time keeps moving even if the step never calls ``progress``.
        """
        if not self.bars:
            yield _no_progress
            return
        from tqdm import tqdm

        fmt = (
            "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}]"
            if total
            else "{desc}: [{elapsed}]"
        )
        bar = tqdm(total=total, desc=desc, file=self.stream, leave=False, bar_format=fmt)
        stop = threading.Event()

        def tick() -> None:
            while not stop.wait(0.5):
                bar.refresh()

        ticker = threading.Thread(target=tick, daemon=True)
        ticker.start()

        last = [0.0]

        def progress(done: float, total: float | None = None) -> None:
            if total is not None and total != bar.total:
                bar.total = total
                bar.bar_format = (
                    "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}]"
                )
            bar.n = done
            now = time.monotonic()
            if now - last[0] >= 0.1 or (bar.total and done >= bar.total):
                last[0] = now  # cheap when called in a tight loop
                bar.refresh()

        try:
            yield progress
        finally:
            stop.set()
            ticker.join()
            bar.close()


def _no_progress(done: float, total: float | None = None) -> None:
    return None


def feedback(args: argparse.Namespace) -> Feedback:
    """The :class:`Feedback` of a parsed command line (``--quiet``)."""
    return Feedback(getattr(args, "command", "") or "", quiet=bool(getattr(args, "quiet", False)))


# ---------------------------------------------------------------------- errors


class Interrupted(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP, raised in the main thread (a KeyboardInterrupt)."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


@contextlib.contextmanager
def signals_as_exceptions() -> Iterator[None]:
    """Turn SIGINT, SIGTERM and SIGHUP into :class:`Interrupted` while the block runs.

    So ``finally`` blocks and :class:`Outputs` clean up on every one of them, and each
    signal is recorded (see :func:`interrupted_by`).
    """
    _RECEIVED.clear()
    _ROLLED_BACK.clear()
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        _RECEIVED.append(signum)
        raise Interrupted(signum)

    old = {s: signal.signal(s, handler) for s in _CAUGHT_SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _RECEIVED.clear()
        _ROLLED_BACK.clear()


def interrupted_by() -> int | None:
    """The first signal received by the running command, if any."""
    return _RECEIVED[0] if _RECEIVED else None


def error_report(
    exc: BaseException, command: str | None, *, as_json: bool, stream: TextIO | None = None
) -> int:
    """Print ``exc`` for the user (text or a JSON object on stderr); return the exit code.

    =================  ===============  ============================================
    exception          ``kind``         exit code
    =================  ===============  ============================================
    ParameterError     ``bad-input``    3
    OSError            ``os-error``     4
    KeyboardInterrupt  ``interrupted``  128 + signal (130 SIGINT, 143 SIGTERM)
    anything else      ``internal``     70, with the traceback
    =================  ===============  ============================================

    An error that follows a signal whose exception was lost is reported as the signal.
    """
    with _signals_blocked():  # a second signal must not cut the report short
        return _report(exc, command, as_json, sys.stderr if stream is None else stream)


def _report(exc: BaseException, command: str | None, as_json: bool, stream: TextIO) -> int:
    tb = None
    nothing = "; no output was written" if _ROLLED_BACK else ""
    signum = interrupted_by()
    if signum is not None and not isinstance(exc, KeyboardInterrupt):
        exc = Interrupted(signum)  # the error that followed a swallowed interruption
    if isinstance(exc, ParameterError):
        kind, code, msg = "bad-input", EXIT_BAD_INPUT, str(exc)
    elif isinstance(exc, KeyboardInterrupt):
        signum = getattr(exc, "signum", signal.SIGINT)
        kind, code = "interrupted", 128 + int(signum)
        msg = f"interrupted by {signal.Signals(signum).name}{nothing}"
    elif isinstance(exc, OSError):
        kind, code = "os-error", EXIT_OS_ERROR
        where = f": {exc.filename!r}" if getattr(exc, "filename", None) else ""
        msg = f"{exc.strerror or exc}{where}{nothing}"
    else:
        kind, code = "internal", EXIT_INTERNAL
        msg = (
            f"internal error {type(exc).__name__}: {exc} (a bug in beatsync; please report "
            "it with the command line and this message)"
        )
        import traceback

        tb = "".join(traceback.format_exception(exc))
    prefix = f"beatsync {command}" if command else "beatsync"
    if as_json:
        obj: dict[str, Any] = {"error": msg, "kind": kind, "command": command, "exit_code": code}
        if tb is not None:
            obj["traceback"] = tb
        print(json.dumps(obj), file=stream, flush=True)
    else:
        if tb is not None:
            stream.write(tb)
        print(f"{prefix}: error: {msg}", file=stream, flush=True)
    return code
