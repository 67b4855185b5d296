"""The study layer: runs the pipelines for the notebooks, builds tables, writes artefacts.

This is the only layer that combines stages, scorers and figures for the papers'
tables. The notebooks call it (one call per step); stages and :mod:`beatsync.evaluate`
never import it. Modules:

- :mod:`.artifacts`: :func:`~.artifacts.write_artifacts`, the one artefact layout of
  every notebook (``results/<notebook>/``: tables as CSV at a fixed precision, figures
  as PNG with fixed metadata, ``params.json`` with the parameters and package version).
- :mod:`.beat_dataset`: beat trackers run and scored over a dataset of annotated audio
  files, on Dask (``beatsync evaluate beats``).
- one module per block of the papers (paper A: segmentation, beat tracking, sync;
  paper B: composition), each named after the paper and the block.
"""

from .artifacts import CSV_FLOAT_FORMAT, write_artifacts

__all__ = ["CSV_FLOAT_FORMAT", "write_artifacts"]
