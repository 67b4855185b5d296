"""One Dask set-up for the parallel commands (``batch``, ``evaluate beats``).

:func:`dask_client` yields a :class:`distributed.Client` on either a local cluster
(``n_workers`` single-threaded worker processes, default one per core) or an existing
scheduler given by address (``"tcp://10.0.0.5:8786"``). It checks its arguments before
starting anything, refuses an unreachable scheduler with a
:class:`~beatsync.errors.ParameterError` that says why (not a hang, not a traceback):
at once for a host name that does not resolve, after :data:`REFUSED_GRACE` seconds
where nothing listens, after ``timeout`` seconds where nothing answers (and
:data:`HANDSHAKE_GRACE` later where a connection is accepted but its handshake never
comes). It connects again when a busy scheduler's handshake reply came batched with
another message (up to :data:`HANDSHAKE_ATTEMPTS` times), and closes the client and
the local cluster on the way out, also on Ctrl-C (local worker processes ignore
SIGINT: see :func:`dask_setup`). Local workers run with glibc's default
memory-allocator settings (Dask's ``MALLOC_TRIM_THRESHOLD_`` makes our work about 1.8x
slower), and a local cluster runs no statistical profiler (it only feeds a dashboard),
samples the system for the dashboard less often, and checks its event loops and memory
less often (:data:`LOCAL_CLUSTER_CONFIG`). Dask's configuration is global to the
process: local clusters start one at a time (a lock), and other threads see these
settings while one starts.

Workers of an existing cluster must see the same file paths as the client (a shared
file system) and have beatsync installed.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import threading
from collections.abc import Iterator
from typing import Any

from .errors import ParameterError

__all__ = [
    "dask_client",
    "check_workers",
    "check_cluster_options",
    "default_workers",
    "CONNECT_TIMEOUT",
    "LOCAL_CLUSTER_CONFIG",
]

#: Held while a local cluster starts under :func:`_local_cluster_config`.
_START_LOCK = threading.Lock()

#: Seconds to wait for an existing scheduler before giving up.
CONNECT_TIMEOUT = 5.0

#: Seconds a refused connection to a scheduler is tried again (one that is starting)
#: before the command says that nothing listens there.
REFUSED_GRACE = 2.0

#: Dask settings of the local clusters, set while a cluster starts (its scheduler,
#: nannies and workers read them then; a nanny passes them on to a worker it starts
#: again). A key that the user's Dask configuration sets (a YAML file, a ``DASK_*``
#: variable, ``dask.config.set``) keeps the user's value, and a cluster given by address
#: keeps its own settings (``dask.config.set`` to distributed's own default is not seen
#: as the user's: set it in a YAML file or a ``DASK_*`` variable). The scheduler, each
#: nanny and each worker run periodic callbacks tens of times a second, and on a
#: machine of a few cores that work competes with the tracking; the first four are for
#: the dashboard (none is started) or need not run so often. Measured against Dask's
#: defaults by ``benchmarks/bench_cluster_config.py`` (16 pairs of runs alternating, see
#: benchmarks/RESULTS.md): idle, this process used 0.7 % of a core instead of 2.8 % and
#: each worker 0.3 % instead of 2.0 %, lower in every pair; the Dask path of ``beatsync
#: evaluate beats`` over 40 songs took 0.99x the time with 1 worker and 0.95x with 2
#: (medians of the pair ratios), 2 workers 1.74x the throughput of 1 against 1.68x.
#: (Before the tracks went to the workers in groups, with the first four settings: 0.93x
#: and 0.92x, idle 1.6 % against 7.8 % and 0.6 % against 5.8 %, on a busier machine.)
LOCAL_CLUSTER_CONFIG: dict[str, Any] = {
    # the statistical profiler: a stack sample of the threads running tasks every 10 ms,
    # in every worker, for the dashboard's profile and performance reports
    "distributed.worker.profile.enabled": False,
    # the event loop's health check (every 20 ms) logs, at level INFO, a loop held for
    # 3 s or more; checked every second, it may also log one held for 2 s
    "distributed.admin.tick.interval": "1s",
    # CPU, memory, network and disk counters for the dashboard (every 500 ms)
    "distributed.admin.system-monitor.interval": "2s",
    # the memory check against the spill, pause and terminate thresholds (every 100 ms):
    # a worker past 95 % of its memory limit is sent SIGTERM within a second and killed
    # a second later if it is still there; a task holds one song or one clip at a time
    "distributed.worker.memory.monitor-interval": "1s",
    # tasks a worker holds beyond its threads: Dask's 1.1 hands a one-thread worker two,
    # so the small last groups of ``beatsync evaluate beats`` (``beat_dataset._groups``) went
    # out one group early and one worker could finish alone; with 1.0 a worker gets its
    # next task when its thread is free. Measured by a scratch run of the benchmark below
    # (6 pairs, 40 songs): 2 workers gave 1.73x the throughput of 1 instead of 1.70x,
    # higher in 5 of the 6 pairs
    "distributed.scheduler.worker-saturation": 1.0,
}


def default_workers() -> int:
    """Workers of a local cluster when none are asked for: one per core."""
    return os.cpu_count() or 1


#: Local worker processes allowed per core (each is a Python process of ~100 MB; a count
#: of 10**12, a typo, started workers until the command hung).
LOCAL_WORKERS_PER_CORE = 16


def max_local_workers() -> int:
    """The largest ``--workers`` a local cluster accepts: 16 per core, at least 64."""
    return max(LOCAL_WORKERS_PER_CORE * default_workers(), 64)


def check_workers(n_workers: Any, *, name: str = "--workers") -> int | None:
    """Check a local cluster's worker count: ``None`` (default) or a whole number >= 1.

    Raises
    ------
    ParameterError
        Zero, negative, fractional or non-numeric counts, and counts above
        :func:`max_local_workers`.
    """
    if n_workers is None:
        return None
    if isinstance(n_workers, bool) or not isinstance(n_workers, (int, float, str)):
        raise ParameterError(f"{name}={n_workers!r} must be a whole number of workers >= 1")
    try:
        value = float(n_workers)
    except OverflowError:  # an int too large for a float
        value = float(max_local_workers() + 1)
    except ValueError:
        raise ParameterError(f"{name}={n_workers!r} is not a number of workers") from None
    if not math.isfinite(value) or value != int(value) or value < 1:
        raise ParameterError(
            f"{name}={n_workers!r} must be a whole number of workers >= 1 "
            f"(this machine has {default_workers()} cores; omit it for one worker per core)"
        )
    if value > max_local_workers():
        raise ParameterError(
            f"{name}={n_workers!r} is more worker processes than a local cluster here can "
            f"start (at most {max_local_workers()} on its {default_workers()} cores); a typo? "
            "For a larger cluster, start one and give its address with --scheduler"
        )
    return int(value)


def check_cluster_options(scheduler: Any, n_workers: Any) -> int | None:
    """Check ``--scheduler`` and ``--workers`` together; return the worker count.

    Raises
    ------
    ParameterError
        A bad worker count (:func:`check_workers`), an empty address, or both options
        (``--workers`` sizes a local cluster; an existing one has its own workers).
    """
    n = check_workers(n_workers)
    if scheduler is None:
        return n
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ParameterError(
            f"--scheduler={scheduler!r} is not an address; expected e.g. tcp://10.0.0.5:8786"
        )
    if n is not None:
        raise ParameterError(
            f"--workers {n} sets the size of a local cluster; with --scheduler "
            f"{scheduler!r} the tasks run on that cluster's workers: give one or the other"
        )
    return n


@contextlib.contextmanager
def dask_client(
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    processes: bool = True,
    timeout: float | None = None,
) -> Iterator[Any]:
    """A Dask client on a new local cluster or on an existing scheduler.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port`` or ``host:port``).
        Default: start a local cluster.
    n_workers : int >= 1, optional
        Workers of the local cluster (default: one per core). Refused together with
        ``scheduler`` (that cluster has its own workers).
    processes : bool
        Local workers are processes (default) or threads of this process.
    timeout : float > 0 [s], optional
        How long to wait for ``scheduler`` (default :data:`CONNECT_TIMEOUT`).

    Yields
    ------
    distributed.Client

    Raises
    ------
    ParameterError
        A bad worker count, both ``scheduler`` and ``n_workers``, a malformed
        address, or a scheduler that does not answer within ``timeout`` seconds.
    """
    n = check_cluster_options(scheduler, n_workers)
    _quiet_sync_cancel_slip()
    from dask.distributed import Client, LocalCluster

    cluster = None
    if scheduler is None:
        # read by the scheduler, nannies and workers as they start; this process's own
        # settings are restored at once, also when the start fails; one start at a time
        # (two threads' set and restore of the global configuration would interleave)
        with _START_LOCK, _local_cluster_config():
            cluster = LocalCluster(
                n_workers=n or default_workers(),
                threads_per_worker=1,
                processes=processes,
                dashboard_address=None,
                # no dashboard; the scheduler's small HTTP server on a free port, not 8787
                scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
                silence_logs=logging.ERROR,
                # worker processes ignore Ctrl-C: this process closes them (no tracebacks)
                **(_worker_preloads() if processes else {}),
            )
        try:
            client = Client(cluster)
        except BaseException:
            with contextlib.suppress(Exception):
                cluster.close()  # no worker processes left behind
            raise
    else:
        client = _connect(scheduler.strip(), CONNECT_TIMEOUT if timeout is None else timeout)
    try:
        yield client
    finally:
        with contextlib.suppress(Exception):
            client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()


def _worker_preloads() -> dict[str, list[Any]]:
    """``preload`` (and ``preload_argv``) for the local workers: those configured for
    Dask workers, and this module (:func:`dask_setup`).

    A configured preload may be one string; arguments given per preload get an empty
    list for ours (distributed refuses lists of different lengths).
    """
    import dask

    configured = dask.config.get("distributed.worker.preload", default=None) or []
    if isinstance(configured, str):
        configured = [configured]
    kwargs: dict[str, list[Any]] = {"preload": [*configured, "beatsync.cluster"]}
    argv = dask.config.get("distributed.worker.preload-argv", default=None) or []
    if argv and not isinstance(argv[0], str):  # one list per preload
        kwargs["preload_argv"] = [*argv, []]
    return kwargs


def _user_sets(key: str, defaults: dict, collected: dict) -> bool:
    """Whether the user's Dask configuration sets ``key``: in a YAML file or a ``DASK_*``
    variable (``collected``, also to distributed's default value), or to another value
    than distributed's default (``dask.config.set`` in this process)."""
    import dask

    missing = object()
    if dask.config.get(key, missing, config=collected) is not missing:
        return True
    return dask.config.get(key, None) != dask.config.get(key, None, config=defaults)


def _local_cluster_config() -> Any:
    """The Dask settings a local cluster starts with: :data:`LOCAL_CLUSTER_CONFIG` (each
    key the user's configuration does not set, :func:`_user_sets`), and worker processes
    without Dask's ``MALLOC_TRIM_THRESHOLD_=65536``.

    Dask sets that variable in its worker processes to hand freed memory back to the
    system at once; glibc then stops adapting its thresholds, and beat tracking (arrays
    of a few MB allocated and freed per call) runs about 1.8x slower: 1.29 s against
    0.72 s per 30 s song, measured in one process with and without the variable. The
    other variables (one thread for OpenMP, MKL, OpenBLAS) are kept.
    """
    import dask

    defaults = dask.config.merge(*dask.config.defaults)  # distributed's, once imported
    collected = dask.config.collect()  # the user's YAML files and DASK_* variables
    ours = {
        key: value
        for key, value in LOCAL_CLUSTER_CONFIG.items()
        if not _user_sets(key, defaults, collected)
    }
    key = "distributed.nanny.pre-spawn-environ"
    env = dict(dask.config.get(key, default={}) or {})
    env.pop("MALLOC_TRIM_THRESHOLD_", None)
    return dask.config.set({**ours, key: env})


#: Connection attempts when the scheduler's first reply is not the lone "stream-start".
HANDSHAKE_ATTEMPTS = 3


def _client_with_handshake_retries(client_cls: Any, address: str, timeout: float) -> Any:
    """``Client(address)``, tried again when the connection handshake trips an assertion.

    The scheduler batches its messages to a client every 2 ms; a message broadcast to
    all clients in that window (another client's cancelled keys, say) arrives together
    with the "stream-start" reply, and ``distributed``'s client then fails
    ``assert len(msg) == 1`` with no message. That is a race on a busy shared
    scheduler, not a bad address: a fresh connection succeeds. Other errors, and the
    last failed attempt, go to the caller.
    """
    import time

    deadline = time.monotonic() + timeout
    attempt = 1
    while True:
        try:
            return client_cls(address, timeout=max(deadline - time.monotonic(), 0.5))
        except AssertionError:
            if attempt >= HANDSHAKE_ATTEMPTS or time.monotonic() >= deadline:
                raise
            attempt += 1


#: Seconds beyond the time-out that a client's connection may take before the command
#: gives up on it (see :func:`_given_up_after`).
HANDSHAKE_GRACE = 1.0


class _GaveUp(Exception):
    """:func:`_in_thread` ran out of time."""


def _in_thread(work: Any, seconds: float, *, late: Any = None) -> Any:
    """``work()`` in a daemon thread: its result, or its exception raised here, or
    :class:`_GaveUp` after ``seconds`` (the thread is left waiting: a daemon does not
    hold the process at exit). A result that comes after that is handed to ``late``
    (e.g. to close it). For calls that take no time limit of their own."""
    box: dict[str, Any] = {}
    lock = threading.Lock()

    def run() -> None:
        try:
            result = work()
        except BaseException as exc:  # noqa: BLE001 (raised by the caller)
            box["error"] = exc
            return
        with lock:
            given_up = box.get("given_up", False)
            box["result"] = result
        if given_up and late is not None:
            with contextlib.suppress(Exception):
                late(result)

    thread = threading.Thread(target=run, name="beatsync-wait", daemon=True)
    thread.start()
    try:
        thread.join(seconds)
    finally:
        with lock:
            if "result" not in box:  # given up, or interrupted (Ctrl-C)
                box["given_up"] = True
    if "error" in box:
        raise box["error"]
    if "result" in box:
        return box["result"]
    raise _GaveUp


def _given_up_after(connect: Any, seconds: float, address: str, timeout: float) -> Any:
    """``connect()`` (which makes a client) given up after ``seconds`` with a
    :class:`~beatsync.errors.ParameterError` that names the caller's ``timeout``.

    distributed's client reads the scheduler's handshake with no time limit, whatever
    its ``timeout``: a server that answered :func:`_probe_tcp` and then accepted the
    client's own connection without a word held the command forever. So the client is
    made in a thread (:func:`_in_thread`); one made after the command gave up is closed
    at once. Its errors are raised here.
    """
    try:
        return _in_thread(connect, seconds, late=lambda client: client.close())
    except _GaveUp:
        raise ParameterError(
            f"could not connect to the Dask scheduler at {address!r}: it accepted the "
            f"connection but did not complete the handshake within the {timeout:g} s "
            "time-out; is it a Dask scheduler, and not overloaded? Omit --scheduler to run "
            "on a local cluster"
        ) from None


def _resolve(host: str, port: int, deadline: float) -> list[tuple[Any, ...]]:
    """``socket.getaddrinfo`` for a TCP connection, given up at ``deadline``.

    The system's resolver has no time limit of its own here (a silent name server
    keeps it waiting for its own time-outs, tens of seconds), so it runs in a thread
    (:func:`_in_thread`). Raises its ``socket.gaierror`` (also for a name the IDNA
    codec refuses), or :class:`_GaveUp`.
    """
    import socket
    import time

    def lookup() -> list[tuple[Any, ...]]:
        try:
            return socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
        except UnicodeError as exc:  # a name the IDNA codec refuses (an empty label)
            raise socket.gaierror(socket.EAI_NONAME, str(exc)) from None

    return _in_thread(lookup, max(deadline - time.monotonic(), 0.1))


#: A Dask frame header (a little-endian count of bytes) larger than this is not Dask's.
_MAX_FIRST_FRAME = 2**32


def _connect_any(addresses: list[tuple[Any, ...]], deadline: float) -> Any:
    """A socket connected to the first of the resolved ``addresses`` that accepts, as
    ``socket.create_connection`` tries them; each gets an equal share of the time left
    (an address that drops packets, an IPv6 one without a route, say, must not take the
    time of the others). If none accepts: a refusal if any refused (nothing listens
    there, maybe not yet), else a time-out if any timed out, else the last error."""
    import socket
    import time

    errors: list[OSError] = []
    for i, (family, kind, proto, _, sockaddr) in enumerate(addresses):
        sock = socket.socket(family, kind, proto)
        try:
            share = (deadline - time.monotonic()) / (len(addresses) - i)
            sock.settimeout(max(share, 0.1))
            sock.connect(sockaddr)
            return sock
        except OSError as exc:
            sock.close()
            errors.append(exc)
    for kind_of_error in (ConnectionRefusedError, TimeoutError):
        for exc in errors:
            if isinstance(exc, kind_of_error):
                raise exc
    raise errors[-1] if errors else ConnectionRefusedError("no address")


def _probe_tcp(address: str, location: str, timeout: float, deadline: float) -> None:
    """Refuse a TCP address where no Dask scheduler can answer, at once and saying why.

    Three failures are told apart before the client tries (it retries each of them
    until its time-out and then reports them all as no answer):

    - a host name that does not resolve (a typo) is refused at once, and one that the
      name server does not answer for when the time is up (:func:`_resolve`);
    - a refused connection (nothing listens on that port) is tried again for
      :data:`REFUSED_GRACE` seconds (a scheduler that is starting), then refused;
    - a connection that is not answered (a firewall, a wrong host) is refused when the
      time is up.

    A Dask scheduler writes its handshake as soon as a connection opens; the client
    then reads it with no time limit of its own, so a server that waits for a request
    (the dashboard's HTTP port, 8787, given for the scheduler's 8786) held the command
    forever, and one that answered with text was read as a frame of exabytes. A silent
    or non-Dask answer is refused too. ``timeout`` is the seconds the caller allows in
    all, ``deadline`` the :func:`time.monotonic` time when they are up.
    """
    import socket
    import struct
    import time

    from distributed.comm.addressing import parse_host_port

    try:
        host, port = parse_host_port(location)
    except ValueError:
        return  # the client says what is wrong with it
    refused_until = min(time.monotonic() + REFUSED_GRACE, deadline)
    addresses = None
    while True:
        try:
            if addresses is None:
                addresses = _resolve(host, port, deadline)
            sock = _connect_any(addresses, deadline)
            break
        except socket.gaierror as exc:
            advice = (
                "is this machine's network or DNS working?"
                if exc.errno == socket.EAI_AGAIN
                else "a typo?"
            )
            why = f"the host name {host!r} could not be resolved ({exc.strerror or exc}); {advice}"
        except _GaveUp:  # the name server did not answer in time (_resolve)
            why = (
                f"the host name {host!r} was not resolved within {timeout:g} s (no answer "
                "from the name server); is this machine's network or DNS working?"
            )
        except ConnectionRefusedError:
            if time.monotonic() < refused_until:
                time.sleep(0.1)
                continue
            why = (
                f"nothing listens on port {port} of {host} (connection refused); is `dask "
                "scheduler` running there, on that port?"
            )
        except TimeoutError:
            why = f"no answer within {timeout:g} s; a firewall, or the wrong host?"
        except OSError as exc:  # no route to the host, network unreachable
            why = f"{exc.strerror or exc}; is the host reachable from here?"
        raise ParameterError(
            f"could not connect to the Dask scheduler at {address!r}: {why} Omit "
            "--scheduler to run on a local cluster"
        )
    with sock:
        sock.settimeout(max(deadline - time.monotonic(), 0.5))
        try:
            first = sock.recv(16)
        except OSError:
            first = None
    hint = (
        "; a Dask scheduler listens on 8786 by default (8787 is its dashboard)"
        if port == 8787 or (first or b"").startswith(b"HTTP")
        else ""
    )
    if first is None:
        why = f"something listens there but sent nothing within {timeout:g} s"
    elif first.startswith(b"HTTP"):
        why = "an HTTP server answers there"
    elif len(first) >= 8 and struct.unpack("<Q", first[:8])[0] > _MAX_FIRST_FRAME:
        why = f"something answers there that does not speak Dask (it began {first[:8]!r})"
    elif not first:
        why = "something listens there but closed the connection at once"
    else:
        return
    raise ParameterError(
        f"--scheduler {address!r} is not a Dask scheduler: {why}{hint}. Give the address "
        "`dask scheduler` prints, or omit --scheduler to run on a local cluster"
    )


def _connect(address: str, timeout: float) -> Any:
    import time

    from dask.distributed import Client
    from distributed.comm import parse_address
    from distributed.comm.registry import get_backend

    deadline = time.monotonic() + timeout  # the probe's time counts against the client's
    try:
        # an unknown scheme is refused here, not inside the client's connection retries
        # (which, on a busy machine, can time out before they report the scheme)
        scheme, location = parse_address(address)
        get_backend(scheme)
        if scheme == "tcp":
            _probe_tcp(address, location, timeout, deadline)
        remaining = max(deadline - time.monotonic(), 0.5)
        return _given_up_after(
            lambda: _client_with_handshake_retries(Client, address, remaining),
            remaining + HANDSHAKE_GRACE,
            address,
            timeout,
        )
    except ParameterError:
        raise
    except ValueError as exc:  # malformed address: unknown scheme, no port
        raise ParameterError(
            f"--scheduler {address!r} is not a Dask scheduler address ({exc}); "
            "expected e.g. tcp://10.0.0.5:8786"
        ) from None
    except Exception as exc:  # refused, timed out, or something else answering there
        if isinstance(exc, (OSError, TimeoutError)):
            reason = f"within {timeout:g} s (no answer)"
        elif isinstance(exc, AssertionError) and not str(exc):
            reason = (
                f"(AssertionError: its reply to {HANDSHAKE_ATTEMPTS} connections was not "
                "the handshake a Dask client expects; is it a Dask scheduler of the same "
                "version, and not overloaded?)"
            )
        else:  # failed at once, not a time-out: say how
            reason = f"({type(exc).__name__}: {exc})" if str(exc) else f"({type(exc).__name__})"
        raise ParameterError(
            f"could not connect to the Dask scheduler at {address!r} {reason}; is `dask "
            "scheduler` running there and reachable? Omit --scheduler to run on a local cluster"
        ) from None


#: The start of the record a worker logs when a heartbeat finds the scheduler gone.
HEARTBEAT_FAILED = "Failed to communicate with scheduler during heartbeat"


def _not_a_lost_heartbeat(record: logging.LogRecord) -> bool:
    return not str(record.msg).startswith(HEARTBEAT_FAILED)


def _not_the_sync_cancel_slip(record: logging.LogRecord) -> bool:
    """False for tornado's record of distributed's ``sync`` cancel callback failing.

    A Ctrl-C that comes while the command waits in ``distributed.utils.sync`` (for a
    track's row, say) before its coroutine has started makes the ``cancel`` callback
    read a variable not yet assigned: ``NameError: cannot access free variable
    'future'``, logged by tornado with a traceback on stderr before the command's own
    message (distributed 2026.8; seen once in about ten runs of the Ctrl-C test). The
    interrupt itself is handled; only that record is dropped.
    """
    exc = record.exc_info[1] if record.exc_info else None
    return not (
        isinstance(exc, NameError)
        and "'future'" in str(exc)
        and "sync.<locals>.cancel" in record.getMessage()
    )


def _quiet_sync_cancel_slip() -> None:
    """Install :func:`_not_the_sync_cancel_slip` on tornado's logger, once."""
    log = logging.getLogger("tornado.application")
    if _not_the_sync_cancel_slip not in log.filters:
        log.addFilter(_not_the_sync_cancel_slip)


def dask_setup(worker: Any) -> None:
    """Preload of the local clusters' worker processes: Ctrl-C ignored, quiet closing.

    A Ctrl-C in a terminal reaches every process of its group: the local workers too,
    which printed a KeyboardInterrupt traceback each before the command's own message.
    The command stops its workers itself when it is interrupted (it closes the
    cluster), so they ignore SIGINT from the moment this runs (after a second or two
    of start-up). Not by ignoring SIGINT in this process while the workers start: that
    lost a Ctrl-C pressed meanwhile. And while the cluster closes, a worker can still
    send a heartbeat to the scheduler that has just gone, which distributed logs as an
    ERROR with two tracebacks: only the command's own process can lose a local
    cluster's scheduler, and it says why, so the workers drop that one record.
    Nothing for a worker thread of this process (``processes=False``).
    """
    if threading.current_thread() is not threading.main_thread():
        return
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed.worker").addFilter(_not_a_lost_heartbeat)
