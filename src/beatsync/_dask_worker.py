"""Dask worker preload of the local clusters :func:`beatsync.cluster.dask_client` starts.

A Ctrl-C in a terminal reaches every process of its group: the local workers too,
which then printed a KeyboardInterrupt traceback each before the command's own
message. The command stops its workers itself when it is interrupted (it closes the
cluster), so they ignore SIGINT from the moment this preload runs (after a second or
two of start-up). Preloading rather than ignoring SIGINT in the parent while the
workers start: that lost a Ctrl-C pressed during the start.

While the cluster closes, a worker can still send a heartbeat to the scheduler that
has just gone: distributed logs that failure as an ERROR with two tracebacks. Only
the command's own process can lose a local cluster's scheduler, and it reports why;
the workers drop that one record.
"""

from __future__ import annotations

import logging
import signal
import threading
from typing import Any

#: The start of the record a worker logs when a heartbeat finds the scheduler gone.
HEARTBEAT_FAILED = "Failed to communicate with scheduler during heartbeat"


def _not_a_lost_heartbeat(record: logging.LogRecord) -> bool:
    return not str(record.msg).startswith(HEARTBEAT_FAILED)


def dask_setup(worker: Any) -> None:
    """Ignore SIGINT in this worker process, and drop the lost-heartbeat record.

    Nothing for a worker thread of this process (``processes=False``).
    """
    if threading.current_thread() is not threading.main_thread():
        return
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed.worker").addFilter(_not_a_lost_heartbeat)
