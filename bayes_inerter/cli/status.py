"""How a command ends: its exit status, the one-line error, and Ctrl-C remembered.

Exit status: 0 success; 1 bad input or a failed run (one-line error, no traceback);
2 usage error (argparse); 130 interrupted; 141 the output's reader closed the pipe.

The commands' modules take these from here, and :func:`..cli.main` runs them; nothing
here imports a command, so the command line has no import cycle.
"""

from __future__ import annotations

__all__ = ["EXIT_OK", "EXIT_FAIL", "EXIT_USAGE", "EXIT_INTERRUPTED", "EXIT_PIPE", "CliError", "on_sigint",
           "check_interrupt", "interrupted", "reset_interrupt"]

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 130, 141


class CliError(Exception):
    """An error reported as one line on stderr with exit status 1."""


#: Set by Ctrl-C (:func:`on_sigint`) for the rest of the command.
_interrupted = False


def on_sigint(signum, frame):
    """Ctrl-C: remembered, then raised as KeyboardInterrupt. Python drops an exception
    raised while it runs a weakref callback or a ``__del__`` ("Exception ignored in ..."):
    a fit on two processes, interrupted there, once ran on to its last step and exit
    status 0. The commands' per-step callbacks raise it again (:func:`check_interrupt`).
    Raised where a compiled function has called back into Python, numba reports it as a
    SystemError (:func:`..executor.interrupt_raised`): :func:`..cli.main` takes that for
    the interruption it is."""
    global _interrupted
    _interrupted = True
    raise KeyboardInterrupt


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if Ctrl-C came, even if its first raise was dropped."""
    if _interrupted:
        raise KeyboardInterrupt


def interrupted() -> bool:
    """Whether Ctrl-C came since the command began."""
    return _interrupted


def reset_interrupt() -> None:
    """A new command begins: no Ctrl-C has come."""
    global _interrupted
    _interrupted = False
