"""What every subcommand shares: options, output checks, feedback, errors.

Outputs are all-or-nothing per command (:class:`Outputs`, see :mod:`beatsync.cli`).
Feedback goes to stderr (:class:`Feedback`): a tqdm bar per step a user waits for, only
when stderr is a terminal, silenced by ``--quiet``; library code receives it as an
optional ``progress(done, total)`` callable and never imports tqdm. No numpy is
imported here, so that ``beatsync --help`` and every subcommand start fast.
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

EXIT_OK = 0
EXIT_FAILED_ITEMS = 1  # ran, but no item done (batch, evaluate) or a checksum failed (data)
EXIT_BAD_INPUT = 3  # ParameterError: a value, file or option combination is unusable
EXIT_OS_ERROR = 4  # the system refused: disk full, permission denied while writing
EXIT_INTERNAL = 70  # a bug in beatsync (EX_SOFTWARE): the traceback is printed
# interrupted by a signal: 128 + its number (SIGINT 130, SIGTERM 143, SIGHUP 129)

STAGING_PREFIX = ".beatsync-tmp-"

ProgressCallback = Callable[..., None]  # progress(done, total=None)

_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))
# The signals received while a command runs. The exception a signal raises can be lost
# (Python code called back from C swallows it): the record still stops the command.
_RECEIVED: list[int] = []


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


def add_position_options(parser: argparse.ArgumentParser) -> None:
    """``--up``, ``--units``, ``--max-gap`` for ``io.read_motion`` (:func:`position_options`)."""
    parser.add_argument(
        "--up",
        choices=("y", "z"),
        help="vertical axis of joint positions (.json/.npy/.npz/.c3d); default detected",
    )
    parser.add_argument(
        "--units",
        choices=("m", "cm", "mm"),
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


def add_music_beat_options(parser: argparse.ArgumentParser) -> None:
    """``--beats FILE``, ``--bpm`` and the tempo range searched (:func:`add_tempo_range`)."""
    parser.add_argument(
        "--beats",
        metavar="FILE",
        help="music beat times [s], one per line (first column): skip beat tracking",
    )
    parser.add_argument(
        "--bpm",
        type=float,
        help="known tempo of the music [BPM]: the tracker only finds the phase",
    )
    add_tempo_range(parser)


def add_tempo_range(parser: argparse.ArgumentParser) -> None:
    """``--min-bpm`` and ``--max-bpm``: the tempo range the beat tracker searches."""
    parser.add_argument(
        "--min-bpm",
        type=float,
        help="slowest tempo the beat tracker considers [BPM] (default 40); with --max-bpm, "
        "a range that keeps the tracker off a metrical level you know is wrong",
    )
    parser.add_argument(
        "--max-bpm",
        type=float,
        help="fastest tempo the beat tracker considers [BPM] (default 240)",
    )


def tempo_options(args: argparse.Namespace) -> dict[str, float]:
    """The beat tracker's tempo keywords (``bpm``, ``min_bpm``, ``max_bpm``), checked
    before any work (``--beats`` or ``--bpm`` with each other or with a range refused)."""
    from ..beats.tracker import DEFAULT_MAX_BPM, DEFAULT_MIN_BPM  # noqa: PLC0415 (numpy)
    from ..validation import check_bpm  # noqa: PLC0415

    beats = getattr(args, "beats", None)
    if beats is not None and args.bpm is not None:
        raise ParameterError(
            "--beats and --bpm conflict: give beat times (--beats FILE) or a tempo (--bpm), "
            "not both"
        )
    bounds = (("--min-bpm", args.min_bpm), ("--max-bpm", args.max_bpm))
    given = [name for name, value in bounds if value is not None]
    fixed = "--beats" if beats is not None else "--bpm" if args.bpm is not None else None
    if given and fixed is not None:
        raise ParameterError(
            f"{' and '.join(given)} {'bound' if len(given) == 2 else 'bounds'} the tempo that "
            f"the beat tracker searches, and {fixed} means that it searches none: give one "
            "or the other"
        )
    if args.bpm is not None:
        return {"bpm": check_bpm(args.bpm, name="--bpm")}
    lo = DEFAULT_MIN_BPM if args.min_bpm is None else check_bpm(args.min_bpm, name="--min-bpm")
    hi = DEFAULT_MAX_BPM if args.max_bpm is None else check_bpm(args.max_bpm, name="--max-bpm")
    if not lo < hi:
        raise ParameterError(
            f"--min-bpm {lo:g} must be smaller than --max-bpm {hi:g}"
            + ("" if len(given) == 2 else " (the other bound is its default)")
        )
    return {"min_bpm": lo, "max_bpm": hi}


def beats_end_early(beats: Any, music_s: float, path: str, then: str) -> str:
    """The warning for a beats file that ends more than a bar (4 beats) before the music
    (``then``: what the dance does from there), or ``""``."""
    import numpy as np

    rest = music_s - float(beats[-1])
    if len(beats) < 2 or rest <= 4.0 * float(np.median(np.diff(beats))):
        return ""
    return (
        f"the beats of {path!r} end at {beats[-1]:.2f} s, {rest:.1f} s before the music does: "
        f"{then} (the annotation of part of the song, or of another recording?)"
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
        return os.path.samefile(a, b)  # a hard link
    except OSError:
        return False


_MEDIA_SUFFIXES = (".mp4", ".bvh", ".mat", ".npy", ".npz", ".c3d")


def check_output(
    path: str | os.PathLike[str],
    *,
    option: str = "output",
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    suffixes: Iterable[str] | None = None,
    text: str | None = None,
) -> Path:
    """Refuse an output path that cannot be written whole; return it as a ``Path``.

    ``text`` says what a text output holds (e.g. ``"beat times"``): an audio, video or
    motion file's suffix is then refused as a mistaken option. Nothing is touched on disk.
    """
    from ..io import AUDIO_SUFFIXES, SOUNDFILE_SUFFIXES, check_output_folder

    raw = os.fspath(path)
    p = Path(path)
    name = f"{option} {raw!r}"
    if not raw:
        raise ParameterError(f"{option} is an empty name; give a file name")
    seps = tuple(x for x in (os.sep, os.altsep) if x)
    if raw.endswith((*seps, *(s + "." for s in seps))) and not p.is_dir():
        raise ParameterError(
            f"{name} ends in {raw.rstrip('.')[-1]!r}, which names a folder, but {option} "
            f"is a file: drop it or add a file name (e.g. {str(p / 'output')!r})"
        )
    if suffixes is not None:
        allowed = tuple(s.lower() for s in suffixes)
        if p.suffix.lower() not in allowed:
            raise ParameterError(f"{name} must end in {' or '.join(allowed)}")
    media = {*AUDIO_SUFFIXES, *SOUNDFILE_SUFFIXES, *_MEDIA_SUFFIXES}
    if text is not None and p.suffix.lower() in media:
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
        if not stat.S_ISREG(p.stat().st_mode):
            raise ParameterError(f"{name} exists and is not a regular file; choose a file name")
        if not p.stat().st_mode & 0o222 or not os.access(p, os.W_OK):
            raise ParameterError(
                f"{name} is a read-only file; beatsync does not replace read-only files: "
                "make it writable (chmod u+w) or choose another name"
            )
    for inp in inputs:
        if inp is not None and _same_file(p, Path(inp)):
            raise ParameterError(
                f"{name} is the same file as the input {str(inp)!r}; beatsync never "
                "overwrites its input: choose another output name"
            )
    try:
        check_output_folder(p)
    except ParameterError as exc:
        raise ParameterError(f"{name}: {exc}") from None
    return p


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT/SIGTERM/SIGHUP until the block ends (renames and reports finish)."""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class Outputs:
    """Every output file of one command: checked up front, written all-or-nothing.

    Use it as a context manager around the command's work: :meth:`add` checks a path at
    once (:func:`check_output`; no two outputs may name one file); :meth:`path` gives
    the file to write instead (beside the destination, hidden, same suffix). On success
    each is renamed over its destination (keeping an old file's mode) with signals held;
    on an exception every file and folder whose name carries this command's token is
    removed from the output folders and the destinations stay as they were.
    """

    def __init__(self, inputs: Iterable[str | os.PathLike[str] | None] = ()):
        import secrets

        self._tag = f"{STAGING_PREFIX}{secrets.token_hex(4)}"
        self._inputs = [Path(p) for p in inputs if p is not None]
        self._declared: dict[Path, tuple[Path, str]] = {}  # resolved -> (path, option)
        self._staged: dict[Path, Path] = {}  # resolved destination -> temporary
        self._folders: set[Path] = set()  # resolved folders that may hold temporaries

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
        self._folders.add(key.parent)
        return p

    def add_folder(self, folder: str | os.PathLike[str], *, option: str) -> Path:
        """Declare an existing, writable folder whose files :meth:`adopt` will declare."""
        d = Path(folder)
        if not d.is_dir():
            why = "is a file, not a folder" if d.exists() else "does not exist; create it first"
            raise ParameterError(f"{option} {str(folder)!r} {why}")
        if not os.access(d, os.W_OK | os.X_OK):
            raise ParameterError(f"{option} {str(folder)!r} is not writable")
        self._folders.add(d.resolve())
        return d

    def path(self, final: str | os.PathLike[str]) -> Path:
        """Where to write the declared output ``final`` (a temporary beside it)."""
        key = Path(final).resolve()
        self._declared[key]  # noqa: B018 - a KeyError for an undeclared output (a bug)
        return self._staged.setdefault(key, key.with_name(f"{self._tag}-{key.name}"))

    def staging_folder(self, folder: str | os.PathLike[str]) -> Path:
        """A temporary folder inside ``folder`` (declared with :meth:`add_folder`) for
        files named by others (e.g. workers), taken in with :meth:`adopt`."""
        stage = Path(folder).resolve() / self._tag
        stage.mkdir(exist_ok=True)
        return stage

    def adopt(self, staged: str | os.PathLike[str], *, option: str) -> Path:
        """Take in a file written under a temporary name (see :meth:`path`) or into a
        :meth:`staging_folder`: declared under its final name (refused if that is
        another option's output) and renamed there on success."""
        s = Path(staged).resolve()
        folder = s.parent.parent if s.parent.name == self._tag else s.parent
        dest = folder / s.name.removeprefix(f"{self._tag}-")
        declared = self._declared.get(dest)
        p = declared[0] if declared and declared[1] == option else self.add(dest, option=option)
        self._staged[p.resolve()] = s
        return p

    def write_video(self, video: Path, motion: Any, **kwargs: Any) -> Path:
        """Render ``motion`` for the declared ``--video`` (:func:`beatsync.render.write_video`);
        without ffmpeg the GIF and WAV written instead are adopted in its place."""
        from .. import render

        staged = self.path(video)
        written = render.write_video(motion, staged, **kwargs)
        if written == staged:
            return video
        self._staged.pop(video.resolve())
        self._declared.pop(video.resolve())
        if staged.with_suffix(".wav").is_file():
            self.adopt(staged.with_suffix(".wav"), option="--video")
        return self.adopt(written, option="--video")

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        """Rename every written temporary into place, or (on an error) none."""
        with _signals_held():
            try:
                if exc is None:
                    if _RECEIVED:  # a signal whose exception was swallowed
                        raise Interrupted(_RECEIVED[0])
                    for key, tmp in self._staged.items():
                        dest = self._declared[key][0]
                        with contextlib.suppress(FileNotFoundError):
                            os.chmod(tmp, dest.stat().st_mode & 0o777)  # an old file's mode
                        os.replace(tmp, dest)
            except BaseException as failed:
                exc = failed
                raise
            finally:
                self._remove_temporaries()
                if exc is not None and self._declared:
                    exc.outcome = "; no output was written"  # said in the report

    def _remove_temporaries(self) -> None:
        import shutil

        for folder in self._folders:
            for p in folder.glob(f"*{self._tag}*"):  # also a writer's own temporaries
                if p.is_dir() and not p.is_symlink():
                    shutil.rmtree(p, ignore_errors=True)
                else:
                    p.unlink(missing_ok=True)


# -------------------------------------------------------------------- feedback


class Feedback:
    """Progress on stderr: bars only on a terminal and not ``quiet``; :meth:`info` lines
    unless ``quiet``; :meth:`warn` lines always."""

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
        """The :class:`~beatsync.errors.BeatsyncWarning` messages issued in the block, filled
        and each said with :meth:`warn` when it ends; other packages' warnings are dropped."""
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
        """A bar for one step (its elapsed time moving even without calls); yields the
        ``progress(done, total=None)`` callable."""
        if not self.bars:
            yield lambda done, total=None: None
            return
        from tqdm import tqdm

        counted = "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}]"
        fmt = counted if total else "{desc}: [{elapsed}]"
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
                bar.total, bar.bar_format = total, counted
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
    """Turn SIGINT, SIGTERM and SIGHUP into :class:`Interrupted` while the block runs
    (so that ``finally`` blocks and :class:`Outputs` clean up), recording each one
    (:func:`interrupted_by`)."""
    _RECEIVED.clear()
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        _RECEIVED.append(signum)
        raise Interrupted(signum)

    old = {s: signal.signal(s, handler) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _RECEIVED.clear()


def interrupted_by() -> int | None:
    """The first signal received by the running command, if any."""
    return _RECEIVED[0] if _RECEIVED else None


def error_report(
    exc: BaseException, command: str | None, *, as_json: bool, stream: TextIO | None = None
) -> int:
    """Print ``exc`` for the user (text or a JSON object on stderr); return the exit code
    (the kinds and codes of :mod:`beatsync.cli`). An error that follows a signal whose
    exception was lost is reported as the signal; an interruption or a system error is
    followed by its ``outcome`` attribute, if set (what was or was not written)."""
    stream = sys.stderr if stream is None else stream
    with _signals_held():  # a second signal must not cut the report short
        tb = None
        outcome = getattr(exc, "outcome", "")
        if _RECEIVED and not isinstance(exc, KeyboardInterrupt):
            exc = Interrupted(_RECEIVED[0])  # the error that followed a lost interruption
        if isinstance(exc, ParameterError):
            kind, code, msg = "bad-input", EXIT_BAD_INPUT, str(exc)
        elif isinstance(exc, KeyboardInterrupt):
            signum = getattr(exc, "signum", signal.SIGINT)
            kind, code = "interrupted", 128 + int(signum)
            msg = f"interrupted by {signal.Signals(signum).name}{outcome}"
        elif isinstance(exc, OSError):
            kind, code = "os-error", EXIT_OS_ERROR
            where = f": {exc.filename!r}" if getattr(exc, "filename", None) else ""
            msg = f"{exc.strerror or exc}{where}{outcome}"
        else:
            import traceback

            kind, code = "internal", EXIT_INTERNAL
            msg = (
                f"internal error {type(exc).__name__}: {exc} (a bug in beatsync; please "
                "report it with the command line and this message)"
            )
            tb = "".join(traceback.format_exception(exc))
        if as_json:
            obj = {"error": msg, "kind": kind, "command": command, "exit_code": code}
            if tb is not None:
                obj["traceback"] = tb
            print(json.dumps(obj), file=stream, flush=True)
        else:
            stream.write(tb or "")
            prefix = f"beatsync {command}" if command else "beatsync"
            print(f"{prefix}: error: {msg}", file=stream, flush=True)
        return code
