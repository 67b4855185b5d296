"""beatsync: beat-synchronous dance animation.

Stages (one module each; the layers are in the README):

- :mod:`beatsync.io` reads and writes files (BVH, MoCap Toolbox ``.mat``, CSV/NPY
  joint-angle tables, audio, beat annotations). No other module reads files.
- :mod:`beatsync.motion` holds the :class:`~beatsync.motion.Motion` value and forward
  kinematics.
- :mod:`beatsync.segment` finds the periods of periodic motion (paper A, sec. 3).
- :mod:`beatsync.beats` tracks music beats (paper A, sec. 4).
- :mod:`beatsync.sync` makes motion periods land on music beats (paper A, sec. 5).
- :mod:`beatsync.graph` composes dances over weighted motion graphs (paper B).
- :mod:`beatsync.evaluate` scores beat tracking and dance-music alignment.

Event times are seconds everywhere (see :mod:`beatsync.units`).
"""

from .errors import BeatsyncWarning, NotPeriodicError, ParameterError

__version__ = "0.1.0"

__all__ = ["ParameterError", "NotPeriodicError", "BeatsyncWarning", "__version__"]
