"""Shared fixtures: seeded RNG, a tiny BVH skeleton, writable temp data."""

from __future__ import annotations

import signal
import threading

import matplotlib
import numpy as np
import pytest

from beatsync.motion import Joint, Motion, Skeleton

# Figures drawn by the tests open no window. matplotlib.use rather than the MPLBACKEND
# variable: the notebook kernels that nbval starts in the same pytest process would
# inherit the variable and stop showing their figures inline.
matplotlib.use("Agg")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


def make_chain_skeleton() -> Skeleton:
    """Root with 6 channels, a 'thigh' and 'shin' chain with ZXY rotations, one end site."""
    return Skeleton(
        (
            Joint(
                "hip",
                -1,
                np.zeros(3),
                ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"),
            ),
            Joint("thigh", 0, np.array([0.1, 0.0, 0.0]), ("Zrotation", "Xrotation", "Yrotation")),
            Joint("shin", 1, np.array([0.0, -0.4, 0.0]), ("Zrotation", "Xrotation", "Yrotation")),
            Joint("shin_end", 2, np.array([0.0, -0.4, 0.0]), (), True),
        )
    )


@pytest.fixture
def chain_motion(rng: np.random.Generator) -> Motion:
    sk = make_chain_skeleton()
    n = 50
    t = np.arange(n) / 30.0
    values = np.zeros((n, 12))
    values[:, 0] = 0.3 * t  # root x translation
    values[:, 1] = 0.9
    values[:, 6:9] = 20 * np.sin(2 * np.pi * t)[:, None] * np.array([0.2, 1.0, 0.1])
    values[:, 9:12] = 30 * np.sin(2 * np.pi * t + 1)[:, None] * np.array([0.1, 1.0, 0.3])
    values += rng.normal(0, 0.01, values.shape)
    return Motion(values, 30.0, sk.channel_names(), sk, "chain")


# An existing in-process cluster reached over TCP: with the default inproc transport a
# client on another event-loop thread shares inproc's non-thread-safe queues with the
# scheduler's loop, and under load its connection can fail (seen once in a full run).
_LOCAL_TCP = {"protocol": "tcp://", "host": "127.0.0.1", "dashboard_address": ":0"}


@pytest.fixture(scope="module")
def scheduler():
    """An existing cluster of 2 workers (threads here: no start-up or compilation per run)."""
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, processes=False, **_LOCAL_TCP) as lc:
        yield lc.scheduler_address


# A test that hangs (e.g. a Dask worker lost under a heavy load) fails after this long
# instead of holding `make test` for ever.
TEST_TIME_LIMIT = 900  # [s]


@pytest.fixture(autouse=True)
def _time_limit():
    if threading.current_thread() is not threading.main_thread():
        yield  # signals reach the main thread only
        return

    def expired(signum, frame):
        raise TimeoutError(f"the test ran longer than {TEST_TIME_LIMIT} s: it hangs")

    before = signal.signal(signal.SIGALRM, expired)
    signal.alarm(TEST_TIME_LIMIT)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, before)
