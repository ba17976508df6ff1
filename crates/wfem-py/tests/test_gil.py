"""Long calls release the GIL (other Python threads run meanwhile) and Ctrl-C interrupts them."""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import wfem


@pytest.fixture(scope="module")
def big():
    V, F = wfem.generate.icosphere(6)  # 40962 vertices
    return wfem.HeatKernel(V, F), V


def _long_apply(K, V):
    # Many right-hand sides at a large t: seconds of work in one call.
    f = np.column_stack([V[:, 0] * (1 + j) for j in range(16)])
    return K.apply(f, [1e-4, 1e-3, 1e-2])


def test_a_python_thread_progresses_during_a_long_apply(big):
    K, V = big
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t0 = time.perf_counter()
    thread = threading.Thread(target=count)
    thread.start()
    try:
        _long_apply(K, V)
    finally:
        stop.set()
        thread.join()
    elapsed = time.perf_counter() - t0
    during = [t for t in ticks if t0 < t < t0 + elapsed]
    assert elapsed > 0.2, "the call was too short to show anything"
    # With the GIL held for the whole call the thread would tick about once.
    assert len(during) > 20, (len(during), elapsed)
    gaps = np.diff(during)
    assert gaps.max() < 0.5 * elapsed


def test_ctrl_c_interrupts_a_long_call(big):
    K, V = big
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        for _ in range(100):  # far longer than the test if not interrupted
            _long_apply(K, V)
    assert time.perf_counter() - t0 < 5.0
    timer.cancel()
    # The kernel still works after an interrupted call.
    assert np.isfinite(K.apply(V[:, 0], 0.1)).all()


def _wait_for_no_worker(timeout):
    from wfem import _wfem

    deadline = time.perf_counter() + timeout
    while _wfem._live_workers() > 0 and time.perf_counter() < deadline:
        time.sleep(0.05)
    return _wfem._live_workers()


@pytest.mark.parametrize(
    "call",
    [
        # The exact HKS: selected inversions, pole by pole (minutes here if not stopped).
        lambda V, F: wfem.hks(V, F, method="exact", num_times=100),
        # The eigensolver behind the spectral HKS: Lanczos restarts.
        lambda V, F: wfem.eigenbasis(V, F, k=300),
    ],
    ids=["hks-exact", "eigenbasis"],
)
def test_an_abandoned_call_stops_its_work(big, call):
    """Issue #23: after Ctrl-C the worker does not keep computing (it held the cores for the
    next call for 42 s): the library's checkpoints stop it within one step."""
    _, V = big
    F = wfem.generate.icosphere(6)[1]
    assert _wait_for_no_worker(30) == 0
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        call(V, F)
    timer.cancel()
    assert _wait_for_no_worker(10) == 0
