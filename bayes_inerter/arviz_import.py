"""arviz, imported where processes start at once (`module()`).

arviz's import writes a stamp file once a day (the day it last warned of its refactor)
through a temporary file of one fixed name. Two processes importing it for the day's
first time together (a study's forked workers, pytest-xdist's) can each write that
file and one then finds it renamed away by the other: FileNotFoundError from the import
itself, seen on a clean machine. The stamp is there by then, so a second import goes
through.

The warning itself (a FutureWarning that arviz 1.x will change its interface) is kept
out: the package pins arviz below 1 (pyproject.toml), so it tells a user nothing they
can act on, and on a fresh machine it was the one warning of the test run."""

import warnings

#: The start of arviz's once-a-day notice of its 1.x refactor (a FutureWarning).
REFACTOR_NOTICE = r"\s*ArviZ is undergoing a major refactor"


def module():
    """The arviz module, imported (a second time if the first met the stamp race),
    without its refactor notice (module docstring)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=REFACTOR_NOTICE, category=FutureWarning)
        try:
            import arviz
        except FileNotFoundError:
            import arviz
    return arviz
