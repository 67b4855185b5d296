"""Stress test of connecting to a busy Dask scheduler: plain ``Client`` against ours.

A client's connection fails distributed's bare ``assert len(msg) == 1`` when the
scheduler's "stream-start" reply goes out in the same 2-ms batch as a message sent to
every client (here: another client cancelling its tasks in a loop). The race needs a
loaded machine: every core but the one running this script spins while it connects.
Compares ``distributed.Client(address)`` with
:func:`beatsync.cluster._client_with_handshake_retries` (what ``--scheduler`` uses)
over the same number of connections, and prints how many failed and how.

Usage::

    .venv/bin/python benchmarks/stress_scheduler_connect.py [--connections 300]

Not part of ``run_all.py`` (it measures failures, not speed). On 2026-11-28 with two
loaded cores: plain ``Client`` 7 of 300 failed (all AssertionError; 5 of 300 in an
earlier run), ours 0 of 300 in each of three runs. (The other client's cancelled futures may
log "Future exception was never retrieved"; that is the load, not a result.)
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing as mp
import threading
import time


def _spin(stop) -> None:
    while not stop.is_set():
        pass


def _slow(x):
    time.sleep(0.01)
    return x


def run(connections: int, retry: bool) -> dict[str, int]:
    from dask.distributed import Client, LocalCluster

    from beatsync.cluster import CONNECT_TIMEOUT, _client_with_handshake_retries

    failures: collections.Counter[str] = collections.Counter()
    tcp = {"protocol": "tcp://", "host": "127.0.0.1", "dashboard_address": ":0"}
    with LocalCluster(n_workers=2, processes=False, **tcp) as lc:
        other = Client(lc.scheduler_address)
        stop = threading.Event()

        def churn():  # another client: cancelled keys are reported to every client
            i = 0
            while not stop.is_set():
                futures = [other.submit(_slow, i + j, pure=False) for j in range(20)]
                other.cancel(futures)
                i += 20

        thread = threading.Thread(target=churn)
        thread.start()
        try:
            for _ in range(connections):
                try:
                    if retry:
                        c = _client_with_handshake_retries(
                            Client, lc.scheduler_address, CONNECT_TIMEOUT
                        )
                    else:
                        c = Client(lc.scheduler_address, timeout=CONNECT_TIMEOUT)
                    c.close()
                except Exception as exc:  # counted, by type
                    failures[type(exc).__name__] += 1
        finally:
            stop.set()
            thread.join()
            other.close()
    return dict(failures)


def main() -> int:
    import logging

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--connections", type=int, default=300)
    args = ap.parse_args()
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    stop = mp.Event()
    spinners = [mp.Process(target=_spin, args=(stop,)) for _ in range(max(mp.cpu_count(), 1))]
    for p in spinners:
        p.start()
    try:
        for retry, name in ((False, "distributed.Client"), (True, "beatsync (retries)")):
            failed = run(args.connections, retry)
            total = sum(failed.values())
            print(f"{name}: {total} of {args.connections} connections failed {failed or ''}")
    finally:
        stop.set()
        for p in spinners:
            p.join()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
