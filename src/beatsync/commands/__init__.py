"""Subcommands of the ``beatsync`` program, one module each.

Each module defines ``register(subparsers)``, which adds its parser and sets
``func=run``; ``run(args)`` returns a JSON-serialisable ``dict`` and a human-readable
text via :func:`beatsync.commands._common.emit`.
"""

# Order shown in ``beatsync --help``.
COMMAND_MODULES = ("segment", "beats", "sync", "compose", "batch", "evaluate", "reproduce", "data")
