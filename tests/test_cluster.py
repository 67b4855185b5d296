"""The one Dask set-up: worker counts, scheduler addresses, local clusters."""

import contextlib
import re
import socket
import threading
import time

import numpy as np
import pytest

from beatsync import cluster, validation
from beatsync.errors import ParameterError


@pytest.mark.parametrize(
    "n",
    # a typo such as 10**12 started workers until the command hung
    [0, -1, 1.5, 2.0, "2", True, [2], float("nan"), float("inf"), 10**12, 10**400],
)
def test_bad_worker_counts_are_refused_before_any_cluster_starts(n):
    match = re.escape(f"--workers={n!r}")
    with pytest.raises(ParameterError, match=match), cluster.dask_client(n_workers=n):
        pass  # pragma: no cover


def test_good_worker_counts():
    assert [validation.check_workers(n) for n in (None, 1, 3, np.int64(4))] == [None, 1, 3, 4]
    assert validation.check_workers(validation.default_workers() * 16) >= 16


@pytest.mark.parametrize(
    "scheduler, workers, match",
    [
        ("tcp://127.0.0.1:8786", 2, "--workers 2"),
        ("", None, "--scheduler=''"),
        ("   ", None, "--scheduler='   '"),
    ],
)
def test_bad_cluster_options(scheduler, workers, match):
    with pytest.raises(ParameterError, match=match):
        validation.check_cluster_options(scheduler, workers)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextlib.contextmanager
def _silent_listener():
    """A TCP server on 127.0.0.1 that accepts connections and never says a word (as a
    server that waits for a request does): its ``tcp://`` address."""
    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def accept():
        with contextlib.suppress(OSError):
            while True:
                held.append(server.accept()[0])

    threading.Thread(target=accept, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        with contextlib.suppress(OSError):
            server.shutdown(socket.SHUT_RDWR)
        server.close()
        for conn in held:
            conn.close()


@pytest.mark.parametrize("where", ["nothing listens", "silent", "http"])
def test_a_scheduler_that_does_not_answer_is_named_within_the_timeout(monkeypatch, where):
    # a silent listener held distributed's client forever; an HTTP server's reply was
    # read as a frame of exabytes
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    with contextlib.ExitStack() as stack:
        if where == "nothing listens":
            address = f"tcp://127.0.0.1:{_free_port()}"
        elif where == "silent":
            address = stack.enter_context(_silent_listener())
        else:
            from http.server import BaseHTTPRequestHandler, HTTPServer

            http = HTTPServer(("127.0.0.1", 0), BaseHTTPRequestHandler)
            threading.Thread(target=http.serve_forever, daemon=True).start()
            stack.callback(http.server_close)
            stack.callback(http.shutdown)
            address = f"tcp://127.0.0.1:{http.server_port}"
        t0 = time.perf_counter()
        with pytest.raises(ParameterError, match=f"'{address}': no answer"):
            with cluster.dask_client(scheduler=address):
                pass  # pragma: no cover
    assert time.perf_counter() - t0 < 5.0


@pytest.mark.parametrize("address", ["nonsense", "foo://127.0.0.1:8786"])
def test_a_malformed_address_is_refused_at_once(address):
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=f"'{address}': it is not a Dask scheduler"):
        with cluster.dask_client(scheduler=address):
            pass  # pragma: no cover
    assert time.perf_counter() - t0 < 2.0


def test_an_existing_scheduler_runs_the_work_and_is_left_running():
    from dask.distributed import LocalCluster

    tcp = {"protocol": "tcp://", "host": "127.0.0.1", "dashboard_address": ":0"}
    with LocalCluster(n_workers=1, processes=False, **tcp) as lc:
        with cluster.dask_client(scheduler=lc.scheduler_address, timeout=2.0) as client:
            assert client.submit(max, [4, 1]).result() == 4
        assert client.status == "closed"
        assert lc.status.name == "running"


def test_a_local_cluster_of_threads_runs_the_work_and_shuts_down():
    with cluster.dask_client(n_workers=2, processes=False) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        assert client.submit(sum, [1, 2, 3]).result() == 6
    assert client.status == "closed"


def _worker_state(dask_worker):
    import logging
    import os
    import signal

    record = logging.LogRecord(
        "distributed.worker", logging.ERROR, __file__, 1,
        "Failed to communicate with scheduler during heartbeat.", None, None,
    )  # fmt: skip
    return (
        os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "profile" in dask_worker.periodic_callbacks,
        dask_worker._tick_interval,
        signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
        bool(logging.getLogger("distributed.worker").filter(record)),
    )


def test_local_worker_processes_run_with_our_settings_and_ignore_ctrl_c(monkeypatch):
    """Dask's MALLOC_TRIM_THRESHOLD_ slows beat tracking; the dashboard's periodic work
    competes with it; a Ctrl-C to the process group printed a traceback per worker. A
    key the user sets keeps the user's value, and this process keeps its settings."""
    import dask
    import distributed  # noqa: F401 (its defaults loaded)

    # a nanny of Dask's defaults started earlier in this process (another test) left
    # the variable in os.environ, which every later worker process inherits
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    keys = [*cluster.LOCAL_CLUSTER_CONFIG, "distributed.nanny.pre-spawn-environ"]
    with dask.config.set({"distributed.admin.tick.interval": "500ms"}):  # the user's
        before = {key: dask.config.get(key) for key in keys}
        with cluster.dask_client(n_workers=2, processes=True) as client:
            states = list(client.run(_worker_state).values())
            assert client.submit(sum, [1, 2]).result() == 3
            saturation = client.run_on_scheduler(
                lambda dask_scheduler: dask_scheduler.WORKER_SATURATION
            )
            during = {key: dask.config.get(key) for key in keys}
    assert states == [(None, False, 0.5, True, False)] * 2
    assert saturation == 1.0  # a worker gets its next task when its thread is free
    assert during == before
