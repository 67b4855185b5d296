"""Subcommands of the ``beatsync`` program, one module each.

Each module's ``register(subparsers)`` adds its parser with ``func=run``; ``run(args)``
checks the options and files (cheapest first), calls the library and prints a result
via :func:`beatsync.commands._common.emit`. ``beatsync --help`` lists the subcommands
from :data:`COMMAND_HELP` without importing any of them.
"""

# One-line help of each subcommand, shown by ``beatsync --help`` (and by its
# ``register``), in the order shown.
COMMAND_HELP = {
    "segment": "find the period boundaries of a periodic motion (paper A, section 3)",
    "beats": "track the beats of a song and print their times in seconds",
    "sync": "resample a periodic dance so that its periods land on the beats of a song",
    "compose": "compose a dance for a song from a library of motion clips (motion graph + DP)",
    "batch": "sync every motion clip with every song, in parallel on Dask",
    "evaluate": "score beat trackers against annotations over a dataset (on Dask)",
    "reproduce": "run the study's notebooks with papermill from a parameter file",
    "data": "list the bundled data files and verify their SHA-256 checksums",
}

# The subcommands' modules, in the order shown in ``beatsync --help``.
COMMAND_MODULES = tuple(COMMAND_HELP)
