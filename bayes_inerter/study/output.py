"""What a study's ``run(config, out, executor, *, progress=None)`` returns.

Every study module of this package (``bayes_inerter.study.<name>``) has a frozen
``Config`` dataclass and that ``run``; ``bayes_inerter.cli.study_script`` makes the
command line of any of them. docs/development.md ("Where a new piece goes") says how
to add one.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["StudyOutput"]


@dataclass(frozen=True)
class StudyOutput:
    """The files a study wrote, the work items that failed (each ``(item, message)``),
    lines worth showing a reader (a table's rows, as text), and its numbers by name."""

    written: tuple = ()
    failed: tuple = ()
    lines: tuple = ()
    values: dict = field(default_factory=dict)
