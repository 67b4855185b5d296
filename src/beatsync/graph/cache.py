"""On-disk cache of built motion graphs (opt-out, keyed by content, parameters and code).

Building a graph costs seconds, searching it milliseconds, so ``beatsync compose``
stores built graphs as ``graph-<key>.npz`` in :func:`cache_dir` (``--no-cache``
bypasses it). The key covers the library files' content, every graph parameter, the
package and cache layout versions and the source of the modules that determine a
graph, so an edit to any of them (also in an editable install) rebuilds it. Deleting
the folder is always safe; a damaged entry is rebuilt; an unwritable folder is not an
error.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from .build import WeightedMotionGraph, build_graph

__all__ = ["CACHE_VERSION", "cache_dir", "graph_source_hash", "graph_cache_key", "load_or_build"]

#: Version of the cache file layout (part of every key).
CACHE_VERSION = 1


def cache_dir() -> Path:
    """The graph cache folder: ``$BEATSYNC_CACHE_DIR`` or ``~/.cache/beatsync``."""
    env = os.environ.get("BEATSYNC_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "beatsync"


def graph_source_hash() -> str:
    """SHA-256 of the source of the modules that determine a graph."""
    from .. import motion, motion_beats, validation
    from ..io import bvh, sha256_file
    from . import build

    h = hashlib.sha256()
    for module in (build, motion_beats, bvh, motion, validation):
        h.update(sha256_file(Path(str(module.__file__))).encode())
    return h.hexdigest()


def graph_cache_key(files: Sequence[Path], params: dict[str, Any]) -> str:
    """Hash of the library files' content (in order), the graph parameters and the code."""
    from .. import __version__
    from ..io import sha256_file

    h = hashlib.sha256()
    h.update(f"beatsync-graph-v{CACHE_VERSION}-{__version__}".encode())
    h.update(graph_source_hash().encode())
    for f in files:
        h.update(sha256_file(f).encode())
    h.update(json.dumps(params, sort_keys=True, default=str).encode())
    return h.hexdigest()[:32]


def load_or_build(
    files: Sequence[Path],
    clips: Sequence[Any],
    params: dict[str, Any],
    *,
    use_cache: bool = True,
    folder: Path | None = None,
) -> tuple[WeightedMotionGraph, bool, Path | None]:
    """The graph of ``clips`` (read from ``files``), from the cache or built (and stored).

    ``params`` holds ``th`` and ``weight_rule`` (passed to :func:`build_graph`) and
    anything else that changed how the clips were read (e.g. ``fps``); all of it is
    hashed. Returns ``(graph, from_cache, cache_file)``.
    """
    from .. import io

    key = graph_cache_key(files, params) if use_cache else None
    path = (folder or cache_dir()) / f"graph-{key}.npz" if key else None
    if path is not None and path.is_file():
        try:
            g = WeightedMotionGraph.from_arrays(io.read_npz(path), clips, params)
            if int(g.node_clip.max(initial=-1)) < len(clips):
                return g, True, path
        except (ParameterError, ValueError, KeyError):
            pass  # a damaged cache entry is rebuilt
    g = build_graph(clips, th=params["th"], weight_rule=params["weight_rule"])
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            io.write_npz(path, g.to_arrays())
        except OSError:
            path = None  # an unwritable cache is not an error
    return g, False, path
