"""The exact kernel's algorithm written plainly: no speed tricks, no generated code.

The same hybrid system and the same rules as ``bayes_inerter.simulate._kernel``, in plain numpy
and scipy, to check the generated kernels against (to rounding: the exponentials come
from scipy's ``expm``, not from the kernel's tables):

- the augmented state z = [x, u, du, w] (state, inputs, their slopes over the sample
  interval, each contact's constant force, each link's offset) moves as z' = A_S z within
  a mode S: which piece of its friction law each contact slides in, or that it sticks
  (its node's row is then zero); which links are closed;
- each element has a guard that must stay within a band: a sliding contact's velocity
  within its piece's speeds (signed), a stuck contact's holding force within +-f_s, a
  link's deflection within its gap (open) or beyond it on its side (closed);
- a sample interval is walked in dyadic steps of h / 2^J; a step whose guard leaves its
  band at its end, or whose cubic Hermite interpolant (values and rates at both ends)
  leaves it in between, is bisected down to one tick, and the elements switch at the
  tick after the crossing (contacts first, then links); then the interval goes on in
  the new mode.
"""

import numpy as np
from scipy.linalg import expm

from bayes_inerter.friction import Coulomb, PiecewiseLinear
from bayes_inerter.network.compile import chain_state_space

MIN_LEVELS = 20


class Contact:
    """A contact at ``node`` with a piecewise-linear law; its force is z[wcol]."""

    def __init__(self, node, mass, wcol, law: PiecewiseLinear):
        self.node, self.mass, self.wcol, self.law = node, mass, wcol, law
        self.speeds, self.a, self.slopes = law.segments()
        self.stuck, self.sign, self.piece = False, 1.0, 0

    def state(self):
        return "stuck" if self.stuck else self.piece

    def band(self):
        if self.stuck:
            return -self.law.f_s, self.law.f_s
        lo, hi = self.speeds[self.piece], np.append(self.speeds, np.inf)[self.piece + 1]
        return (lo, hi) if self.sign > 0 else (-hi, -lo)

    def slide(self, z, sign, piece):
        self.stuck, self.sign, self.piece = False, sign, piece
        z[self.wcol] = sign * self.a[piece]

    def switch(self, z, holding):
        """The switch due at z (holding(contact, z): the holding force at z): break away,
        stick, reverse, or move to the piece of its speed."""
        if self.stuck:
            r = holding(self, z)
            if abs(r) > self.law.f_s:
                self.slide(z, np.sign(r), 0)
        elif self.sign * z[self.node] < 0.0:
            z[self.node] = 0.0
            r = holding(self, z)
            if abs(r) <= self.law.f_s:
                self.stuck = True
            else:
                self.slide(z, np.sign(r), 0)
        else:
            speed = self.sign * z[self.node]
            piece = int(np.searchsorted(self.speeds, speed, side="right") - 1)
            # on a knot it stays in its piece (the bands are closed)
            if speed == self.speeds[piece] and piece == self.piece + 1:
                piece = self.piece
            self.slide(z, self.sign, piece)


class Link:
    """A link with a dead zone: deflection z[col], half-width gap, offset z[wcol]; ``part``
    is what closing it adds to the augmented matrix."""

    def __init__(self, col, gap, wcol, part):
        self.col, self.gap, self.wcol, self.part = col, gap, wcol, part
        self.closed, self.side = False, 1.0

    def state(self):
        return self.closed

    def band(self):
        if not self.closed:
            return -self.gap, self.gap
        return (self.gap, np.inf) if self.side > 0 else (-np.inf, -self.gap)

    def switch(self, z):
        d = z[self.col]
        if not self.closed and abs(d) > self.gap:
            self.closed, self.side = True, np.sign(d)
            z[self.wcol] = self.side * self.gap
        elif self.closed and self.side * d < self.gap:
            self.closed, z[self.wcol] = False, 0.0


def hermite_range(y0, d0, y1, d1):
    """Min and max over s in [0, 1] of the cubic with values y0, y1 and slopes d0, d1."""
    # p(s) = y0 + d0 s + b s^2 + a s^3
    a = 2 * y0 - 2 * y1 + d0 + d1
    b = -3 * y0 + 3 * y1 - 2 * d0 - d1
    values = [y0, y1]
    roots = np.roots([3 * a, 2 * b, d0]) if (a or b) else []
    for s in roots:
        if abs(s.imag) < 1e-300 and 0.0 < s.real < 1.0:
            s = s.real
            values.append(((a * s + b) * s + d0) * s + y0)
    return min(values), max(values)


class Reference:
    """x' = A x + B u (A with every link closed) with friction contacts at ``nodes`` (their
    piecewise-linear laws and masses) and dead zones in the links ``gaps`` ({link index:
    half-width}) of the chain ``compiled``, sampled at h."""

    def __init__(self, A, B, nodes, laws, mass, h, *, compiled=None, gaps=None):
        n, n_in = A.shape[0], B.reshape(A.shape[0], -1).shape[1]
        self.n, self.n_in, self.h = n, n_in, h
        wcol = n + 2 * n_in
        gaps = gaps or {}
        m = wcol + len(nodes) + len(gaps)
        self.contacts = [Contact(int(nodes[i]), mass[i], wcol + i, laws[i]) for i in range(len(nodes))]
        self.links = []
        for q, (j, gap) in enumerate(sorted(gaps.items())):
            part = self._link_part(compiled, j, n, m)
            part[:n, wcol + len(nodes) + q] = -part[:n, compiled.n_nodes + j]  # the spring acts on d - offset
            self.links.append(Link(compiled.n_nodes + j, gap, wcol + len(nodes) + q, part))
        self.Abar = np.zeros((m, m))  # every link open, every contact at its law's slope c
        self.Abar[:n, :n] = A - sum((lk.part[:n, :n] for lk in self.links), np.zeros_like(A))
        self.Abar[:n, n:n + n_in] = B.reshape(n, -1)
        self.Abar[n:n + n_in, n + n_in:wcol] = np.eye(n_in)
        for c in self.contacts:
            self.Abar[c.node, c.wcol] = -1.0 / c.mass
        self.J = MIN_LEVELS
        while self._envelope() * h / 2.0**self.J > 1.0 / 16.0:
            self.J += 1
        self._exp, self._mat = {}, {}

    @classmethod
    def coulomb(cls, A, B, nodes, f0, mass, h):
        return cls(A, B, nodes, [Coulomb(f, 0.0).piecewise() for f in f0], mass, h)

    @staticmethod
    def _link_part(compiled, j, n, m):
        c, k = np.zeros_like(compiled.link_c), np.zeros_like(compiled.link_k)
        c[j], k[j] = compiled.link_c[j], compiled.link_k[j]
        position = n == compiled.n_states(position=True)
        part = np.zeros((m, m))
        part[:n, :n] = (chain_state_space(compiled.masses, c, k, position=position)[0]
                        - chain_state_space(compiled.masses, 0 * c, 0 * k, position=position)[0])
        return part

    def _envelope(self):
        """A bound on every mode's matrix norm (row sums), as the kernel takes it."""
        E = np.abs(self.Abar) + sum((np.abs(lk.part) for lk in self.links), np.zeros_like(self.Abar))
        for c in self.contacts:
            E[c.node, c.node] += np.max(np.abs(c.slopes - c.law.c)) / c.mass
        return E.sum(axis=1).max()

    def mode(self):
        return tuple(e.state() for e in self.contacts + self.links)

    def matrix(self, stuck_rows=True):
        """A_S: the closed links' parts in, each sliding contact's piece slope, the stuck
        contacts' rows zeroed (unless not ``stuck_rows``)."""
        key = (self.mode(), stuck_rows)
        if key not in self._mat:
            self._mat[key] = self._matrix(stuck_rows)
        return self._mat[key]

    def _matrix(self, stuck_rows):
        As = self.Abar + sum((lk.part for lk in self.links if lk.closed), np.zeros_like(self.Abar))
        for c in self.contacts:
            if not c.stuck:
                As[c.node, c.node] -= (c.slopes[c.piece] - c.law.c) / c.mass
            elif stuck_rows:
                As[c.node] = 0.0
        return As

    def step(self, z, ticks):
        key = (self.mode(), ticks)
        if key not in self._exp:
            self._exp[key] = expm(self.matrix() * (ticks * self.h / 2.0**self.J))
        return self._exp[key] @ z

    def holding(self, contact, z):
        """The force that holds the contact's node at rest: its mass times its acceleration
        without the contacts' forces."""
        row = self.matrix(stuck_rows=False)[contact.node].copy()
        row[[c.wcol for c in self.contacts]] = 0.0
        return contact.mass * row @ z

    def guard(self, element, z):
        """The element's guard value at z and its rate."""
        As = self.matrix()
        if isinstance(element, Link):
            return z[element.col], As[element.col] @ z
        if element.stuck:
            return self.holding(element, z), self.holding(element, As @ z)
        return z[element.node], As[element.node] @ z

    def crossed(self, za, zb, ticks):
        T = ticks * self.h / 2.0**self.J
        for e in self.contacts + self.links:
            lo, hi = e.band()
            (va, da), (vb, db) = self.guard(e, za), self.guard(e, zb)
            cmin, cmax = hermite_range(va, T * da, vb, T * db)
            if not lo <= vb <= hi or cmin < lo or cmax > hi:
                return True
        return False

    def interval(self, z, max_events, stats):
        """One sample interval from z: dyadic steps, bisection where a guard is crossed, the
        switches. Returns the state at its end, or None after more than max_events."""
        full, pos, events = 2**self.J, 0, 0
        while pos < full:
            size = full if pos == 0 else pos & -pos  # the longest dyadic step from pos
            zb = self.step(z, size)
            if not self.crossed(z, zb, size):
                z, pos = zb, pos + size
                continue
            stats[1] += 1
            advanced = 0
            while size > 1:  # the crossing lies between z + advanced and zb = z + advanced + size
                size //= 2
                zm = self.step(z, size)
                if self.crossed(z, zm, size):
                    zb = zm
                else:
                    z, advanced = zm, advanced + size
            pos += advanced + 1
            z = zb.copy()
            before = self.mode()
            self.switch_all(z)
            stats[0] += self.mode() != before
            events += 1
            if events > max_events:
                return None
        return z

    def switch_all(self, z):
        """The contacts switch (their holding forces in the mode before any switch), then
        the links."""
        As = self.matrix(stuck_rows=False)
        rows = {id(c): As[c.node].copy() for c in self.contacts}  # (copies: the cache keeps As)
        for c in self.contacts:
            rows[id(c)][[d.wcol for d in self.contacts]] = 0.0
        for c in self.contacts:
            c.switch(z, lambda contact, zz: contact.mass * rows[id(contact)] @ zz)
        for lk in self.links:
            lk.switch(z)

    def start(self, z):
        for c in self.contacts:  # at rest: stuck, if it can be; else in piece 0, then its own
            c.stuck = z[c.node] == 0.0
            if not c.stuck:
                c.slide(z, np.sign(z[c.node]), 0)
        self.switch_all(z)

    def run(self, inputs, z_init=None, out_node=0, max_events=200):
        """(accel, vel, states, ok, stats) as the kernel returns them."""
        n, n_in = self.n, self.n_in
        inputs = np.asarray(inputs, dtype=float).reshape(len(inputs), n_in)
        K = len(inputs)
        z = np.zeros(self.Abar.shape[0])
        z[:n] = 0.0 if z_init is None else z_init
        z[n:n + n_in] = inputs[0]
        self.start(z)
        accel, vel, states = np.full(K, np.nan), np.full(K, np.nan), np.zeros((K, n))
        stats = np.zeros(2, dtype=int)
        for k in range(K):
            if k > 0:
                z[n:n + n_in] = inputs[k - 1]
                z[n + n_in:n + 2 * n_in] = (inputs[k] - inputs[k - 1]) / self.h
                z = self.interval(z, max_events, stats)
                if z is None:
                    return accel, vel, states, False, stats
            accel[k], vel[k], states[k] = self.matrix()[out_node] @ z, z[out_node], z[:n]
        return accel, vel, states, True, stats
