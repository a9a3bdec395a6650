"""The command line: ``bayes-inerter COMMAND ...``.

Exit status: 0 success; 1 bad input or a failed run (one-line error, no traceback);
2 usage error (argparse); 130 interrupted; 141 the output's reader closed the pipe.

Here: how a command runs (the one-line error, Ctrl-C). The exit statuses, the error
and the interruption's flag are in :mod:`.status`; the options in :mod:`.parser`; the
commands in :mod:`.records` (``generate``, ``inspect``, ``demo``), :mod:`.fit`,
:mod:`.identify` and :mod:`.study` (``study``, ``report``).
"""

from __future__ import annotations

import sys

from ..executor import caused_by_interrupt
from .fit import cmd_fit
from .identify import cmd_identify
from .parser import (BLOCK_PARTNERS, CHECKPOINT_SECONDS, DEFAULT_BLOCK_PARTNERS, DEFAULT_RESIDUAL,  # noqa: F401
                     FIT_COORDINATES, FIT_RESIDUALS, RECORD_CHECKS, build_parser)  # (tests' names)
from .records import cmd_demo, cmd_generate, cmd_inspect
from .status import (EXIT_FAIL, EXIT_INTERRUPTED, EXIT_PIPE, CliError, interrupted, on_sigint,  # noqa: F401
                     reset_interrupt)  # (CliError: tests' name)
from .study import cmd_report, cmd_study

__all__ = ["main"]


def _stdout_to_devnull() -> None:
    import os

    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _flush_quietly() -> None:
    """Flush stdout on every way out of :func:`main`. Where stdout is buffered (not a
    terminal, no PYTHONUNBUFFERED) a closed pipe shows only at a flush; left to Python's
    flush at exit it ends the process with status 120 and a message, whatever the
    command's own status (a failed command's 1 too)."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _stdout_to_devnull()


def main(argv=None) -> int:
    import signal
    import threading

    # the commands looked up as main runs: a test puts its own in their place
    parser = build_parser({"demo": cmd_demo, "generate": cmd_generate, "fit": cmd_fit, "identify": cmd_identify,
                           "study": cmd_study,
                           "report": cmd_report, "inspect": cmd_inspect})
    args = parser.parse_args(argv)
    reset_interrupt()
    # Ctrl-C's own handler, where Python's default one is in place (not where SIGINT is
    # ignored, as in a background job, nor off the main thread); restored on the way out
    previous = signal.getsignal(signal.SIGINT)
    ours = previous is signal.default_int_handler and threading.current_thread() is threading.main_thread()
    if ours:
        signal.signal(signal.SIGINT, on_sigint)
    import warnings

    import numpy as np

    # library warnings that mean nothing to a user (arviz's FutureWarning on import,
    # numpy's on an overflow the code handles); the commands say what matters in words
    try:
        import logging

        logging.getLogger("arviz").setLevel(logging.ERROR)  # shape warnings of short chains, said in words
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.filterwarnings("ignore", category=FutureWarning)
            warnings.filterwarnings("ignore", category=RuntimeWarning)
            code = args.func(args)
        sys.stdout.flush()  # a closed pipe shows here, where it is handled (see _flush_quietly)
        if interrupted():  # came where it could only be dropped, and nothing asked again
            raise KeyboardInterrupt
        return code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (| head): nothing more to say, to anyone
        _stdout_to_devnull()
        return EXIT_PIPE
    except Exception as exc:
        # an error Ctrl-C caused (numba's SystemError where it came inside compiled code) is
        # the interruption, not a failure
        if interrupted() or caused_by_interrupt(exc):
            print("interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
        if not isinstance(exc, (CliError, ValueError, OSError, RuntimeError)):
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FAIL
    finally:
        if ours:
            signal.signal(signal.SIGINT, previous)
        _flush_quietly()

