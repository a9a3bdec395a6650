"""arviz, imported where processes start at once (`module()`).

arviz's import writes a stamp file once a day (the day it last warned of its refactor)
through a temporary file of one fixed name. Two processes importing it for the day's
first time together (a study's forked workers, pytest-xdist's) can each write that
file and one then finds it renamed away by the other: FileNotFoundError from the import
itself, seen on a clean machine. The stamp is there by then, so a second import goes
through."""


def module():
    """The arviz module, imported (a second time if the first met the stamp race)."""
    try:
        import arviz
    except FileNotFoundError:
        import arviz
    return arviz
