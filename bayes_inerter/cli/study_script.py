"""The command line of a study: its configuration's fields as options, its executor, its
progress, its one-line errors.

Every study of this package has one shape, so that its script is a few lines::

    from bayes_inerter.cli.study_script import study_main
    from bayes_inerter.study import design

    sys.exit(study_main(design, out=ROOT / "results" / "design", doc=__doc__))

The study module (``bayes_inerter.study.<name>``) holds

- ``Config``: a frozen dataclass, every field with a default (the study as committed);
  a field's ``metadata`` may hold ``help`` and ``choices``;
- ``run(config, out, executor, *, progress=None) -> StudyOutput``
  (``bayes_inerter.study.output``): the study, written
  into the folder ``out``, its parallel work on ``executor``
  (``bayes_inerter.executor.Executor``), ``progress(done, total)`` told as it goes,
  a ``ValueError`` for a configuration or folder it cannot use.

:func:`study_main` makes one option of each field (``--field-name``; a bool field a
switch, a tuple field takes several values, a field whose default is None takes its
type's values), adds ``--out``, ``--processes`` and ``--scheduler``, adds the run to the
folder's manifest (``study.manifest.write_manifest``), runs the study with a progress bar on
standard error, and prints the files written. Exit codes (``cli.status``): 0 done, 1 some of the work
failed (the output says which), 2 a bad option or folder (a one-line error naming the
cause), 130 interrupted (everything finished is kept; run the command again to go on).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import types
import typing
from pathlib import Path
from typing import Any, Callable

from ..study.output import StudyOutput
from .status import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE

__all__ = ["config_options", "config_from_arguments", "config_from_folder", "study_main", "StudyOutput"]


def _simple(hint) -> tuple[type | None, bool]:
    """(element type, is a tuple) of a field's type hint (``X | None`` read as X); element
    None where the command line cannot give it (a nested dataclass)."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(args) != 1:
            return None, False
        hint = args[0]
        origin = typing.get_origin(hint)
    if hint is tuple or origin is tuple:
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        elem = args[0] if args else str
        return (elem if elem in (int, float, str) else None), True
    return (hint if hint in (int, float, str, bool) else None), False


def _command_line_fields(config_type) -> list[tuple]:
    """(field, element type, is a tuple) of each field of ``config_type`` the command line
    can give."""
    hints = typing.get_type_hints(config_type)
    out = []
    for f in dataclasses.fields(config_type):
        elem, many = _simple(hints[f.name])
        if elem is not None and not f.name.startswith("_"):
            out.append((f, elem, many))
    return out


def config_options(parser: argparse.ArgumentParser, config_type) -> list[str]:
    """Add an option for each field of ``config_type`` the command line can give; returns
    the fields' names."""
    names = []
    for f, elem, many in _command_line_fields(config_type):
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        flag = "--" + f.name.replace("_", "-")
        meta = dict(f.metadata)
        shown = "" if default is None else f" (default: {' '.join(map(str, default)) if many else default})"
        kw: dict[str, Any] = {"dest": f.name, "default": default, "help": meta.get("help", "") + shown}
        if elem is bool:
            kw["action"] = argparse.BooleanOptionalAction
        else:
            kw["type"] = elem
            if many:
                kw["nargs"] = "+"
            if "choices" in meta:
                kw["choices"] = meta["choices"]
        parser.add_argument(flag, **kw)
        names.append(f.name)
    return names


def config_from_arguments(config_type, args: argparse.Namespace, names) -> Any:
    """``config_type`` from the parsed options (a tuple field's values as a tuple); the
    dataclass's own checks raise ValueError on a bad value."""
    values = {}
    for name in names:
        v = getattr(args, name)
        values[name] = tuple(v) if isinstance(v, list) else v
    return config_type(**values)


def config_from_folder(config_type, folder, run: int = 0) -> Any:
    """``config_type`` as a results folder's run was given it (its ``manifest.json``'s
    entry ``run``, the fields a command line gives read as :func:`config_from_arguments`
    reads them): to fit that folder's replicates again. A field newer than the run, or
    one the command line cannot give, is at its default."""
    import json

    from ..study.manifest import MANIFEST

    given = json.loads((Path(folder) / MANIFEST).read_text())["runs"][run]["configuration"]["config"]
    names = [f.name for f, _, _ in _command_line_fields(config_type) if f.name in given]
    return config_from_arguments(config_type, argparse.Namespace(**given), names)


def _bar(desc: str) -> tuple[Callable, Callable]:
    """(progress, close) of a bar on standard error, made at the first progress a study
    reports (none for one that reports none), that also prints where standard error is
    not a terminal (at most every 30 s there). Its first line counts what a continued
    run found done, not 0."""
    from tqdm import tqdm

    shown = []

    def progress(done: int, total: int) -> None:
        if not shown:
            shown.append(tqdm(desc=desc, total=total, initial=done, unit="item", file=sys.stderr,
                              mininterval=0.5 if sys.stderr.isatty() else 30))
        bar = shown[0]
        bar.total = total
        bar.update(done - bar.n)

    def close() -> None:
        if shown:
            shown[0].close()

    return progress, close


def study_main(module, *, out, doc: str | None = None, argv=None) -> int:
    """Run the study ``module`` (see the module docstring) from the command line
    ``argv`` (default: the script's own); ``out``: the default output folder, or a
    function of the configuration that names it. Returns the exit code."""
    from ..executor import make_executor
    from ..study.manifest import write_manifest

    name = module.__name__.rsplit(".", 1)[-1]
    ap = argparse.ArgumentParser(prog=f"{name}.py", description=doc or module.__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    names = config_options(ap, module.Config)
    ap.add_argument("--out", default=None, help="the folder the study writes (default: "
                    + ("one named by the configuration" if callable(out) else str(out)) + ")")
    ap.add_argument("--processes", type=int, default=min(2, os.cpu_count() or 1),
                    help="local worker processes (default: %(default)s)")
    ap.add_argument("--scheduler", default=None, help="a Dask scheduler's address, in place of local processes")
    args = ap.parse_args(argv)
    try:
        config = config_from_arguments(module.Config, args, names)
        executor = make_executor(args.processes, args.scheduler)
        args.out = args.out or str(out(config) if callable(out) else out)
    except (ValueError, TypeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    progress, close = _bar(name)
    try:
        write_manifest(args.out, {"study": name, "config": dataclasses.asdict(config),
                                  "processes": args.processes, "scheduler": args.scheduler})
        with executor:
            got = module.run(config, Path(args.out), executor, progress=progress)
    except KeyboardInterrupt:
        close()
        print(f"interrupted: what finished is kept in {args.out}; run the same command to go on", file=sys.stderr)
        return EXIT_INTERRUPTED
    except ValueError as exc:
        close()
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    close()
    for line in got.lines:
        print(line)
    for path in got.written:
        print(f"wrote {path}")
    for item, message in got.failed:
        print(f"failed: {item}: {message}", file=sys.stderr)
    return EXIT_FAIL if got.failed else EXIT_OK
