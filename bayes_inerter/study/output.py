"""What a study's ``run(config, out, executor, *, progress=None)`` returns, and how it
writes one work item's result (:func:`write_json`).

Every study module of this package (``bayes_inerter.study.<name>``) has a frozen
``Config`` dataclass and that ``run``; ``bayes_inerter.cli.study_script`` makes the
command line of any of them. docs/development.md ("Where a new piece goes") says how
to add one.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["StudyOutput", "write_json"]


@dataclass(frozen=True)
class StudyOutput:
    """The files a study wrote, the work items that failed (each ``(item, message)``),
    lines worth showing a reader (a table's rows, as text), and its numbers by name."""

    written: tuple = ()
    failed: tuple = ()
    lines: tuple = ()
    values: dict = field(default_factory=dict)


def write_json(path, value, *, indent: int | None = None) -> None:
    """``value`` as JSON (and a newline) in ``path``, written whole or not at all: a run
    killed while it writes leaves no half-written result for the next run to read."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(value, indent=indent) + "\n")
    tmp.replace(path)
