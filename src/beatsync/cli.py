"""The ``beatsync`` command-line program (only the chosen subcommand's module is imported).

Every subcommand accepts ``--json`` (the result as a JSON object on stdout) and
``--quiet`` (no progress on stderr; warnings and errors are still printed).

Outputs are all-or-nothing: every output file of a command is checked before any work,
written beside it under a hidden temporary name (``.beatsync-tmp-*``) and renamed into
place only when the whole command succeeded; an error or a signal leaves them as they were.

Exit status
-----------
===  ===============================================================================
0    success
1    the command ran but some of its items failed (``batch``: no pair synchronised;
     ``data``: a checksum mismatch); the output says which
2    usage error: unknown subcommand or option, missing or malformed argument
     (argparse)
3    bad input: a value, file or combination of options that cannot be used; the
     message names it and the likely mistake (no traceback)
4    the operating system refused (disk full, permission denied while writing)
70   internal error: a bug in beatsync; the traceback is printed
130  interrupted by Ctrl-C (SIGINT); 143 by SIGTERM; 129 by SIGHUP
===  ===============================================================================

Errors go to stderr as ``beatsync COMMAND: error: MESSAGE``; with ``--json`` as one
line holding a JSON object ``{"error": MESSAGE, "kind": KIND, "command": COMMAND,
"exit_code": N}``, where ``KIND`` is ``usage``, ``bad-input``, ``os-error``,
``interrupted`` or ``internal`` (which adds ``"traceback"``).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Iterable, Sequence
from typing import NoReturn

from . import __version__
from .commands import COMMAND_HELP, COMMAND_MODULES

EXIT_USAGE = 2  # argparse's own exit status for a usage error

__all__ = ["build_parser", "main", "UsageError"]


class UsageError(Exception):
    """An argparse error, raised instead of exiting so that ``main`` reports it."""

    def __init__(self, parser: argparse.ArgumentParser, message: str):
        super().__init__(message)
        self.parser = parser
        self.message = message


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        raise UsageError(self, message)


def build_parser(commands: Iterable[str] | None = None) -> argparse.ArgumentParser:
    """The program's parser; subcommands not in ``commands`` (default: all) are listed
    with their one-line help only, without importing their modules."""
    full = set(COMMAND_MODULES if commands is None else commands)
    parser = _Parser(
        prog="beatsync",
        description="Beat-synchronous dance animation: segment periodic motion, track "
        "music beats, make a dance follow a song, compose dances from a motion library.",
        epilog="Exit status: 0 success (batch, evaluate: at least one item done; the failed "
        "ones are listed), 1 no item done or a checksum mismatch (data), 2 usage error, "
        "3 bad input, 4 system error (disk full, permission), 70 internal error, "
        "130/143 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"beatsync {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        if name in full:
            importlib.import_module(f".commands.{name}", __package__).register(sub)
        else:
            sub.add_parser(name, help=COMMAND_HELP[name], add_help=False)
    return parser


def _chosen_command(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line (the first non-option word), if any."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMAND_MODULES else None
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Run the program; return its exit status (see the module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    as_json = "--json" in argv
    chosen = _chosen_command(argv)
    parser = build_parser([chosen] if chosen else [])
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        return _usage_error(exc, chosen, as_json)
    command = args.command
    from .commands._common import error_report, signals_as_exceptions

    with signals_as_exceptions():
        try:
            return int(args.func(args) or 0)
        except BrokenPipeError:
            # stdout closed early (e.g. `beatsync beats song.wav | head -1`): not an error
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
        except SystemExit:
            raise
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a report
            return error_report(_as_options(exc, argv), command, as_json=as_json)


def _as_options(exc: BaseException, argv: Sequence[str]) -> BaseException:
    """Bad input checked by the library names its argument (``first_beat=-1``); said to
    the command line, the option given for it (``--first-beat=-1``; ``motion.fps=0`` as
    ``--fps=0``)."""
    from .errors import ParameterError

    if not isinstance(exc, ParameterError):
        return exc
    import re

    msg = str(exc)
    for opt in {a.split("=")[0] for a in argv if a.startswith("--")}:
        name = re.escape(opt[2:].replace("-", "_"))
        msg = re.sub(rf"(?<![\w.-])(?:[a-z_]+\.)?{name}=", f"{opt}=", msg)
    return exc if msg == str(exc) else ParameterError(msg)


def _usage_error(exc: UsageError, command: str | None, as_json: bool) -> int:
    if as_json:
        import json

        obj = {"error": exc.message, "kind": "usage", "command": command, "exit_code": EXIT_USAGE}
        print(json.dumps(obj), file=sys.stderr)
    else:
        exc.parser.print_usage(sys.stderr)
        print(f"{exc.parser.prog}: error: {exc.message}", file=sys.stderr)
    return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
