"""One Dask set-up for the parallel commands (``batch``, ``evaluate beats``): a client of
a new local cluster of single-threaded workers, or of an existing scheduler given by address
(``"tcp://10.0.0.5:8786"``; its workers must see the same file paths and have beatsync).
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Iterator
from typing import Any

from .errors import ParameterError
from .validation import check_cluster_options, default_workers

#: Seconds to wait for an existing scheduler (and its handshake) before giving up.
CONNECT_TIMEOUT = 5.0

#: Dask settings of a local cluster where the user's configuration keeps Dask's default: no
#: profiler, fewer periodic checks (on a few cores they compete with the work), a worker
#: takes its next task when its thread is free (``benchmarks/bench_cluster_config.py``).
LOCAL_CLUSTER_CONFIG: dict[str, Any] = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.worker-saturation": 1.0,
}

_START_LOCK = threading.Lock()  # dask.config is global: one local start at a time


@contextlib.contextmanager
def dask_client(
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    processes: bool = True,
    timeout: float | None = None,
) -> Iterator[Any]:
    """A Dask client of a new local cluster of ``n_workers`` (default: one per core)
    processes or threads, closed on the way out; or of ``scheduler`` if it answers within
    ``timeout`` [s] (default :data:`CONNECT_TIMEOUT`)."""
    n = check_cluster_options(scheduler, n_workers)
    import dask
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        with _connect(scheduler.strip(), timeout or CONNECT_TIMEOUT) as client:
            yield client
        return
    # our settings where the user keeps Dask's; no MALLOC_TRIM_THRESHOLD_ in the workers
    # (glibc then stops adapting, and beat tracking, freeing arrays of a few MB, slows)
    dask_default = dask.config.merge(*dask.config.defaults)
    ours = {
        k: v
        for k, v in LOCAL_CLUSTER_CONFIG.items()
        if dask.config.get(k, None) == dask.config.get(k, None, config=dask_default)
    }
    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}) or {})
    environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    ours["distributed.nanny.pre-spawn-environ"] = environ
    with _START_LOCK, dask.config.set(ours):
        local = LocalCluster(
            n_workers=n or default_workers(),
            threads_per_worker=1,
            processes=processes,
            dashboard_address=None,
            scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},  # not 8787
            silence_logs=logging.ERROR,
        )
    with local, Client(local) as client:
        if processes:
            client.register_plugin(_quiet_worker())
        yield client


def _connect(address: str, timeout: float) -> Any:
    """A client of the scheduler at ``address`` if it answers within ``timeout`` [s].

    A first connection, with a time limit the client's handshake lacks, runs on a loop of
    its own thread (the caller's may run one, as Jupyter's does). The client refuses a
    handshake batched with a busy scheduler's broadcast (an AssertionError): it tries twice.
    """
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from dask.distributed import Client
    from distributed.comm import connect

    async def handshake() -> None:
        (await asyncio.wait_for(connect(address, timeout), timeout)).abort()

    def probe() -> None:
        loop = asyncio.new_event_loop()
        try:
            loop.run_until_complete(handshake())
        finally:
            loop.close()  # without waiting for a resolver thread that is stuck

    try:
        with ThreadPoolExecutor(1) as thread:
            thread.submit(probe).result()
        try:
            return Client(address, timeout=timeout)
        except AssertionError:
            return Client(address, timeout=timeout)
    except Exception as exc:  # a malformed address; refused, no answer, not Dask's answer
        why = (
            f"it is not a Dask scheduler address ({exc}), e.g. tcp://10.0.0.5:8786"
            if isinstance(exc, ValueError)
            else f"no answer within {timeout:g} s ({type(exc).__name__}); is it running?"
        )
        raise ParameterError(
            f"could not connect to the Dask scheduler at {address!r}: {why} Omit --scheduler "
            "to run on a local cluster"
        ) from None


def _quiet_worker() -> Any:
    """Local worker processes ignore Ctrl-C (sent to the process group; the command closes
    them) and do not log a heartbeat lost as the cluster closes. (Made here: the option
    checks need not import distributed.)"""
    from distributed import WorkerPlugin

    class QuietWorker(WorkerPlugin):
        name = "beatsync-quiet-worker"

        def setup(self, worker: Any) -> None:
            import signal

            signal.signal(signal.SIGINT, signal.SIG_IGN)
            logging.getLogger("distributed.worker").addFilter(
                lambda r: "Failed to communicate with scheduler during heartbeat" not in str(r.msg)
            )

    return QuietWorker()
