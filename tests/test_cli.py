"""The program frame: help for every subcommand, version, data check."""

import json
import subprocess
import sys

import pytest

from beatsync.cli import build_parser, main
from beatsync.datasets import CHECKSUMS


def _subcommands():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return sorted(action.choices)


def test_every_subcommand_has_help(capsys):
    from beatsync.commands import COMMAND_MODULES

    subs = _subcommands()
    assert set(subs) == set(COMMAND_MODULES)  # none silently missing
    for name in subs:
        with pytest.raises(SystemExit) as exc:
            main([name, "--help"])
        assert exc.value.code == 0
        out = capsys.readouterr().out
        assert "--json" in out


def test_data_command_json(capsys):
    assert main(["data", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert all(res["files"].values()) and len(res["files"]) == len(CHECKSUMS)


def test_console_script_runs():
    out = subprocess.run(
        [sys.executable, "-m", "beatsync.cli", "--version"], capture_output=True, text=True
    )
    assert out.returncode == 0 and out.stdout.startswith("beatsync ")


def test_json_output_is_strict(capsys):
    import argparse

    from beatsync.commands._common import emit

    emit({"x": float("nan"), "y": [1.0, float("inf")]}, "", argparse.Namespace(json=True))
    assert json.loads(capsys.readouterr().out) == {"x": None, "y": [1.0, None]}
