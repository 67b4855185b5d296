"""The locked environment: uv.lock, environment.yml and the pinned Python agree."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_environment_yml_is_written_from_the_lock():
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "environment_from_lock.py"), "--check"],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stdout + out.stderr


def test_lock_pins_one_version_of_every_direct_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lock = tomllib.loads((ROOT / "uv.lock").read_text())
    versions: dict[str, set[str]] = {}
    for package in lock["package"]:
        versions.setdefault(package["name"], set()).add(package.get("version", ""))
    for requirement in project["dependencies"]:
        name = requirement.split("[")[0].split(">")[0].split("<")[0].split("=")[0].strip()
        name = name.lower().replace("_", "-")
        assert len(versions.get(name, ())) == 1, (name, versions.get(name))


def test_python_is_pinned_to_the_locked_version():
    pinned = (ROOT / ".python-version").read_text().strip()
    uv = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["uv"]
    assert uv["environments"] == [f"python_version == '{pinned}'"]
    assert f"PYTHON     ?= python{pinned}" in (ROOT / "Makefile").read_text()
    assert f"- python={pinned}" in (ROOT / "environment.yml").read_text()
