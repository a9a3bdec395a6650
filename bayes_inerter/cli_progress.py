"""The command line's progress: a bar on a terminal, lines in a log file.

On a terminal, tqdm's bar. Elsewhere (a log file, a batch job) a line at most every
:data:`LINE_SECONDS`, and at the start and end, with the step, the autocorrelation
estimate, the acceptance and the steps still needed, as the sampler last reported them
(``inference.sampling.sampler.SamplerStatus``). Part of the command line: it prints.
"""

from __future__ import annotations

import math
import sys
import time

__all__ = ["StepProgress", "LINE_SECONDS"]

#: Seconds between two progress lines when the output is not a terminal.
LINE_SECONDS = 30.0


class StepProgress:
    """Progress of one sampling run: ``step(iteration, target)`` after each step (the
    sampler's ``progress``), ``status(SamplerStatus)`` at its start and checks (its
    ``report``); ``close()`` at the end."""

    def __init__(self, desc: str, total=None, stream=None, interval: float = LINE_SECONDS, check_interrupt=None,
                 cap: int | None = None):
        self.stream = stream or sys.stderr
        self.desc = desc
        #: the step cap of a run until converged (``Convergence.max_steps``): no estimate beyond it is promised
        self.cap = cap
        self.interval = interval
        self.check_interrupt = check_interrupt
        self.last = None
        self.iteration = 0
        self.target = total
        self._printed = -math.inf
        self.bar = None
        if self.stream.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=desc, unit="step", file=self.stream)

    def _line(self) -> str:
        of = f" of {self.target}" if self.target else ""
        parts = [f"{self.desc}: step {self.iteration}{of}"]
        s = self.last
        if s is not None and math.isfinite(s.tau_max):
            parts.append(f"tau {s.tau_max:.0f} steps")
        if s is not None and math.isfinite(s.acceptance):
            parts.append(f"acceptance {s.acceptance:.2f}")
        if s is not None and s.steps_needed is not None and not self.target:
            if not s.steps_needed:
                parts.append("checking convergence")
            elif self.cap is not None and self.iteration + s.steps_needed > self.cap:
                parts.append(f"more steps needed than the cap of {self.cap} leaves")
            else:
                parts.append(f"about {s.steps_needed} more steps needed")
        return ", ".join(parts)

    def _say(self, text: str) -> None:
        if self.bar is not None:
            self.bar.write(text, file=self.stream)
        else:
            print(text, file=self.stream, flush=True)

    def status(self, status) -> None:
        """The sampler's report: at the start (says whether it continues) and after checks."""
        self.last = status
        if status.target is not None:
            self.target = status.target
        if status.iteration == status.resumed_at and math.isnan(status.tau_max):  # the run's start
            if status.resumed_at:
                self._say(f"{self.desc}: {self._resume(status.resumed_at, status.target)}")
            self.iteration = status.iteration

    def _resume(self, done: int, target) -> str:
        """The line that says how a run goes on from a checkpoint of ``done`` steps."""
        held = f"the checkpoint holds {done} steps"
        if target is not None:
            if done >= target:
                return f"{held}, as many as --steps {target} asks or more: nothing more to sample"
            return f"{held}; continuing to step {target}"
        if self.cap is not None and done >= self.cap:
            return (f"{held}, the cap of {self.cap}: nothing more to sample (a higher --max-steps continues it)")
        cap = f" (at most {self.cap} steps)" if self.cap is not None else ""
        return f"{held}; continuing until converged{cap}"

    def step(self, iteration: int, target) -> None:
        if self.check_interrupt:
            self.check_interrupt()
        self.iteration = iteration
        if target is not None:
            self.target = target
        if self.bar is not None:
            self.bar.total = self.target
            self.bar.n = iteration
            self.bar.refresh()
            return
        now = time.monotonic()
        if now - self._printed >= self.interval:
            self._printed = now
            self._say(self._line())

    def close(self, done: bool = True) -> None:
        """End the progress; ``done`` False for a run that stopped early (Ctrl-C, an error)."""
        if self.bar is not None:
            self.bar.close()
        elif self.iteration:
            self._say(self._line() + (" (done)" if done else " (stopped)"))
