"""The one Dask set-up: worker counts, scheduler addresses, timeouts, shutdown."""

import contextlib
import re
import time

import pytest

from beatsync import cluster
from beatsync.errors import ParameterError


@pytest.mark.parametrize(
    "n, match",
    [
        (0, "whole number of workers >= 1"),
        (-1, "whole number of workers >= 1"),
        (1.5, "whole number of workers >= 1"),
        ("two", "not a number of workers"),
        (True, "whole number of workers"),
        ([2], "whole number of workers"),
        (float("inf"), "whole number of workers"),
        # a typo such as 10**12 started workers until the command hung
        (10**12, r"more worker processes than a local cluster here can start \(at most"),
        ("99999999999999999999999", "more worker processes"),
        (10**400, "more worker processes"),  # too large for a float: an internal error
        (float("nan"), "whole number of workers"),
    ],
)
def test_bad_worker_counts(n, match):
    with pytest.raises(ParameterError, match=match):
        cluster.check_workers(n)
    with pytest.raises(ParameterError, match=match), cluster.dask_client(n_workers=n):
        pass  # pragma: no cover - refused before any cluster starts


def test_good_worker_counts():
    assert cluster.check_workers(None) is None
    assert cluster.check_workers(3) == 3
    assert cluster.check_workers(2.0) == 2


@pytest.mark.parametrize(
    "scheduler, workers, match",
    [
        ("tcp://127.0.0.1:8786", 2, "give one or the other"),
        ("", None, "not an address"),
        ("   ", None, "not an address"),
    ],
)
def test_bad_cluster_options(scheduler, workers, match):
    with pytest.raises(ParameterError, match=match):
        cluster.check_cluster_options(scheduler, workers)


@pytest.mark.parametrize(
    "address, match",
    [
        ("nonsense", "is not a Dask scheduler address"),
        ("foo://127.0.0.1:8786", "is not a Dask scheduler address"),
        ("tcp://127.0.0.1:9", "could not connect to the Dask scheduler"),
    ],
)
def test_unreachable_scheduler_fails_fast_and_clearly(monkeypatch, address, match):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=match), cluster.dask_client(scheduler=address):
        pass  # pragma: no cover
    assert time.perf_counter() - t0 < 10.0


@contextlib.contextmanager
def _refusing_port():
    """A socket bound on 127.0.0.1 that does not listen (yielded): connections to its port
    are refused, and no other process can take the port meanwhile."""
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        yield sock


def _connect_error(monkeypatch, address, timeout):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", timeout)
    t0 = time.perf_counter()
    with pytest.raises(ParameterError) as info, cluster.dask_client(scheduler=address):
        pass  # pragma: no cover
    return str(info.value), time.perf_counter() - t0


#: The start of a Dask message: a small frame count, then a frame length.
PLAUSIBLE_FRAME = (1).to_bytes(8, "little") + (0).to_bytes(8, "little")


@contextlib.contextmanager
def _listener(first_reply, *, delay=0.0, later="silent"):
    """A TCP server on 127.0.0.1, its ``tcp://`` address yielded. The first connection
    gets ``first_reply`` after ``delay`` s (None: nothing; b"": closed at once); later
    ones are held without a word (``later="silent"``) or refused (``"refused"``: the
    server stops listening after the first)."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held = []

    def serve():
        with contextlib.suppress(OSError):
            conn, _ = server.accept()
            held.append(conn)
            if later == "refused":
                server.close()
            time.sleep(delay)
            if first_reply is not None:
                conn.sendall(first_reply)
                if not first_reply:
                    conn.close()
            while later == "silent":
                held.append(server.accept()[0])

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        with contextlib.suppress(OSError):
            server.shutdown(socket.SHUT_RDWR)  # wakes the accept (close alone does not)
        server.close()
        for conn in held:
            conn.close()


def test_refused_connection_is_named_without_waiting_out_the_timeout(monkeypatch):
    # once: retried until the time-out, then "no answer", for a port where nothing listens
    with _refusing_port() as sock:
        address = f"tcp://127.0.0.1:{sock.getsockname()[1]}"
        message, seconds = _connect_error(monkeypatch, address, 30.0)
    assert "nothing listens on port" in message and "connection refused" in message
    assert seconds < cluster.REFUSED_GRACE + 8.0  # not the 30 s


@pytest.mark.parametrize(
    "error, advice",
    [
        ("EAI_NONAME", "; a typo?"),
        ("EAI_AGAIN", "; is this machine's network or DNS working?"),
        ("idna", "; a typo?"),  # an empty label: UnicodeError, once a thread traceback
    ],
)
def test_unknown_host_is_named_at_once(monkeypatch, error, advice):
    import socket

    def unknown(host, *args, **kwargs):
        if error == "idna":
            return socket.getaddrinfo.__wrapped__(host, *args, **kwargs)
        raise socket.gaierror(getattr(socket, error), "no such name")

    unknown.__wrapped__ = socket.getaddrinfo
    monkeypatch.setattr(socket, "getaddrinfo", unknown)
    host = "a..b" if error == "idna" else "scheduler.example"
    message, seconds = _connect_error(monkeypatch, f"tcp://{host}:8786", 30.0)
    assert f"the host name {host!r} could not be resolved (" in message
    assert advice + " Omit --scheduler" in message
    assert seconds < 20.0  # not the 30 s


def test_a_silent_name_server_is_named_when_the_time_is_up(monkeypatch):
    # the system's resolver waits for its own time-outs (tens of seconds) with none of ours
    import socket
    import threading

    release = threading.Event()

    def silent(*args, **kwargs):
        release.wait(30)
        raise socket.gaierror(socket.EAI_AGAIN, "Temporary failure in name resolution")

    monkeypatch.setattr(socket, "getaddrinfo", silent)
    try:
        message, seconds = _connect_error(monkeypatch, "tcp://scheduler.example:8786", 1.0)
    finally:
        release.set()
    assert "the host name 'scheduler.example' was not resolved within 1 s" in message
    assert seconds < 1.0 + 5.0


def test_every_resolved_address_is_tried():
    # localhost may resolve to ::1 first; a scheduler on 127.0.0.1 alone is still reached
    import socket

    with _listener(PLAUSIBLE_FRAME) as address, _refusing_port() as refusing:
        port = int(address.rsplit(":", 1)[1])
        infos = [
            (socket.AF_INET, socket.SOCK_STREAM, 6, "", refusing.getsockname()),
            (socket.AF_INET, socket.SOCK_STREAM, 6, "", ("127.0.0.1", port)),
        ]
        with cluster._connect_any(infos, time.monotonic() + 5.0) as sock:
            assert sock.getpeername()[1] == port


class _FakeSocket:
    """A stand-in for ``socket.socket`` whose ``connect`` raises the error given for the
    address, recording the time-out each address got."""

    errors: dict = {}
    timeouts: list = []

    def __init__(self, *args):
        pass

    def settimeout(self, seconds):
        _FakeSocket.timeouts.append(seconds)

    def connect(self, sockaddr):
        raise _FakeSocket.errors[sockaddr]

    def close(self):
        pass


@pytest.mark.parametrize(
    "errors, raised",
    [
        # IPv4 refused, IPv6 without a route: the refusal (retried for a starting one)
        ([ConnectionRefusedError(), OSError(113, "No route to host")], ConnectionRefusedError),
        ([OSError(113, "No route to host"), ConnectionRefusedError()], ConnectionRefusedError),
        ([TimeoutError(), OSError(101, "Network is unreachable")], TimeoutError),
        ([OSError(101, "Network is unreachable")], OSError),
    ],
)
def test_the_most_telling_error_of_several_addresses(monkeypatch, errors, raised):
    import socket

    addresses = [(f"10.0.0.{i}", 8786) for i in range(len(errors))]
    monkeypatch.setattr(_FakeSocket, "errors", dict(zip(addresses, errors, strict=True)))
    monkeypatch.setattr(_FakeSocket, "timeouts", [])
    monkeypatch.setattr(socket, "socket", _FakeSocket)
    infos = [(socket.AF_INET, socket.SOCK_STREAM, 6, "", a) for a in addresses]
    with pytest.raises(raised) as info:
        cluster._connect_any(infos, time.monotonic() + 4.0)
    assert type(info.value) is raised
    # each address gets a share of the time left, not the first one all of it
    assert _FakeSocket.timeouts[0] <= 4.0 / len(errors) + 0.01


def test_unanswered_connection_is_named(monkeypatch):
    def no_answer(addresses, deadline):
        raise TimeoutError("timed out")

    monkeypatch.setattr(cluster, "_connect_any", no_answer)
    message, _ = _connect_error(monkeypatch, "tcp://10.0.0.5:8786", 1.0)
    assert message.startswith("could not connect to the Dask scheduler at 'tcp://10.0.0.5:8786'")
    assert "no answer within 1 s" in message


def test_a_scheduler_that_starts_within_the_grace_time_is_reached():
    # a refused connection is tried again: the listener starts 0.5 s after the probe
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))  # bound, not listening: refused until listen()
    port = server.getsockname()[1]
    held = []

    def serve_later():
        time.sleep(0.5)
        server.listen()
        with contextlib.suppress(OSError):
            conn, _ = server.accept()
            held.append(conn)
            conn.sendall(PLAUSIBLE_FRAME)

    thread = threading.Thread(target=serve_later, daemon=True)
    thread.start()
    try:
        deadline = time.monotonic() + 5.0
        cluster._probe_tcp(f"tcp://127.0.0.1:{port}", f"127.0.0.1:{port}", 5.0, deadline)
    finally:
        thread.join(timeout=5)
        server.close()
        for conn in held:
            conn.close()


def test_the_probe_and_the_client_share_one_timeout(monkeypatch):
    # the probe's connection answered after 3.5 s, then nothing listens: the client got
    # the whole timeout again after the probe (7.5 s in all for a 4 s timeout)
    with _listener(PLAUSIBLE_FRAME, delay=3.5, later="refused") as address:
        message, seconds = _connect_error(monkeypatch, address, 4.0)
    assert message.startswith("could not connect to the Dask scheduler"), message
    assert "did not complete the handshake" not in message
    assert seconds < 6.0


def test_a_handshake_that_never_comes_does_not_hang(monkeypatch):
    # the probe's connection answered like a scheduler, the client's never: distributed
    # reads the handshake with no time limit, and the command waited forever
    with _listener(PLAUSIBLE_FRAME) as address:
        message, seconds = _connect_error(monkeypatch, address, 1.0)
    assert "accepted the connection but did not complete the handshake" in message
    assert seconds < 1.0 + cluster.HANDSHAKE_GRACE + 5.0


def test_a_client_made_after_the_command_gave_up_is_closed():
    import threading

    release = threading.Event()
    made = []

    class Late:
        closed = False

        def close(self):
            Late.closed = True

    def connect():
        release.wait(5)
        made.append(Late())
        return made[-1]

    with pytest.raises(ParameterError, match="did not complete the handshake within the 5 s"):
        cluster._given_up_after(connect, 0.2, "tcp://10.0.0.5:8786", 5.0)
    release.set()
    for _ in range(100):
        if Late.closed:
            break
        time.sleep(0.02)
    assert made and Late.closed


def test_a_connection_error_is_raised_by_the_caller():
    def connect():
        raise OSError("refused")

    with pytest.raises(OSError, match="refused"):
        cluster._given_up_after(connect, 5.0, "tcp://10.0.0.5:8786", 5.0)
    assert cluster._given_up_after(lambda: "client", 5.0, "x", 5.0) == "client"


@pytest.mark.parametrize("reply", [None, b"HTTP/1.0 400 Bad Request\r\n\r\n", b""])
def test_a_listener_that_is_not_dask_is_refused_fast(monkeypatch, reply):
    # the dashboard's HTTP port given for the scheduler's: the client waited forever for
    # a handshake; an HTTP answer was read as a frame of exabytes (a MemoryError)
    with _listener(reply) as address:
        message, seconds = _connect_error(monkeypatch, address, 1.0)
    assert re.match(r"^--scheduler '[^']*' is not a Dask scheduler: ", message), message
    assert seconds < 5.0


def test_local_cluster_runs_and_shuts_down():
    with cluster.dask_client(n_workers=2, processes=False) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        assert client.submit(sum, [1, 2, 3]).result() == 6
    assert client.status == "closed"


def test_existing_scheduler_by_address():
    from dask.distributed import LocalCluster

    # TCP, not inproc: the client's loop thread and the scheduler's share no queue
    tcp = {"protocol": "tcp://", "host": "127.0.0.1"}
    with LocalCluster(n_workers=1, processes=False, dashboard_address=":0", **tcp) as lc:
        with cluster.dask_client(scheduler=lc.scheduler_address) as client:
            assert client.submit(max, [4, 1]).result() == 4
        assert client.status == "closed"
        assert lc.status.name == "running"  # an existing cluster is left running


def test_local_workers_keep_glibc_malloc_skip_dashboard_work_and_take_a_task_at_a_time():
    """Dask's MALLOC_TRIM_THRESHOLD_=65536 made every track about 1.8x slower; the
    periodic work of LOCAL_CLUSTER_CONFIG took 5-9 % of a core per process, idle. A
    key the user sets keeps the user's value."""
    import os

    import dask
    import distributed  # noqa: F401 (its defaults loaded)

    def settings(dask_worker):
        return (
            os.environ.get("MALLOC_TRIM_THRESHOLD_"),
            os.environ.get("OMP_NUM_THREADS"),
            "profile" in dask_worker.periodic_callbacks,
            dask_worker._tick_interval,
            dask_worker.periodic_callbacks["monitor"].callback_time,
            dask_worker.memory_manager.memory_monitor_interval,
        )

    keys = [*cluster.LOCAL_CLUSTER_CONFIG, "distributed.nanny.pre-spawn-environ"]
    with dask.config.set({"distributed.admin.tick.interval": "500ms"}):  # the user's
        before = {key: dask.config.get(key) for key in keys}
        with cluster.dask_client(n_workers=1, processes=True) as client:
            (worker,) = client.run(settings).values()
            scheduler = client.run_on_scheduler(
                lambda dask_scheduler: (
                    dask_scheduler._tick_interval,
                    dask_scheduler.periodic_callbacks["monitor"].callback_time,
                    dask_scheduler.WORKER_SATURATION,
                )
            )
            (nanny,) = client.cluster.workers.values()  # in this process; it stops a
            nanny_interval = nanny.memory_manager.memory_monitor_interval  # worker
            # restored once the cluster has started: this process keeps its settings
            during = {key: dask.config.get(key) for key in keys}
    assert worker == (None, "1", False, 0.5, 2000, 1.0)
    assert scheduler == (0.5, 2000, 1.0)  # a worker gets a task when its thread is free
    assert nanny_interval == 1.0
    assert during == before


def test_a_key_the_user_sets_to_dasks_default_keeps_it(monkeypatch):
    """Setting a key back to Dask's default (a DASK_* variable, a YAML file) is how a
    user gets Dask's behaviour back: it is the user's, not ours to override."""
    import dask
    import distributed  # noqa: F401 (its defaults loaded)

    monkeypatch.setenv("DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED", "True")
    with cluster._local_cluster_config():
        assert dask.config.get("distributed.worker.profile.enabled") is True
        assert dask.config.get("distributed.admin.system-monitor.interval") == "2s"  # ours
    # and a worker process of a local cluster runs with the user's value
    with cluster.dask_client(n_workers=1, processes=True) as client:
        (profiling,) = client.run(
            lambda dask_worker: "profile" in dask_worker.periodic_callbacks
        ).values()
    assert profiling


def test_local_cluster_that_fails_to_start_leaves_settings_and_no_cluster(monkeypatch):
    import dask
    import dask.distributed

    started = []

    class Recorded(dask.distributed.LocalCluster):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            started.append(self)

    def refuse(*args, **kwargs):
        raise RuntimeError("no client")

    monkeypatch.setattr(dask.distributed, "LocalCluster", Recorded)
    monkeypatch.setattr(dask.distributed, "Client", refuse)
    keys = [*cluster.LOCAL_CLUSTER_CONFIG, "distributed.nanny.pre-spawn-environ"]
    before = {key: dask.config.get(key) for key in keys}
    with pytest.raises(RuntimeError, match="no client"):
        with cluster.dask_client(n_workers=1, processes=False):
            pass
    assert {key: dask.config.get(key) for key in keys} == before
    (local,) = started
    assert local.status.name == "closed"


def test_local_clusters_started_from_two_threads_leave_the_settings_as_they_were(monkeypatch):
    """dask.config is global: two starts whose set and restore interleaved would leave
    one start's settings in place for good (the second saves the first's as 'before')."""
    import threading
    import time

    import dask
    import dask.distributed

    class SlowStart:  # a cluster that takes a while to start, and nothing else
        def __init__(self, *args, **kwargs):
            time.sleep(0.3)

        def close(self):
            pass

    class NoClient:
        def __init__(self, *args, **kwargs):
            pass

        def close(self):
            pass

    monkeypatch.setattr(dask.distributed, "LocalCluster", SlowStart)
    monkeypatch.setattr(dask.distributed, "Client", NoClient)
    keys = [*cluster.LOCAL_CLUSTER_CONFIG, "distributed.nanny.pre-spawn-environ"]
    before = {key: dask.config.get(key) for key in keys}
    errors = []

    def start():
        try:
            with cluster.dask_client(n_workers=1, processes=False):
                pass
        except Exception as exc:  # noqa: BLE001 (reported below)
            errors.append(exc)

    threads = [threading.Thread(target=start) for _ in range(2)]
    for t in threads:
        t.start()
        time.sleep(0.1)  # the second starts while the first is starting
    for t in threads:
        t.join()
    assert errors == []
    assert {key: dask.config.get(key) for key in keys} == before


def _sigint_and_heartbeat_record():
    import logging
    import signal

    record = logging.LogRecord(
        "distributed.worker", logging.ERROR, __file__, 1,
        "Failed to communicate with scheduler during heartbeat.", None, None,
    )  # fmt: skip
    shown = logging.getLogger("distributed.worker").filter(record)
    return signal.getsignal(signal.SIGINT) is signal.SIG_IGN, bool(shown)


def test_local_worker_processes_ignore_ctrl_c_and_keep_configured_preloads(monkeypatch):
    # the command closes its workers on Ctrl-C; each worker printed a traceback too
    import dask
    import distributed  # noqa: F401 (its defaults loaded first: config.set would drop them)

    with dask.config.set({"distributed.worker.preload": ["json"]}):
        assert cluster._worker_preloads() == {"preload": ["json", "beatsync.cluster"]}
    # one string (as an environment variable gives it), arguments per preload or shared
    settings = {
        "distributed.worker.preload": "json",
        "distributed.worker.preload-argv": [["--x"]],
    }
    with dask.config.set(settings):
        assert cluster._worker_preloads() == {
            "preload": ["json", "beatsync.cluster"],
            "preload_argv": [["--x"], []],
        }
        with cluster.dask_client(n_workers=1, processes=True) as client:
            (state,) = client.run(_sigint_and_heartbeat_record).values()
    assert state == (True, False)  # SIGINT ignored, the lost-heartbeat record dropped
    with dask.config.set({"distributed.worker.preload-argv": ["--y"]}):
        assert "preload_argv" not in cluster._worker_preloads()  # passed to each
    # worker threads of this process change nothing here
    import signal

    before = signal.getsignal(signal.SIGINT)
    with cluster.dask_client(n_workers=1, processes=False) as client:
        client.submit(sum, [1]).result()
    assert signal.getsignal(signal.SIGINT) is before  # (pytest-xdist's own: ignored)
    assert _sigint_and_heartbeat_record()[1]  # the record is not dropped here


class _FlakyHandshake:
    """A stand-in for ``distributed.Client`` whose first ``fail`` connections trip the
    handshake assertion, as when a broadcast is batched with "stream-start"."""

    def __init__(self, fail):
        self.fail, self.calls = fail, []

    def __call__(self, address, timeout):
        self.calls.append(timeout)
        if len(self.calls) <= self.fail:
            raise AssertionError
        return ("client", address)


def test_connection_handshake_race_is_retried():
    """CI once failed: a shared test scheduler's broadcast arrived with "stream-start"
    and the client's bare `assert len(msg) == 1` ended the batch run."""
    flaky = _FlakyHandshake(fail=2)
    got = cluster._client_with_handshake_retries(flaky, "tcp://127.0.0.1:1", 5.0)
    assert got == ("client", "tcp://127.0.0.1:1") and len(flaky.calls) == 3
    assert all(0.5 <= t <= 5.0 for t in flaky.calls)


def test_connection_handshake_failing_every_time_is_reported(monkeypatch):
    flaky = _FlakyHandshake(fail=99)
    with pytest.raises(AssertionError):
        cluster._client_with_handshake_retries(flaky, "tcp://127.0.0.1:1", 5.0)
    assert len(flaky.calls) == cluster.HANDSHAKE_ATTEMPTS

    import dask.distributed

    monkeypatch.setattr(dask.distributed, "Client", _FlakyHandshake(fail=99))
    monkeypatch.setattr(cluster, "_probe_tcp", lambda *args: None)  # nothing listens there
    with pytest.raises(
        ParameterError, match=r"could not connect .*AssertionError: its reply to 3 connections"
    ):
        cluster._connect("tcp://127.0.0.1:1", 1.0)


def test_a_ctrl_c_before_a_sync_call_starts_logs_no_traceback(caplog):
    # distributed's sync(): a KeyboardInterrupt before its coroutine has started made the
    # cancel callback fail with NameError, which tornado logged with a traceback (seen
    # once in the Ctrl-C test of `evaluate beats`)
    import asyncio
    import signal
    import threading

    from distributed.utils import sync

    async def nothing():
        await asyncio.sleep(0)

    with cluster.dask_client(n_workers=1, processes=False) as client:
        client.loop.add_callback(time.sleep, 0.5)  # the loop is busy when Ctrl-C comes
        main = threading.main_thread().ident
        threading.Timer(0.1, signal.pthread_kill, (main, signal.SIGINT)).start()
        with pytest.raises(KeyboardInterrupt):
            sync(client.loop, nothing)
        time.sleep(1.0)  # the loop runs the coroutine, then the cancel callback
    slips = [r for r in caplog.records if r.exc_info and isinstance(r.exc_info[1], NameError)]
    assert not slips
