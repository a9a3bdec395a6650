"""Ctrl-C at any moment ends a fit cleanly: "interrupted", exit status 130, no traceback,
no dump of emcee's, the checkpoint intact and continued by the next run.

A KeyboardInterrupt raised while a numba-compiled function has called back into Python
(to box the arrays it returns, where a fit on one process spends most of its time) comes
out as ``SystemError: CPUDispatcher(...) returned a result with an exception set``; one
raised inside a sampler step comes out of emcee's log-probability wrapper, which prints
every walker's parameters first. The sampler holds Ctrl-C during each step and raises it
after the step is stored (``executor.interrupts_held``); elsewhere (the start search)
numba's SystemError is turned back into the KeyboardInterrupt it was
(``executor.interrupt_raised``), and the command line takes it for the interruption.
"""

import os
import queue
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from numba import njit
from conftest import SEARCH_SOURCE

from bayes_inerter.cli import main
from bayes_inerter.executor import caused_by_interrupt, interrupt_raised, interrupts_held
from bayes_inerter.inference.sampling.checkpoint import read_chain, steps_written


@pytest.fixture(autouse=True)
def pythons_ctrl_c():
    """Python's own SIGINT handler in this process for the test: a test run in the
    background of a non-interactive shell (as CI may be) inherits SIGINT ignored."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


# --- Ctrl-C inside a compiled function, made to happen every time -----------------------


@njit(nogil=True, cache=False)
def _wait_for(flag):
    """Say it runs (``flag[1]``), spin until ``flag[0]`` is set, then return two arrays
    (numba boxes them by calling back into Python: where a waiting Ctrl-C's handler runs)."""
    flag[1] = 1
    out = np.zeros(3)
    i = 0
    while flag[0] == 0:
        out[i % 3] += 1.0
        i += 1
    return out, out.copy()


def _ctrl_c_inside_compiled_code():
    """Call :func:`_wait_for` and send this process SIGINT while it runs (the GIL released:
    the signal's Python handler waits for the compiled code to call back)."""
    _wait_for(np.ones(2, dtype=np.int64))  # compiled, the first time, before any signal
    flag = np.zeros(2, dtype=np.int64)

    def ctrl_c_then_release():
        while flag[1] == 0:
            time.sleep(0.001)
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.02)
        flag[0] = 1

    thread = threading.Thread(target=ctrl_c_then_release)
    thread.start()
    try:
        return _wait_for(flag)
    finally:
        thread.join()


def test_ctrl_c_inside_compiled_code_is_a_keyboard_interrupt():
    # as numba (0.68) reports it: a SystemError whose causes end at the KeyboardInterrupt
    with pytest.raises(BaseException) as raw:
        _ctrl_c_inside_compiled_code()
    assert caused_by_interrupt(raw.value), repr(raw.value)
    # and as the package passes it on
    with pytest.raises(KeyboardInterrupt) as got:
        with interrupt_raised():
            _ctrl_c_inside_compiled_code()
    assert type(got.value) is KeyboardInterrupt and got.value.__cause__ is None
    with pytest.raises(ValueError):  # other errors go through as they are
        with interrupt_raised():
            raise ValueError("not an interruption")


def test_the_command_line_says_interrupted_for_ctrl_c_inside_compiled_code(monkeypatch, capsys):
    from bayes_inerter import cli

    def command(args):
        _ctrl_c_inside_compiled_code()
        return 0

    monkeypatch.setattr(cli, "cmd_inspect", command)
    assert main(["inspect", "any.csv"]) == 130
    err = capsys.readouterr().err
    assert err == "interrupted\n"


def test_interrupts_held_until_the_block_ends():
    before = signal.getsignal(signal.SIGINT)
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts_held():
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # Python lines, where a Ctrl-C not held would be raised
                time.sleep(0)
            done.append(True)
    assert done == [True]
    assert signal.getsignal(signal.SIGINT) is before
    with interrupts_held():  # nothing came: nothing raised
        pass


def test_a_second_ctrl_c_is_not_held():
    before = signal.getsignal(signal.SIGINT)
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts_held():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                time.sleep(0)
            done.append(True)
    assert done == []
    assert signal.getsignal(signal.SIGINT) is before


# --- the library: Python's own handler ------------------------------------------------------


@pytest.fixture(scope="module")
def model():
    """A posterior whose density is a cheap normal in theta (``conftest.normal_posterior``)."""
    from conftest import normal_posterior

    return normal_posterior(duration=1.0, ramp=0.3)


def test_ctrl_c_inside_a_sampler_step_stops_after_the_step_is_stored(model, tmp_path, capsys):
    from bayes_inerter.inference.sampling.sampler import run_sampler

    path = tmp_path / "chain.h5"
    density = model.log_prob
    armed = []

    def log_prob(theta):  # Ctrl-C inside emcee's call of the density, in step 4
        if armed == [True]:
            armed.append(True)
            os.kill(os.getpid(), signal.SIGINT)
        return density(theta)

    def progress(iteration, target):
        if iteration == 3:
            armed.append(True)

    model.log_prob = log_prob
    try:
        with pytest.raises(KeyboardInterrupt):
            run_sampler(model, path, nwalkers=24, steps=10, seed=3, start=model.test_start, progress=progress,
                        checkpoint_seconds=0)
    finally:
        model.log_prob = density
    out = capsys.readouterr()
    assert "Exception while calling" not in out.out + out.err  # emcee's dump of the walkers
    assert len(armed) == 2
    kept = read_chain(path)
    assert len(kept) == 4  # the step it came in, stored
    run = run_sampler(model, path, nwalkers=24, steps=6, seed=3, start=model.test_start)
    assert run.resumed_at == 4 and run.iteration == 6
    np.testing.assert_array_equal(read_chain(path)[:4], kept)


def test_ctrl_c_in_the_start_search_is_a_keyboard_interrupt(model, tmp_path):
    from bayes_inerter.inference.sampling.sampler import run_sampler

    def start():  # the start search's compiled simulation, interrupted
        _ctrl_c_inside_compiled_code()
        return model.test_start

    with pytest.raises(KeyboardInterrupt) as got:
        run_sampler(model, tmp_path / "chain.h5", nwalkers=24, steps=4, seed=3, start=start)
    assert type(got.value) is KeyboardInterrupt


# --- the command, on one process, as a user runs it -------------------------------------------

#: Generations of the start search in these runs: how good the start is does not matter
#: here, and each run that samples goes through it (conftest's twenty take twice as long).
DE_MAXITER = 3


def _command(de_maxiter: int) -> list:
    """The command line in a process of its own, its start search evolving ``de_maxiter``
    generations."""
    return [sys.executable, "-c", "import sys; " + SEARCH_SOURCE + f"optimize.DE_MAXITER = {de_maxiter}; "
            "from bayes_inerter.cli import main; sys.exit(main(sys.argv[1:]))"]


COMMAND = _command(DE_MAXITER)

#: The same command with a start search of many generations, for the run interrupted inside
#: it: three generations can end within the second the test waits on a fast processor (on
#: one, 27 steps were written by then); this one lasts seconds on any.
SLOW_SEARCH_COMMAND = _command(100_000)

#: What an unclean end prints: a traceback, emcee's dump of the walkers, numba's error.
UNCLEAN = ("Traceback", "Exception while calling", "SystemError", "Exception ignored")


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    from bayes_inerter import paper_parameters
    from bayes_inerter.records import GeneratorSettings, generate_record, write_record

    rec = generate_record(paper_parameters("A4"), 1.5, settings=GeneratorSettings(duration=2.5, ramp=0.8), rng=11,
                          setting_name="A4")
    path, _ = write_record(tmp_path_factory.mktemp("rec") / "a4.csv", rec)
    return path


class _Run:
    """The command in a process of its own, its output lines read as they come."""

    def __init__(self, cmd):
        self.t0 = time.monotonic()
        # a test run in the background of a non-interactive shell inherits SIGINT
        # ignored: give the run a terminal's default, as a user pressing Ctrl-C has
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     start_new_session=True,
                                     preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        self.lines = queue.Queue()
        self.out, self.err = [], []
        self._readers = [threading.Thread(target=self._read, args=(s, kept), daemon=True)
                         for s, kept in ((self.proc.stdout, self.out), (self.proc.stderr, self.err))]
        for r in self._readers:
            r.start()

    def _read(self, stream, kept):
        for line in iter(stream.readline, ""):
            kept.append(line)
            self.lines.put(line)

    def wait_for(self, text: str, timeout: float = 120.0) -> str:
        """The first line (stdout or stderr) that holds ``text``; fails if the run ends first."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.lines.get(timeout=0.05)
            except queue.Empty:
                if self.proc.poll() is not None and self.lines.empty():
                    break
                continue
            if text in line:
                return line
        self.kill()
        pytest.fail(f"no line with {text!r}; output:\n{''.join(self.out)}{''.join(self.err)}")

    def ctrl_c(self, timeout: float = 60.0) -> str:
        """Send SIGINT (the process on its own: one process, no workers); its whole output
        once it ended."""
        assert self.proc.poll() is None, "the run ended before it could be interrupted"
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f"the run did not end within {timeout} s of Ctrl-C")
        for r in self._readers:
            r.join()
        return "".join(self.out) + "".join(self.err)

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def _assert_interrupted(run: _Run, output: str) -> None:
    assert run.proc.returncode == 130, output
    assert "".join(run.err).rstrip().endswith("interrupted"), output
    for text in UNCLEAN:
        assert text not in output, output


def _wait_for_steps(run: _Run, out, steps: int, timeout: float = 120.0) -> None:
    """Wait until the run's checkpoint holds ``steps`` steps (written every step)."""
    deadline = time.monotonic() + timeout
    while run.proc.poll() is None and steps_written(out / "chain.h5") < steps and time.monotonic() < deadline:
        time.sleep(0.02)


def _fit(record_file, out, steps: int = 40, command=COMMAND) -> list:
    """The command, with the time-domain likelihood: its start search and steps simulate
    the record, so each lasts long enough to be interrupted in (the default's, motion in,
    force out, simulate nothing), and the 2.5 s record holds too few drive periods for
    the default."""
    return [*command, "fit", str(record_file), "--out", str(out), "--steps", str(steps), "--walkers", "24",
            "--processes", "1", "--no-plots", "--seed", "3", "--checkpoint-seconds", "0", "--residual", "ar1"]


#: Steps the interrupted runs ask for: far more than they take before Ctrl-C, so that no
#: processor finishes a run between two looks at its checkpoint (each run is interrupted,
#: so the number costs nothing).
INTERRUPTED_STEPS = 400


def test_ctrl_c_in_the_start_search_in_sampling_and_in_a_continued_run(tmp_path, record_file):
    """About 15 s: three runs of one command, each interrupted once."""
    out = tmp_path / "fit"
    cmd = _fit(record_file, out, steps=INTERRUPTED_STEPS)
    # during the start search (a long one: its differential evolution takes seconds after
    # the record's lines; no step is written)
    run = _Run(_fit(record_file, out, INTERRUPTED_STEPS, command=SLOW_SEARCH_COMMAND))
    run.wait_for("drive frequency:")
    time.sleep(1.0)
    assert steps_written(out / "chain.h5") == 0
    _assert_interrupted(run, run.ctrl_c())
    assert steps_written(out / "chain.h5") == 0
    # during sampling: its first step reported, a few more written
    run = _Run(cmd)
    run.wait_for(f"sampling: step 1 of {INTERRUPTED_STEPS}")
    _wait_for_steps(run, out, 3)
    _assert_interrupted(run, run.ctrl_c())
    kept = read_chain(out / "chain.h5")
    assert 3 <= len(kept) < INTERRUPTED_STEPS
    # the same command again continues the checkpoint; interrupted two steps on
    run = _Run(cmd)
    said = run.wait_for("continuing")
    assert f"the checkpoint holds {len(kept)} steps; continuing to step {INTERRUPTED_STEPS}" in said
    _wait_for_steps(run, out, len(kept) + 2)
    _assert_interrupted(run, run.ctrl_c())
    now = read_chain(out / "chain.h5")
    assert len(kept) + 2 <= len(now) < INTERRUPTED_STEPS
    np.testing.assert_array_equal(now[: len(kept)], kept)


#: Steps of the runs interrupted at many moments: enough that no run ends between two looks
#: at its checkpoint (30 did, on a processor where a step of this record takes 20 ms).
MOMENTS_STEPS = 120


@pytest.mark.slow  # about a minute: five interrupted runs, a finished one and an uninterrupted one
def test_ctrl_c_at_many_moments_then_the_chain_an_uninterrupted_run_gives(tmp_path, record_file):
    start = tmp_path / "start"  # its own folder: a fast machine may sample past 3 s, or finish
    for seconds in (0.2, 3.0):  # early and late in the start search
        run = _Run(_fit(record_file, start, steps=MOMENTS_STEPS))
        run.wait_for("drive frequency:")
        time.sleep(seconds)
        if run.proc.poll() is None and steps_written(start / "chain.h5") == 0:
            _assert_interrupted(run, run.ctrl_c())
        else:
            run.kill()
    out = tmp_path / "fit"
    cmd = _fit(record_file, out, steps=MOMENTS_STEPS)
    kept = None
    for at in (1, 9, 17):  # during sampling, the step watched in the checkpoint
        run = _Run(cmd)
        run.wait_for("drive frequency:")  # past its imports: its Ctrl-C handler is in place
        _wait_for_steps(run, out, at)
        _assert_interrupted(run, run.ctrl_c())
        now = read_chain(out / "chain.h5")
        assert at <= len(now) < MOMENTS_STEPS
        if kept is not None:
            assert f"continuing to step {MOMENTS_STEPS}" in "".join(run.err)
            np.testing.assert_array_equal(now[: len(kept)], kept)
        kept = now
    finished = subprocess.run(cmd, capture_output=True, text=True)
    assert finished.returncode == 0, finished.stderr
    assert f"the checkpoint holds {len(kept)} steps; continuing to step {MOMENTS_STEPS}" in finished.stderr
    whole = tmp_path / "whole"
    assert subprocess.run(_fit(record_file, whole, steps=MOMENTS_STEPS), capture_output=True).returncode == 0
    np.testing.assert_array_equal(read_chain(out / "chain.h5"), read_chain(whole / "chain.h5"))
