"""Where parallel work runs: in this process, on local worker processes, or on Dask.

One abstraction for everything the package runs in parallel (the sampler's walkers, the
joint model's records, a study's fits, calibration replicates). An :class:`Executor`
offers two ways to run a function over items:

- :meth:`Executor.map`: results in the items' order, on long-lived workers (cheap per
  item: the sampler calls it at every step). An executor made with ``state`` (a
  picklable object: a posterior, a joint model) gives it to each worker once, when the
  worker starts, and :meth:`Executor.map_state` calls ``fn(state, item)`` there, so that
  only the items travel per call.
- :meth:`Executor.as_completed`: each item's :class:`Outcome` as it finishes, each in a
  worker process of its own on local processes, so that a worker that dies (killed, out
  of memory) takes only its own item with it and the others go on.

Local workers are forked (they share the parent's memory at the fork, numba's compiled
kernels included) and leave Ctrl-C to the parent, which ends them: a worker that died of
it mid-task would leave the parent waiting for its result for ever.

Ctrl-C in the process that evaluates: :func:`interrupts_held` keeps it back while a block
runs (a sampler step) and raises it when the block ends; :func:`interrupt_raised` turns
numba's report of one that came inside a compiled function back into a KeyboardInterrupt.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.connection
import os
import signal
import threading
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator

import threadpoolctl

__all__ = ["Executor", "Serial", "LocalProcesses", "Dask", "Outcome", "WorkerDied", "make_executor",
           "interrupts_held", "interrupt_raised", "caused_by_interrupt", "blas_threads"]

#: The state a worker process was given when it started (set only in workers, by
#: :func:`_start_worker`; never in the process that made the executor).
_WORKER_STATE: Any = None


class WorkerDied(RuntimeError):
    """A worker process ended without a result (killed, out of memory)."""


@dataclass(frozen=True)
class Outcome:
    """One item's end: its index among the items, and its value or the error it raised
    (:class:`WorkerDied` where its worker died)."""

    index: int
    value: Any = None
    error: BaseException | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


class Executor:
    """Runs a function over items (see module docstring); a context manager that ends its
    workers on exit. ``workers``: how many items run at once."""

    workers: int = 1

    def map(self, fn: Callable, items: Iterable) -> list:
        """``fn(item)`` for each item, in order."""
        raise NotImplementedError

    def map_state(self, fn: Callable, items: Iterable) -> list:
        """``fn(state, item)`` for each item, in order, with the ``state`` the executor
        was made with."""
        raise NotImplementedError

    def as_completed(self, fn: Callable, items: Iterable) -> Iterator[Outcome]:
        """``fn(item)`` for each item, each :class:`Outcome` as it comes."""
        raise NotImplementedError

    def close(self) -> None:
        """End the workers (after Ctrl-C a task may still be running)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class Serial(Executor):
    """Everything in the calling process, in order."""

    def __init__(self, state: Any = None):
        self._state = state

    def map(self, fn, items) -> list:
        return [fn(x) for x in items]

    def map_state(self, fn, items) -> list:
        return [fn(self._state, x) for x in items]

    def as_completed(self, fn, items) -> Iterator[Outcome]:
        for i, x in enumerate(items):
            try:
                yield Outcome(i, fn(x))
            except Exception as exc:  # reported with the item; the others go on
                yield Outcome(i, error=exc)


def blas_threads(workers: int) -> int:
    """The BLAS threads each of ``workers`` local worker processes may use: its share of
    the machine's cores (at least one). Each worker's BLAS would otherwise start a thread
    per core, and the workers' pools would oversubscribe the cores. Measured on a 2-core
    machine: the quick study on 2 processes took 27 s at one thread a worker and 33 s at
    BLAS's default, and a test's SVDs ran up to 20 times longer beside another worker."""
    return max(1, (os.cpu_count() or 1) // workers)


def _start_worker(state: Any = None, workers: int = 1) -> None:
    global _WORKER_STATE
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threadpoolctl.threadpool_limits(limits=blas_threads(workers))  # for the process's life
    _WORKER_STATE = state


def _with_state(args):
    fn, x = args
    return fn(_WORKER_STATE, x)


class LocalProcesses(Executor):
    """``workers`` forked processes on this machine. :meth:`map` runs on a pool started
    on first use, one item per task (the pool's default chunks, a quarter of a worker's
    share each, left one worker a chunk behind at the end of every batch of walkers: 21
    walkers on 2 workers, 12 against 9); :meth:`as_completed` gives every item a process
    of its own, at most ``workers`` at a time."""

    def __init__(self, workers: int, state: Any = None):
        if not (isinstance(workers, int) and workers >= 1):
            raise ValueError(f"processes must be a whole number of at least 1, got {workers!r}")
        self.workers = workers
        self._state = state
        self._ctx = multiprocessing.get_context("fork")
        self._pool = None

    def map(self, fn, items) -> list:
        if self._pool is None:
            self._pool = self._ctx.Pool(self.workers, initializer=_start_worker,
                                        initargs=(self._state, self.workers))
        return self._pool.map(fn, list(items), chunksize=1)

    def map_state(self, fn, items) -> list:
        return self.map(_with_state, [(fn, x) for x in items])

    def as_completed(self, fn, items) -> Iterator[Outcome]:
        pending = list(enumerate(items))
        running = {}  # sentinel -> (process, connection, index)
        try:
            while pending or running:
                while pending and len(running) < self.workers:
                    i, x = pending.pop(0)
                    recv, send = self._ctx.Pipe(duplex=False)
                    proc = self._ctx.Process(target=_child, args=(fn, x, send, self._state, self.workers),
                                             daemon=True)
                    proc.start()
                    send.close()
                    running[proc.sentinel] = (proc, recv, i)
                for sentinel in multiprocessing.connection.wait(list(running)):
                    proc, recv, i = running.pop(sentinel)
                    yield _collect(proc, recv, i)
        finally:
            for proc, recv, _ in running.values():
                proc.terminate()
                proc.join()
                recv.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.terminate()
            self._pool.join()
            self._pool = None


def _child(fn, x, conn, state, workers) -> None:
    _start_worker(state, workers)
    try:
        conn.send(Outcome(-1, fn(x)))
    except BaseException as exc:  # reported to the parent, which goes on with the others
        conn.send(Outcome(-1, error=_portable(exc)))
    finally:
        conn.close()


def _portable(exc: BaseException) -> BaseException:
    """``exc``, or where it cannot be pickled to the parent, a RuntimeError that names it."""
    import pickle

    try:
        pickle.dumps(exc)
        return exc
    except Exception:  # any pickling failure: send its name and message instead
        return RuntimeError(f"{type(exc).__name__}: {exc}")


def _collect(proc, recv, index: int) -> Outcome:
    """The outcome a finished child sent, or a worker-died error when it sent none (the
    pipe is then at end-of-file)."""
    try:
        got = recv.recv() if recv.poll() else None
    except EOFError:
        got = None
    proc.join()
    recv.close()
    if got is None:
        return Outcome(index, error=WorkerDied(f"worker process died (exit code {proc.exitcode})"))
    return Outcome(index, got.value, got.error)


class Dask(Executor):
    """The workers of a Dask cluster (``scheduler``: its address, ``tcp://host:port``);
    needs ``dask.distributed``. ``state`` is sent once to every worker."""

    def __init__(self, scheduler: str, state: Any = None):
        try:
            from distributed import Client
        except ImportError:
            raise RuntimeError("running on a Dask cluster needs dask.distributed: "
                               "pip install 'bayes-inerter[dask]'") from None
        self._client = Client(scheduler)
        self.workers = max(1, sum(self._client.nthreads().values()))
        if state is not None:
            self._client.run(_install, state)

    def map(self, fn, items) -> list:
        return self._client.gather(self._client.map(fn, list(items), pure=False))

    def map_state(self, fn, items) -> list:
        return self.map(_with_state, [(fn, x) for x in items])

    def as_completed(self, fn, items) -> Iterator[Outcome]:
        from distributed import as_completed

        futures = {self._client.submit(fn, x, pure=False): i for i, x in enumerate(items)}
        for fut in as_completed(futures):
            try:
                yield Outcome(futures[fut], fut.result())
            except Exception as exc:  # the item's error, or a worker lost mid-item
                yield Outcome(futures[fut], error=exc)

    def close(self) -> None:
        self._client.close()


def _install(state) -> None:
    """Give a Dask worker its state (Ctrl-C is not the worker's concern there)."""
    global _WORKER_STATE
    _WORKER_STATE = state


def make_executor(processes: int = 1, scheduler: str | None = None, *, state: Any = None) -> Executor:
    """:class:`Dask` on ``scheduler`` if given, else :class:`LocalProcesses` for more than
    one process, else :class:`Serial`; ``state``: what :meth:`Executor.map_state` hands
    to its function."""
    if scheduler:
        return Dask(scheduler, state)
    if not (isinstance(processes, int) and processes >= 1):
        raise ValueError(f"processes must be a whole number of at least 1, got {processes!r}")
    if processes == 1:
        return Serial(state)
    return LocalProcesses(processes, state)


@contextlib.contextmanager
def interrupts_held():
    """Ctrl-C (SIGINT) held back while the block runs, then given to the handler that was
    in place (Python's raises KeyboardInterrupt) as the block ends, in the caller's own
    code. For a sampler step: a KeyboardInterrupt raised inside it would come out of
    emcee's log-probability wrapper, which prints every walker's parameters before it
    passes the exception on, or out of a compiled function, which numba reports as a
    SystemError; held, the step ends and is stored first. A second Ctrl-C while held is
    given at once (a step waiting for a worker that will never answer must not hold it
    for ever). Nothing is held off the main thread (signals go to the main thread alone)
    or where SIGINT is ignored."""
    previous = signal.getsignal(signal.SIGINT)
    if (threading.current_thread() is not threading.main_thread() or previous is None
            or previous is signal.SIG_IGN):
        yield
        return
    came = []

    def hold(signum, frame):
        came.append(signum)
        if len(came) > 1:  # asked again: now
            came.clear()
            signal.signal(signal.SIGINT, previous)
            signal.raise_signal(signum)

    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if came:  # the handler runs here, before raise_signal returns
            signal.raise_signal(signal.SIGINT)


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is a KeyboardInterrupt or was caused by one (its chain holds one)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


@contextlib.contextmanager
def interrupt_raised():
    """A KeyboardInterrupt out of the block, where Ctrl-C came inside a compiled function.

    A KeyboardInterrupt raised while numba's compiled code has called back into Python
    (as it does to box the arrays it returns) is not passed on as it is: numba goes on and
    reports ``SystemError: CPUDispatcher(...) returned a result with an exception set``,
    the KeyboardInterrupt at the end of its causes. Such an error leaves the block as the
    KeyboardInterrupt it was; every other exception as it is."""
    try:
        yield
    except Exception as exc:
        if not caused_by_interrupt(exc):
            raise
        raise KeyboardInterrupt().with_traceback(exc.__traceback__) from None
