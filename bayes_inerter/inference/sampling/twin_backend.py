"""The twin-file emcee back end: two HDF5 files written in turn, each sealed per write.

emcee's ``HDFBackend`` writes each step in place. A process killed in the middle of such
a write can leave the file unreadable (seen here: HDF5's 'addr overflow'), or readable
but with the random state of step k beside the step count of step k - 1 (emcee writes
the random state before it counts the step), so that the continued chain is no longer
the one an uninterrupted run gives.

Here (:class:`TwinBackend`) the steps go to ``chain.h5`` as they are taken, at most
:data:`WRITE_SECONDS` apart (every step of a run whose steps take longer), and, every
:data:`TWIN_EVERY` steps and when the run ends, to ``chain.twin.h5``. Each write *seals*
its file in the same open: one attribute that holds the number of steps it vouches for,
a sha256 chained over those steps (positions, log probabilities, blobs), the acceptance
counts and the sampler's random state after the last of them (and the sha256 of any
state of its own the sampler stores beside them, :data:`EXTRA`). A kill can damage at most
the one file being written at that moment; the other is intact, and at most
``TWIN_EVERY`` steps behind. Opening, checking and recovering the pair is
:mod:`.checkpoint`'s.

The back end subclasses emcee's ``HDFBackend`` and relies on some of its internals
(``tests/test_inference_twin_backend.py`` pins them).
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import emcee
import numpy as np

__all__ = ["TwinBackend", "twin_path", "TWIN_EVERY", "WRITE_SECONDS", "check_write_seconds", "write_empty",
           "sealed_steps", "restore_seal", "read_extra", "GROUP", "SEAL", "EXTRA", "STEP_ROWS"]

#: The HDF5 group that holds the chain (emcee's ``name``).
GROUP = "mcmc"
#: The attribute of the seal (see module docstring).
SEAL = "bayes_inerter_seal"
#: The chain group's subgroup of the sampler's own state after the last sealed step
#: (named arrays; a tempered run's hot ensembles, :mod:`.tempering`), in two slots
#: written in turn, each overwritten in place: the seal names the slot of its step and
#: holds its sha256, so a kill while one slot is written leaves the sealed one whole.
EXTRA = "sampler_state"

#: The chain group's datasets that hold the sampler's own state at every step, beside
#: emcee's chain, log probabilities and blobs (a tempered run's hot ensembles' walkers
#: and every slot's replica label, :mod:`.tempering`; what the convergence rule reads to
#: follow the replicas, :func:`.convergence.check_chain`). Written and sealed with the
#: step, in this order; absent from a run that stores none.
STEP_ROWS = ("hot_chain", "replicas")

#: Every per-step dataset of the chain group in the order the seal hashes a step.
_HASHED = ("chain", "log_prob", "blobs") + STEP_ROWS


def twin_path(path) -> Path:
    """The second file of a checkpoint: ``chain.h5`` -> ``chain.twin.h5``."""
    path = Path(path)
    return path.with_name(path.stem + ".twin" + path.suffix)


class _Backend(emcee.backends.HDFBackend):
    """emcee's HDF5 backend, opening the file without HDF5's advisory lock.

    With the lock, anyone reading ``chain.h5`` while a run writes it (h5py, a viewer)
    makes the run's next write fail with BlockingIOError and the run stop (seen here).
    A reader may then see a step half-written; the writer never fails. Same logic as
    ``HDFBackend.open`` (emcee 3.1) otherwise.
    """

    def open(self, mode="r"):
        import h5py

        if self.read_only and mode != "r":
            raise RuntimeError("the backend is read-only")
        f = h5py.File(self.filename, mode, locking=False)
        if not self.dtype_set and self.name in f:
            g = f[self.name]
            if "chain" in g:
                self.dtype = g["chain"].dtype
                self.dtype_set = True
        return f


#: The twin file is brought up to date every this many steps (and when a run ends or
#: stops): a kill that damages chain.h5 costs at most this many steps, which the
#: continued run takes again, identically. Writing the twin at every step would double
#: the checkpoint's cost for nothing a continued run needs.
TWIN_EVERY = 10

#: Steps are written to chain.h5 at most this many seconds apart (default 2; 0: every
#: step), and a kill loses at most this much sampling (the continued run takes it again,
#: identically). A write costs a few milliseconds however many steps it carries: at every
#: step it was about 10 % of a two-port step's 24 evaluations. Measured on 1,000-step fits
#: of a paper-like A3 record at 1 Hz (two rounds, alternating, beside two other
#: processes): every 0.5 s, 64 and 70 writes of 4.2 and 4.5 ms and sampling 1.163 and
#: 1.167 times its evaluations; every 2 s, 22 and 24 writes and 1.153 and 1.145 times.
WRITE_SECONDS = 2.0


def check_write_seconds(seconds: float) -> float:
    """``seconds`` as the interval between writes (:data:`WRITE_SECONDS`), or ValueError."""
    if not seconds >= 0:
        raise ValueError(f"checkpoint write interval must be a non-negative number of seconds, got {seconds}")
    return float(seconds)


class TwinBackend(_Backend):
    """Writes and seals the steps in its own file in one open, at most ``write_seconds``
    apart (every step where steps take longer), and the same steps in the twin file every
    ``twin_every`` steps and on :meth:`flush`; reads from its own, after writing what it
    holds."""

    def __init__(self, filename, twin_every: int = TWIN_EVERY, write_seconds: float = WRITE_SECONDS, **kwargs):
        self.write_seconds = check_write_seconds(write_seconds)
        super().__init__(str(filename), name=GROUP, **kwargs)
        self.twin = _Backend(str(twin_path(filename)), name=GROUP, **kwargs)
        self.twin_every = twin_every
        self._held = []  # steps taken and not yet written to chain.h5
        self._last_write = time.monotonic()
        self._pending = []  # steps written to chain.h5 and not yet to the twin
        self._sums = {}  # file -> running sha256 over its sealed steps, read from its seal once
        self._facts = {}  # iteration, shape, has_blobs: read from chain.h5 once, kept up to date here

    # emcee's HDF5 backend opens the file for each of these, and emcee's check of every
    # step asks four times, the progress bar once more: five opens of chain.h5 a step
    # besides the write, about 3 ms of a two-port step's 24 evaluations of about 1 ms.
    # This backend is the only writer of chain.h5 while a run holds it, so it answers
    # from what it read once and what it wrote since.
    def _fact(self, name: str, read):
        if name not in self._facts:
            self._facts[name] = read()
        return self._facts[name]

    @property
    def iteration(self):
        """Steps taken, the ones not yet written included."""
        return self._fact("iteration", lambda: int(_Backend.iteration.fget(self))) + len(self._held)

    # everything read from the file comes after the steps held are written
    def get_value(self, name, flat=False, thin=1, discard=0):
        self._write_held()
        return super().get_value(name, flat=flat, thin=thin, discard=discard)

    @property
    def accepted(self):
        self._write_held()
        return _Backend.accepted.fget(self)

    @property
    def random_state(self):
        self._write_held()
        return _Backend.random_state.fget(self)

    @property
    def extra(self) -> dict | None:
        """The sampler's extra state after the last step (:meth:`save_step`), None where
        the run stores none."""
        self._write_held()
        with self.open() as f:
            return read_extra(f[GROUP])

    def has_rows(self, name: str) -> bool:
        """Whether the chain keeps the per-step dataset ``name`` (:data:`STEP_ROWS`) for
        every step it holds: one that did not from its first step never does."""
        if self.iteration == 0:
            return True
        self._write_held()
        with self.open() as f:
            return name in f[GROUP]

    def get_rows(self, name: str, start: int = 0) -> np.ndarray:
        """The per-step dataset ``name`` (:data:`STEP_ROWS`) from step ``start`` to the
        last one taken; KeyError where the chain keeps none."""
        self._write_held()
        with self.open() as f:
            g = f[GROUP]
            return g[name][start:int(g.attrs["iteration"])]

    @property
    def shape(self):
        return self._fact("shape", lambda: tuple(int(v) for v in _Backend.shape.fget(self)))

    def has_blobs(self):
        return self._fact("has_blobs", lambda: bool(_Backend.has_blobs(self)))

    def reset(self, nwalkers, ndim):  # pragma: no cover - new_checkpoint makes the files
        self._facts = {}
        super().reset(nwalkers, ndim)
        self.twin.reset(nwalkers, ndim)

    def grow(self, ngrow, blobs):
        self._write_held()  # emcee grows from the file's step count
        super().grow(ngrow, blobs)
        self._facts.pop("has_blobs", None)  # the first growth with blobs sets it (after asking)
        self.twin.grow(ngrow, blobs)

    def save_step(self, state, accepted, extra: dict | None = None, rows: dict | None = None):
        """Hold the step ``state`` (emcee's); ``extra``: named arrays of the sampler's own
        state after it (same names and shapes at every step of a run), written and sealed
        with it (:data:`EXTRA`; what a tempered run's hot ensembles need to go on);
        ``rows``: named arrays kept for every step (:data:`STEP_ROWS`, same shapes at
        every step), stored only by a chain that has kept them from its first step
        (:meth:`has_rows`)."""
        self._check(state, accepted)
        if rows is not None and set(rows) != set(STEP_ROWS):  # all or none: a dataset left out would be lost
            raise ValueError(f"per-step rows must be all of {STEP_ROWS}, got {sorted(rows)}")
        values = {"chain": np.array(state.coords), "log_prob": np.array(state.log_prob)}
        if state.blobs is not None:
            values["blobs"] = np.array(state.blobs)
        values.update({k: np.array(v) for k, v in (rows or {}).items()})
        row = (values, np.asarray(accepted), state.random_state, extra)
        self._held.append(row)
        if time.monotonic() - self._last_write >= self.write_seconds:
            self._write_held()
            if len(self._pending) >= self.twin_every:
                self.flush()

    def _write_held(self) -> None:
        """Write the steps held to chain.h5 (sealed); the twin's turn comes later."""
        if self._held:
            # a write stopped part-way (Ctrl-C inside it) loses these steps, as a kill
            # would: chain.h5 may be damaged, and the twin gets only what was written
            rows, self._held = self._held, []
            self._append(self.filename, rows)
            self._pending.extend(rows)
        self._last_write = time.monotonic()

    def flush(self) -> None:
        """Write every step held to chain.h5 and bring the twin file up to date (called
        every ``twin_every`` steps and when a run ends or stops)."""
        self._write_held()
        if self._pending:
            self._append(self.twin.filename, self._pending)
            self._pending = []

    def _append(self, filename, rows) -> None:
        """Write ``rows`` (steps) and the seal that covers them, in one open of the file."""
        import h5py

        with h5py.File(filename, "a", locking=False) as f:
            g = f[GROUP]
            it = int(g.attrs["iteration"])
            if filename not in self._sums:
                seal = json.loads(g.attrs[SEAL])
                if seal["steps"] != it:  # not sealed up to here: hash from the start
                    self._sums[filename] = _rows_hash(g, 0, it, b"")
                else:
                    self._sums[filename] = bytes.fromhex(seal["sha256"])
            h = self._sums[filename]
            need = it + len(rows)
            if it == 0:  # a chain keeps its per-step rows from its first step, or never
                for name in STEP_ROWS:
                    if name in rows[0][0] and name not in g:
                        first = np.asarray(rows[0][0][name])
                        g.create_dataset(name, (0,) + first.shape, first.dtype, maxshape=(None,) + first.shape,
                                         chunks=(max(1, 4096 // max(first.size, 1)),) + first.shape)
            names = [name for name in _HASHED if name in g]
            for name in names:
                if g[name].shape[0] < need:
                    g[name].resize(need, axis=0)
            stored = [[np.asarray(row[0][name], dtype=g[name].dtype) for name in names] for row in rows]
            for j, name in enumerate(names):  # one block a dataset: a row at a time cost a write per row
                g[name][it:need] = np.stack([values[j] for values in stored])
            for values in stored:
                h = _step_hash(h, *values)
            acc = g["accepted"]
            accepted = acc[:] + np.sum([r[1] for r in rows], axis=0).astype(acc.dtype)
            acc[:] = accepted
            random_state = rows[-1][2]
            for i, v in enumerate(random_state):
                g.attrs[f"random_state_{i}"] = v
            extra = rows[-1][3]
            extra_seal = None
            if extra is not None:  # into the slot the seal does not vouch for: a kill here leaves the file intact
                slot = str(1 - int(json.loads(g.attrs[SEAL]).get("extra_slot", 1)))
                for name, values in extra.items():
                    values = np.asarray(values)
                    g.require_dataset(f"{EXTRA}/{slot}/{name}", values.shape, values.dtype, exact=True)[...] = values
                extra_seal = (slot, _extra_hash(g[EXTRA][slot]))
            g.attrs["iteration"] = need
            g.attrs[SEAL] = _seal_text(need, h, accepted, random_state, extra_seal)
            self._sums[filename] = h
        if filename == self.filename:
            self._facts["iteration"] = need


def _step_hash(h: bytes, *rows) -> bytes:
    return hashlib.sha256(h + b"".join(np.ascontiguousarray(r).tobytes() for r in rows)).digest()


def _rows_hash(g, start: int, stop: int, h: bytes) -> bytes:
    names = [n for n in _HASHED if n in g]
    if stop > start:
        blocks = [g[n][start:stop] for n in names]
        for i in range(stop - start):
            h = _step_hash(h, *(b[i] for b in blocks))
    return h


def _seal_text(steps: int, h: bytes, accepted, random_state, extra: tuple | None = None) -> str:
    """The seal attribute: the steps it vouches for, their running sha256, the acceptance
    counts and numpy's random state after the last of them (None before any step), and
    where the sampler stores state of its own (:data:`EXTRA`), the slot that holds it and
    its sha256 (``extra``: (slot, sha256))."""
    rs = None if random_state is None else [
        str(random_state[0]), np.asarray(random_state[1]).tolist(), int(random_state[2]), int(random_state[3]),
        float(random_state[4])]
    seal = {"steps": steps, "sha256": h.hex(), "accepted": np.asarray(accepted).tolist(), "random_state": rs}
    if extra is not None:
        seal["extra_slot"], seal["extra_sha256"] = extra
    return json.dumps(seal)


def _extra_hash(slot) -> str:
    """The sha256 over one slot of the sampler's extra state (its arrays in name order)."""
    h = hashlib.sha256()
    for name in sorted(slot):
        h.update(name.encode() + np.ascontiguousarray(slot[name][...]).tobytes())
    return h.hexdigest()


def _sealed_slot(g, seal: dict):
    """The extra state's slot that ``seal`` vouches for, or None where it has none or the
    slot does not match its sha256."""
    slot = seal.get("extra_slot")
    if slot is None or EXTRA not in g or slot not in g[EXTRA]:
        return None
    return g[EXTRA][slot] if _extra_hash(g[EXTRA][slot]) == seal["extra_sha256"] else None


def read_extra(g) -> dict | None:
    """The sampler's extra state that the seal of the chain group ``g`` vouches for (named
    arrays), None where it has none."""
    slot = _sealed_slot(g, json.loads(g.attrs[SEAL]))
    return None if slot is None else {name: slot[name][...] for name in slot}


def write_empty(path, nwalkers: int, ndim: int, attrs: dict) -> None:
    """Write at ``path`` an empty chain of ``nwalkers`` x ``ndim`` (emcee's layout), with
    ``attrs`` on its group and a seal of no steps."""
    b = _Backend(str(path), name=GROUP)
    b.reset(nwalkers, ndim)
    with b.open("a") as f:
        g = f[GROUP]
        for k, v in attrs.items():
            g.attrs[k] = v
        g.attrs[SEAL] = _seal_text(0, b"", g["accepted"][:], None)


def sealed_steps(g) -> int | None:
    """The steps the seal of the chain group ``g`` vouches for, or None when they are not
    all in the file or do not match its sha256 (damaged). KeyError without a seal."""
    seal = json.loads(g.attrs[SEAL])
    n = int(seal["steps"])
    if n > g["chain"].shape[0] or _rows_hash(g, 0, n, b"").hex() != seal["sha256"]:
        return None
    if "extra_sha256" in seal and _sealed_slot(g, seal) is None:
        return None
    return n


def restore_seal(path) -> None:
    """Put the step count, acceptance counts and random state of the file at ``path``
    back to its seal's (a kill may have left emcee's own ahead of them)."""
    import h5py

    with h5py.File(path, "a", locking=False) as f:
        g = f[GROUP]
        seal = json.loads(g.attrs[SEAL])
        g.attrs["iteration"] = seal["steps"]
        g["accepted"][:] = np.asarray(seal["accepted"], dtype=g["accepted"].dtype)
        rs = seal["random_state"]
        if rs is not None:
            values = [rs[0], np.asarray(rs[1], dtype=np.uint32), int(rs[2]), int(rs[3]), float(rs[4])]
            for i, v in enumerate(values):
                g.attrs[f"random_state_{i}"] = v
