"""Write environment.yml from pyproject.toml and uv.lock, so conda users get the locked versions.

Every direct dependency of beatsync (and of its ``test``, ``dev`` and ``lab`` extras) is
pinned to the version that ``uv.lock`` holds; conda-forge names differ from PyPI's for a
few packages (:data:`CONDA_NAMES`). Run by ``make lock``; a test checks that the
committed environment.yml is what this script writes.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: PyPI name -> conda-forge name(s), where they differ.
CONDA_NAMES = {
    "soundfile": ["pysoundfile"],
    "soxr": ["soxr-python"],
    "dask": ["dask", "distributed"],
}
#: Extras whose packages go into the conda environment.
EXTRAS = ("test", "dev", "lab")
#: Extras installed with pip inside the conda environment (not on conda-forge for every
#: platform): ``peers``, the essentia beat trackers (AGPL-3.0; optional).
PIP_EXTRAS = ("peers",)
PYTHON = "3.11"


def _name(requirement: str) -> str:
    return re.split(r"[\[<>=!~; ]", requirement, maxsplit=1)[0].strip().lower().replace("_", "-")


def render() -> str:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lock = tomllib.loads((ROOT / "uv.lock").read_text())
    versions = {p["name"].lower(): p["version"] for p in lock["package"] if "version" in p}
    requirements = list(project["dependencies"])
    for extra in EXTRAS:
        requirements += project.get("optional-dependencies", {}).get(extra, [])
    lines = [
        "# Conda environment for beatsync, written by `make lock`",
        "# (scripts/environment_from_lock.py): the versions of uv.lock, pinned.",
        "# conda env create -f environment.yml && conda activate beatsync",
        "name: beatsync",
        "channels:",
        "  - conda-forge",
        "dependencies:",
        f"  - python={PYTHON}",
    ]
    seen = set()
    for req in requirements:
        name = _name(req)
        if name in seen:
            continue
        seen.add(name)
        if name not in versions:
            raise SystemExit(f"{name} is not in uv.lock; run `make lock`")
        for conda_name in CONDA_NAMES.get(name, [name]):
            version = versions.get(conda_name, versions[name])
            lines.append(f"  - {conda_name}={version}")
    lines += ["  - pip", "  - pip:"]
    for extra in PIP_EXTRAS:
        for req in project.get("optional-dependencies", {}).get(extra, []):
            name = _name(req)
            lines.append(f"      - {name}=={versions[name]}  # optional extra {extra!r}")
    lines.append("      - -e .")
    return "\n".join(lines) + "\n"


def main() -> int:
    text = render()
    if "--check" in sys.argv:
        current = (ROOT / "environment.yml").read_text()
        if current != text:
            print("environment.yml is not in step with uv.lock: run `make lock`")
            return 1
        return 0
    (ROOT / "environment.yml").write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
