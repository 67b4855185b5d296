"""The study layer: runs the pipelines for the notebooks, builds tables, writes artefacts.

The only layer that combines stages, scorers and figures for the papers' tables; the
notebooks call it (one call per step), stages and :mod:`beatsync.evaluate` never
import it. :mod:`.artifacts` is every notebook's artefact layout, :mod:`.beat_dataset`
``beatsync evaluate beats``, and each other module one block of a paper.
"""

from .artifacts import CSV_FLOAT_FORMAT, write_artifacts

__all__ = ["CSV_FLOAT_FORMAT", "write_artifacts"]
