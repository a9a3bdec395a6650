"""Tests of where parallel work runs (bayes_inerter.executor)."""

import os
import signal

import numpy as np
import pytest
import threadpoolctl

from bayes_inerter.executor import LocalProcesses, Serial, WorkerDied, blas_threads, make_executor


def _square(x):
    return x * x


def _scaled(state, x):
    return state["factor"] * x, os.getpid()


def _fails_on_two(x):
    if x == 2:
        raise ValueError("two is not allowed")
    return x


def _dies_on_one(x):
    if x == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return x


def test_make_executor_picks_serial_for_one_process_and_local_processes_for_more():
    assert isinstance(make_executor(1), Serial)
    with make_executor(2) as ex:
        assert isinstance(ex, LocalProcesses) and ex.workers == 2
    for bad in (0, -1, 1.5):
        with pytest.raises(ValueError, match="processes"):
            make_executor(bad)


@pytest.mark.parametrize("processes", [1, 2])
def test_map_keeps_the_items_order_and_map_state_hands_each_worker_its_state(processes):
    with make_executor(processes, state={"factor": 3}) as ex:
        assert ex.map(_square, range(7)) == [x * x for x in range(7)]
        got = ex.map_state(_scaled, range(7))
    assert [v for v, _ in got] == [3 * x for x in range(7)]
    pids = {pid for _, pid in got}
    assert (pids == {os.getpid()}) if processes == 1 else (os.getpid() not in pids)


@pytest.mark.parametrize("processes", [1, 2])
def test_as_completed_reports_each_items_error_and_goes_on(processes):
    with make_executor(processes) as ex:
        outcomes = sorted(ex.as_completed(_fails_on_two, [0, 1, 2, 3]), key=lambda o: o.index)
    assert [o.index for o in outcomes] == [0, 1, 2, 3]
    assert [o.value for o in outcomes if o.ok] == [0, 1, 3]
    assert isinstance(outcomes[2].error, ValueError) and "two" in str(outcomes[2].error)


def test_a_local_worker_that_dies_takes_only_its_own_item():
    with LocalProcesses(2) as ex:
        outcomes = sorted(ex.as_completed(_dies_on_one, [0, 1, 2]), key=lambda o: o.index)
    assert [o.ok for o in outcomes] == [True, False, True]
    assert isinstance(outcomes[1].error, WorkerDied) and "exit code -9" in str(outcomes[1].error)


def _blas_threads(_):
    np.linalg.svd(np.ones((4, 4)))  # BLAS loaded and in use
    return [pool["num_threads"] for pool in threadpoolctl.threadpool_info() if pool["user_api"] == "blas"]


@pytest.mark.parametrize("workers", [1, 2])
def test_each_local_worker_keeps_its_share_of_the_cores_for_blas(workers):
    share = max(1, (os.cpu_count() or 1) // workers)
    assert blas_threads(workers) == share and blas_threads(10_000) == 1
    with LocalProcesses(workers) as ex:
        pooled = ex.map(_blas_threads, range(workers))
        alone = [o.value for o in ex.as_completed(_blas_threads, range(2))]
    found = [n for threads in pooled + alone for n in threads]
    assert found and set(found) == {share}
