"""Crash-safe emcee checkpoints: opening, checking, recovering and starting them.

A checkpoint is two HDF5 files, ``chain.h5`` and its twin ``chain.twin.h5``, written in
turn and each sealed per write by :class:`.twin_backend.TwinBackend` (its module says
why and how). A run that continues a checkpoint takes the longer intact file, puts the
step count, acceptance counts and random state back to what its seal says, and copies
it over its twin. A file that cannot be read or whose steps do not match its seal is
never overwritten: it is moved aside to ``<name>.damaged`` (numbered if one exists) and
the run says so. When neither file is intact the run stops with :class:`CheckpointError`.

Each file holds the identity of the run that wrote it (:func:`.identity.run_identity`)
as one JSON attribute, :data:`IDENTITY_ATTR`; a run continues only a checkpoint of its
own identity, compared field by field (:func:`.identity.mismatch`), and refuses any
other with a one-line :class:`CheckpointError` that names the field and the fix.
Checkpoints of an earlier format (without that attribute: written before the identity
was data, or before the twin file) are refused too: their run starts over (``--fresh``).

This protects against the process being killed (SIGKILL, out of memory, a closed
terminal), not against the machine losing power: the files are not fsync'ed per step.
A kill loses the steps taken since the last write, at most ``WRITE_SECONDS`` of sampling,
which the continued run takes again, identically; Ctrl-C and errors lose nothing (the
run writes them as it stops).
"""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .identity import mismatch
from .twin_backend import (GROUP, WRITE_SECONDS, TwinBackend, check_write_seconds, restore_seal, sealed_steps,
                           twin_path, write_empty)

__all__ = ["CheckpointError", "Checkpoint", "open_checkpoint", "new_checkpoint", "read_chain", "steps_written",
           "stored_identity",
           "twin_path", "WRITE_SECONDS", "check_write_seconds", "IDENTITY_ATTR"]

#: The attribute of each file's chain group that holds its run's identity (JSON).
IDENTITY_ATTR = "bayes_inerter_identity"


class CheckpointError(ValueError):
    """A checkpoint that cannot be continued (damaged, of an earlier format, or made for
    another run)."""


@dataclass(frozen=True)
class _Inspection:
    path: Path
    status: str  # "missing", "empty" (no chain group), "old" (an earlier format), "intact" or "damaged"
    steps: int = 0
    why: str = ""
    identity: dict | None = None


def _inspect(path: Path) -> _Inspection:
    import h5py

    if not path.exists():
        return _Inspection(path, "missing")
    try:
        with h5py.File(path, "r", locking=False) as f:
            if GROUP not in f:
                return _Inspection(path, "empty")
            g = f[GROUP]
            if IDENTITY_ATTR not in g.attrs:  # an earlier format: refused, its steps not read
                return _Inspection(path, "old", identity={})
            identity = json.loads(g.attrs[IDENTITY_ATTR])
            n = sealed_steps(g)
            if n is None:
                return _Inspection(path, "damaged", why="its steps do not match their checksum")
            return _Inspection(path, "intact", n, identity=identity)
    except Exception as exc:  # h5py raises OSError, KeyError, ValueError for damaged files
        return _Inspection(path, "damaged", why=f"it is unreadable or truncated ({type(exc).__name__})")


def stored_identity(path) -> dict | None:
    """The run identity (:func:`.identity.run_identity`) that the checkpoint at ``path``
    (or its twin) was written with, or None where neither holds one that can be read, or
    where it holds no step: a chain that never took one (its start failed) has nothing
    to continue, and its identity must not pin the next run's coordinates."""
    path = Path(path)
    for s in (_inspect(path), _inspect(twin_path(path))):
        if s.status == "intact" and s.steps > 0:
            return s.identity
    return None


def _copy_atomically(src: Path, dst: Path) -> None:
    tmp = dst.with_name(dst.name + ".tmp")
    shutil.copyfile(src, tmp)
    os.replace(tmp, dst)


def _move_aside(path: Path) -> Path:
    target = path.with_name(path.name + ".damaged")
    k = 1
    while target.exists():
        k += 1
        target = path.with_name(f"{path.name}.damaged{k}")
    os.replace(path, target)
    return target


@dataclass(frozen=True)
class Checkpoint:
    """An opened checkpoint: its backend, the steps it holds, and what was recovered."""

    backend: TwinBackend
    steps: int
    recovered: str = ""


def open_checkpoint(path, *, identity: dict, fresh: bool = False,
                    write_seconds: float = WRITE_SECONDS) -> Checkpoint | None:
    """Open the checkpoint at ``path`` (and its twin) to continue it as the run
    ``identity`` (:func:`.identity.run_identity`).

    Returns None when there is nothing to continue (no files, or ``fresh``: both are
    deleted). Raises :class:`CheckpointError` when a file that can be read is of an
    earlier format or belongs to another run (its identity differs from ``identity``:
    the message names the first field that does), or when no intact copy exists.
    ``write_seconds`` is checked before any file is touched.
    """
    check_write_seconds(write_seconds)
    path = Path(path)
    twin = twin_path(path)
    if fresh:
        for p in (path, twin):
            p.unlink(missing_ok=True)  # the user asked to start over
    seen = [_inspect(path), _inspect(twin)]
    for s in seen:
        found = mismatch(s.identity, identity) if s.status in ("old", "intact") else None
        if found is not None:
            raise CheckpointError(f"{s.path}: the checkpoint was written {found.what}; {found.fix}")
    intact = [s for s in seen if s.status == "intact"]
    damaged = [s for s in seen if s.status == "damaged"]
    if not intact:
        if damaged:
            why = damaged[0].why
            raise CheckpointError(
                f"{path}: checkpoint cannot be continued: {why}, and no intact copy is left; it is "
                "left as it is: move it away to keep it, or run with --fresh to start over"
            )
        return None
    best = max(intact, key=lambda s: s.steps)  # max keeps the first (chain.h5) on a tie
    notes = [f"{s.path.name} {s.why}: kept as {_move_aside(s.path).name}" for s in damaged]
    other = twin if best.path == path else path
    _copy_atomically(best.path, other)
    for p in (other, best.path):
        restore_seal(p)
    recovered = ""
    if notes:
        recovered = "; ".join(notes) + f"; continuing from {best.path.name} ({best.steps} steps)"
    return Checkpoint(TwinBackend(path, write_seconds=write_seconds), best.steps, recovered)


def new_checkpoint(path, *, identity: dict, write_seconds: float = WRITE_SECONDS) -> TwinBackend:
    """Make both files of a new, empty checkpoint of the run ``identity``
    (:func:`.identity.run_identity`: its ``nwalkers`` and ``ndim`` give the chain's
    shape, its model's parameters the attribute ``parameter_names``); each file appears
    whole or not at all (none for a bad ``write_seconds``)."""
    check_write_seconds(write_seconds)
    path = Path(path)
    tmp = path.with_name(path.name + ".new")
    tmp.unlink(missing_ok=True)
    attrs = {IDENTITY_ATTR: json.dumps(identity, allow_nan=False)}
    names = (identity.get("model") or {}).get("parameters")
    if names:
        attrs["parameter_names"] = ",".join(names)
    write_empty(tmp, int(identity["nwalkers"]), int(identity["ndim"]), attrs)
    _copy_atomically(tmp, twin_path(path))
    os.replace(tmp, path)
    return TwinBackend(path, write_seconds=write_seconds)


def read_chain(path, *, log_prob: bool = False):
    """The steps of the checkpoint at ``path`` that a continued run would keep: the
    sealed steps of its longer intact file, shape (steps, walkers, parameters); with
    ``log_prob``, (those steps, their log-probabilities (steps, walkers)), both from that
    file. Safe to call while a run writes it."""
    import h5py

    path = Path(path)
    seen = [_inspect(path), _inspect(twin_path(path))]
    intact = [s for s in seen if s.status == "intact"]
    if not intact:
        older = any(s.status == "old" for s in seen)
        raise CheckpointError(f"{path}: no intact checkpoint there"
                              + (" (it was written by an older version of bayes-inerter)" if older else ""))
    best = max(intact, key=lambda s: s.steps)
    with h5py.File(best.path, "r", locking=False) as f:
        chain = f[GROUP]["chain"][: best.steps].copy()
        return (chain, f[GROUP]["log_prob"][: best.steps].copy()) if log_prob else chain


def steps_written(path) -> int:
    """The steps ``chain.h5`` at ``path`` says it holds, read without checking them (for
    watching a run from outside; 0 while the file is missing or half-written)."""
    import h5py

    try:
        with h5py.File(path, "r", locking=False) as f:
            return int(f[GROUP].attrs["iteration"])
    except (OSError, KeyError):
        return 0
