"""The one generator of specialised kernel source.

A kernel is generated for one network shape: its sizes, its contacts' nodes, its output
node and its augmented matrix's nonzero pattern. The templates (``templates.py``) are the
algorithm: a line ``$name(args)`` there stands for a block of written-out arithmetic (a
step, the guards, a copy of the state) that the functions below produce for the shape,
with the state and the guards in local variables. Every sum is formed in the
order of j, so that the numbers do not depend on how the code is laid out; terms where
the pattern has a structural zero are left out (a term 0 * z adds nothing to a sum that
starts at 0.0), and the exponential tables are taken as dense.

Why generate at all: a kernel that learns its sizes at run time keeps the state in
arrays, and the compiler must then reload state, tables and guards from memory at every
sample (about 20 ns a sample of bookkeeping); with fixed sizes the state lives in
registers. Golden files of the output for the paper's networks are kept with the tests
(``tests/golden``), so that any change of the generated code shows in review.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .templates import (CLEAR_BAND, CLEAR_TEST, CROSSED, CROSSED_BAND, CROSSED_CONTACT, EVENTS, GUARD,
                        GUARD_LINK, KERNEL)

__all__ = ["Shape", "RichShape", "kernel_source"]


@dataclass(frozen=True)
class Shape:
    """What a kernel is specialised to: state size ``n``, ``n_in`` inputs, the contacts'
    nodes, the output node, and the augmented matrix's nonzero pattern
    (``(Abar != 0).tobytes()``, or None for a dense one)."""

    n: int
    n_in: int
    node: tuple
    out_node: int
    nonzero: bytes | None = None

    @property
    def nc(self) -> int:
        return len(self.node)

    @property
    def wcol(self) -> int:
        return self.n + 2 * self.n_in

    @property
    def m(self) -> int:
        return self.wcol + self.nc

    def columns(self):
        """The columns where the guards' rows and the output row can be nonzero: a
        contact's holding force R (its node's row without the Coulomb forces), its rate
        R @ Abar, its acceleration (its node's row); the output node's row."""
        m, wcol = self.m, self.wcol
        P = np.ones((m, m), dtype=bool) if self.nonzero is None else np.frombuffer(self.nonzero, bool).reshape(m, m)
        r_cols, vd_cols, rd_cols = [], [], []
        for i in range(self.nc):
            r = P[self.node[i]].copy()
            r[wcol:] = False
            r_cols.append(np.flatnonzero(r).tolist())
            vd_cols.append(np.flatnonzero(P[self.node[i]]).tolist())
            rd_cols.append(np.flatnonzero((r[:, None] & P).any(axis=0)).tolist())
        return r_cols, vd_cols, rd_cols, np.flatnonzero(P[self.out_node]).tolist()


def dot(coef, vec: str, cols) -> str:
    """The expression 0.0 + coef(j) * vec_j + ... for j in cols, summed in that order."""
    expr = "0.0"
    for j in cols:
        expr = f"({expr} + {coef(j)} * {vec}{j})"
    return expr


#: How the coefficients are read: from locals loaded at each mode change (the common
#: step, ``fast``) or from the arrays (the rare path, ``rare``).
COEFFICIENTS = {
    "fast": {"F": "f{i}_{j}", "R": "r{i}_{j}", "RD": "rd{i}_{j}", "VD": "vd{i}_{j}"},
    "rare": {"F": "F[mode, level, {i}, {j}]", "R": "R[{i}, {j}]", "RD": "RD[mode, {i}, {j}]",
             "VD": "VD[mode, {i}, {j}]"},
}


#: The Coulomb kernel's arguments and its calls of the compiled helpers.
CALLS = {
    "kernel_params": "Abar, n_, n_in_, node, f0, mass, inputs, h, z_init, out_node_, store, max_events",
    "setup": ["J, F, VD, RD, OUT, R = setup(Abar, np.int64(n), np.int64(n_in), node, mass, h, out_node_)"],
    "start": ["z, sgn, mode = start(z_init, inputs, np.int64(n), np.int64(n_in), np.int64(m), node, R, f0)"],
    "events_params": "F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events",
    "events_args": "F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events",
}


class _Blocks:
    """The blocks the templates name, for one shape (Coulomb contacts)."""

    coefficients = COEFFICIENTS

    def __init__(self, shape: Shape):
        self.s = shape
        self.ne = shape.nc  # the guards: one per contact
        self.r_cols, self.vd_cols, self.rd_cols, self.out_cols = shape.columns()

    def _coef(self, kind: str, name: str, i: int):
        pattern = self.coefficients[kind][name]
        return lambda j: pattern.format(i=i, j=j)

    def load(self, vec):
        return [f"{vec}{j} = {vec}[{j}]" for j in range(self.s.m)]

    def store(self, vec):
        return [f"{vec}[{j}] = {vec}{j}" for j in range(self.s.m)]

    def copy(self, src, dst):
        return [f"{dst}{j} = {src}{j}" for j in range(self.s.m)]

    def advance(self, src, dst):
        """The step's end becomes the start, its guards too."""
        return self.copy(src, dst) + [x for i in range(self.ne) for x in (f"va{i} = vb{i}", f"da{i} = db{i}")]

    def step(self, src, dst, kind, T):
        """dst = src + F src over a time T: the state rows; the inputs move linearly, their
        slopes and the Coulomb forces stay."""
        n, n_in, m = self.s.n, self.s.n_in, self.s.m
        lines = []
        for i in range(n):
            expr = f"{src}{i}"
            for j in range(m):
                expr = f"({expr} + {self._coef(kind, 'F', i)(j)} * {src}{j})"
            lines.append(f"{dst}{i} = {expr}")
        lines += [f"{dst}{j} = {src}{j}" for j in range(n, m)]
        lines += [f"{dst}{n + q} = {src}{n + q} + {T} * {src}{n + n_in + q}" for q in range(n_in)]
        return lines

    def _rows(self, i, vec, kind):
        return {"i": i, "r": dot(self._coef(kind, "R", i), vec, self.r_cols[i]),
                "rd": dot(self._coef(kind, "RD", i), vec, self.rd_cols[i]),
                "v": f"{vec}{self.s.node[i]}", "vd": dot(self._coef(kind, "VD", i), vec, self.vd_cols[i])}

    def stuck(self, i):
        """The condition that contact i sticks."""
        return f"(mode >> {i}) & 1"

    def guards(self, vec, val, der, kind):
        """Each contact's guard and its rate at the state ``vec``."""
        return [x for i in range(self.s.nc) for x in expand(GUARD, val=val, der=der, stuck=self.stuck(i),
                                                               **self._rows(i, vec, kind))]

    def clear_test(self):
        return [x for i in range(self.s.nc) for x in expand(CLEAR_TEST, **self._rows(i, "y", "fast"))]

    def stuck_rates(self):
        return [x for i in range(self.s.nc) for x in (
            f"if {self.stuck(i)}:", f"    da{i} = {dot(self._coef('fast', 'RD', i), 'z', self.rd_cols[i])}")]

    def output(self, vec):
        return dot(lambda j: f"OUT[mode, {j}]", vec, self.out_cols)

    def output_sample(self):
        at_out = [i for i in range(self.s.nc) if self.s.node[i] == self.s.out_node]
        lines = [x for k, i in enumerate(at_out) for x in (
            f"{'el' if k else ''}if acon == {i} and mode == cur:", f"    accel[k + 1] = da{i}")]
        if not at_out:
            return [f"accel[k + 1] = {self.output('z')}"]
        return lines + ["else:", f"    accel[k + 1] = {self.output('z')}"]

    def guard_locals(self):
        lines = []
        for i in range(self.s.nc):
            lines += [f"bound{i} = f0[{i}]", f"sg{i} = sgn[{i}]", f"va{i} = 0.0", f"da{i} = 0.0"]
            lines += [f"r{i}_{j} = R[{i}, {j}]" for j in self.r_cols[i]]
            lines += [f"vd{i}_{j} = 0.0" for j in self.vd_cols[i]]
            lines += [f"rd{i}_{j} = 0.0" for j in self.rd_cols[i]]
        return lines

    def mode_locals(self):
        n, m = self.s.n, self.s.m
        lines = [f"f{i}_{j} = F[mode, 0, {i}, {j}]" for i in range(n) for j in range(m)]
        for i in range(self.s.nc):
            lines += [f"vd{i}_{j} = VD[mode, {i}, {j}]" for j in self.vd_cols[i]]
            lines += [f"rd{i}_{j} = RD[mode, {i}, {j}]" for j in self.rd_cols[i]]
        return lines

    def parts(self) -> dict:
        s, nc = self.s, self.s.nc
        q_in = range(s.n_in)
        return {
            "n": s.n, "n_in": s.n_in, "m": s.m, "wcol": s.wcol, "guards_or_1": max(self.ne, 1),
            "out_node": s.out_node, "output": self.output("z"),
            "guard_args": "".join(f", va{i}, da{i}, vb{i}, db{i}, sg{i}, bound{i}" for i in range(nc)),
            "load": self.load, "store": self.store, "copy": self.copy, "advance": self.advance,
            "step": self.step, "guards": self.guards,
            "load_switch_state": [f"sg{i} = sgn[{i}]" for i in range(nc)],
            "load_guards": [f"{a}{i} = {a}[{i}]" for i in range(self.ne) for a in ("va", "da")],
            "store_guards": [f"{a}[{i}] = {a}{i}" for i in range(self.ne) for a in ("va", "da")],
            "event_locals": [x for i in range(nc) for x in (
                f"va{i} = va[{i}]", f"da{i} = da[{i}]", f"vb{i} = 0.0", f"db{i} = 0.0", f"bound{i} = f0[{i}]")],
            "crossed_guards": [x for i in range(nc) for x in expand(CROSSED_CONTACT, i=i)],
            "guard_locals": self.guard_locals(),
            "table_locals": [f"f{i}_{j} = 0.0" for i in range(s.n) for j in range(s.m)],
            "output_contact": [x for i in range(nc) if s.node[i] == s.out_node
                               for x in (f"if not {self.stuck(i)}:", f"    acon = {i}")],
            "mode_locals": self.mode_locals(),
            "inputs": [x for q in q_in for x in (f"z{s.n + q} = inputs[k, {q}]",
                                                  f"z{s.n + s.n_in + q} = (inputs[k + 1, {q}] - inputs[k, {q}]) / h")],
            "stuck_rates": self.stuck_rates(), "clear_test": self.clear_test(),
            "output_sample": self.output_sample(),
            "store_state": [f"states[k + 1, {i}] = z{i}" for i in range(s.n)],
            **CALLS, "switch_call": f"switch(z, mode, np.int64({nc}), node, R, f0, sgn, np.int64(wcol))",
        }


@dataclass(frozen=True)
class RichShape(Shape):
    """A shape with piecewise-linear contacts (``pieces``: each contact's number of pieces)
    and links with a dead zone (``links``: each one's deflection column), as ``_rich``
    simulates them; ``nonzero`` is the pattern of every mode's matrix together."""

    pieces: tuple = ()
    links: tuple = ()

    @property
    def m(self) -> int:
        return self.wcol + self.nc + len(self.links)

    def columns(self):
        """As ``Shape.columns``, the links' deflections as guards too; a holding force sees
        the links' offsets (not the contacts' forces)."""
        m, wcol, nc = self.m, self.wcol, self.nc
        P = np.ones((m, m), dtype=bool) if self.nonzero is None else np.frombuffer(self.nonzero, bool).reshape(m, m)
        r_cols, rd_cols = [], []
        for i in range(nc):
            r = P[self.node[i]].copy()
            r[wcol:wcol + nc] = False
            r_cols.append(np.flatnonzero(r).tolist())
            rd_cols.append(np.flatnonzero((r[:, None] & P).any(axis=0)).tolist())
        vd_cols = [np.flatnonzero(P[col]).tolist() for col in self.node + self.links]
        return r_cols, vd_cols, rd_cols, np.flatnonzero(P[self.out_node]).tolist()


class _RichBlocks(_Blocks):
    """The blocks for a :class:`RichShape`: guards with bands, states per element, the
    tables and holding-force rows per mode."""

    coefficients = {"fast": COEFFICIENTS["fast"], "rare": {**COEFFICIENTS["rare"], "R": "R[mode, {i}, {j}]"}}

    def __init__(self, shape: RichShape):
        super().__init__(shape)
        self.ne = shape.nc + len(shape.links)

    def stuck(self, i):
        return f"st{i} == {self.s.pieces[i]}"

    def guards(self, vec, val, der, kind):
        lines = super().guards(vec, val, der, kind)
        for e in range(self.s.nc, self.ne):
            lines += expand(GUARD_LINK, e=e, val=val, der=der, d=f"{vec}{self.s.links[e - self.s.nc]}",
                            vd=dot(self._coef(kind, "VD", e), vec, self.vd_cols[e]))
        return lines

    def clear_test(self):
        return [x for e in range(self.ne) for x in expand(CLEAR_BAND, e=e)]

    def guard_locals(self):
        lines = []
        for e in range(self.ne):
            lines += [f"lo{e} = lo[{e}]", f"hi{e} = hi[{e}]", f"va{e} = 0.0", f"da{e} = 0.0"]
            lines += [f"vd{e}_{j} = 0.0" for j in self.vd_cols[e]]
        for i in range(self.s.nc):
            lines += [f"st{i} = st[{i}]"] + [f"r{i}_{j} = 0.0" for j in self.r_cols[i]]
            lines += [f"rd{i}_{j} = 0.0" for j in self.rd_cols[i]]
        return lines

    def mode_locals(self):
        lines = super().mode_locals()
        lines += [f"vd{e}_{j} = VD[mode, {e}, {j}]" for e in range(self.s.nc, self.ne) for j in self.vd_cols[e]]
        return lines + [f"r{i}_{j} = R[mode, {i}, {j}]" for i in range(self.s.nc) for j in self.r_cols[i]]

    def parts(self) -> dict:
        ne, args = self.ne, "F, mode, J, h, z, va, da, st, sgn, lo, hi, R, VD, RD, net, tabs, stats, max_events"
        return {
            **super().parts(),
            "guard_args": "".join(f", va{e}, da{e}, vb{e}, db{e}, lo{e}, hi{e}" for e in range(ne)),
            "load_switch_state": [f"st{i} = st[{i}]" for i in range(self.s.nc)]
            + [f"{b}{e} = {b}[{e}]" for e in range(ne) for b in ("lo", "hi")],
            "event_locals": [x for e in range(ne) for x in (
                f"va{e} = va[{e}]", f"da{e} = da[{e}]", f"vb{e} = 0.0", f"db{e} = 0.0")],
            "crossed_guards": [x for e in range(ne) for x in expand(CROSSED_BAND, e=e)],
            "clear_test": self.guards("y", "vb", "db", "fast") + self.clear_test(),
            "kernel_params": "net, inputs, z_init, store, max_events",
            "setup": ["h = net.h", "tabs = setup(net)", "J, F, VD, RD, OUT, R, ready = tabs"],
            "start": ["z, st, sgn, lo, hi, mode = start(z_init, inputs, net, tabs)"],
            "events_params": args, "events_args": args,
            "switch_call": "switch(z, mode, st, sgn, lo, hi, net, tabs)",
        }


_MACRO = re.compile(r"^(\s*)\$(\w+)(?:\((.*)\))?\s*$")


def expand(template: str, **parts) -> list:
    """The template's lines: a line ``$name`` or ``$name(a, b)`` becomes the lines of
    ``parts[name]`` (a list, or a function called with the arguments), indented as the
    line (``pass`` where there are none); ``{name}`` elsewhere becomes ``parts[name]``."""
    lines = []
    for line in template.splitlines():
        macro = _MACRO.match(line)
        if not macro:
            lines.append(line.format(**parts))
            continue
        indent, name, args = macro.groups()
        block = parts[name]
        if callable(block):
            block = block(*[a.strip() for a in args.split(",")] if args else [])
        lines.extend(indent + x for x in (block or ["pass"]))
    return lines


def kernel_source(shape: Shape) -> str:
    """The source of the kernel specialised to ``shape``: functions ``crossed``,
    ``events`` and ``kernel`` (see the templates above), to be compiled by ``cache``."""
    parts = (_RichBlocks if isinstance(shape, RichShape) else _Blocks)(shape).parts()
    out = []
    for template in (CROSSED, EVENTS, KERNEL):
        out += expand(template, **parts) + ["", ""]
    return "\n".join(out[:-2]) + "\n"
