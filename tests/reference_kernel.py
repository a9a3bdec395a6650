"""The exact kernel's algorithm written plainly: no speed tricks, no generated code.

The same hybrid system and the same rules as ``bayes_inerter._kernel``, in plain numpy
and scipy, to check the generated kernels against (to rounding: the exponentials come
from scipy's ``expm``, not from the kernel's tables):

- the augmented state z = [x, u, du, w] (state, inputs, their slopes over the sample
  interval, each contact's Coulomb force) moves as z' = A_S z within a mode S (which
  contacts stick; a stuck node's velocity row is zero);
- each contact has a guard that must stay within a band: a sliding contact's velocity
  within [0, inf) or (-inf, 0] (its sign), a stuck contact's holding force within
  [-f0, f0];
- a sample interval is walked in dyadic steps of h / 2^J; a step whose guard leaves its
  band at its end, or whose cubic Hermite interpolant (values and rates at both ends)
  leaves it in between, is bisected down to one tick, and the contacts switch at the
  tick after the crossing; then the interval goes on in the new mode.
"""

import numpy as np
from scipy.linalg import expm

MIN_LEVELS = 20


class Contact:
    """A Coulomb contact at ``node``: bound f0 (N), node mass (kg), column of its force in z."""

    def __init__(self, node, f0, mass, wcol):
        self.node, self.f0, self.mass, self.wcol = node, f0, mass, wcol
        self.stuck, self.sign = False, 1.0

    def band(self):
        if self.stuck:
            return -self.f0, self.f0
        return (0.0, np.inf) if self.sign > 0 else (-np.inf, 0.0)

    def slide(self, z, sign):
        self.stuck, self.sign = False, sign
        z[self.wcol] = sign * self.f0

    def switch(self, z, holding):
        """The switch due at z (holding: the holding force at z): break away, stick or reverse."""
        if self.stuck:
            r = holding(self, z)
            if abs(r) > self.f0:
                self.slide(z, np.sign(r))
        elif self.sign * z[self.node] < 0.0:
            z[self.node] = 0.0
            r = holding(self, z)
            if abs(r) <= self.f0:
                self.stuck = True
            else:
                self.slide(z, np.sign(r))


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
    """x' = A x + B u with Coulomb contacts at ``nodes`` (bounds f0, masses), sampled at h."""

    def __init__(self, A, B, nodes, f0, mass, h):
        n, n_in = A.shape[0], B.reshape(A.shape[0], -1).shape[1]
        self.n, self.n_in, self.h = n, n_in, h
        wcol = n + 2 * n_in
        self.contacts = [Contact(int(nodes[i]), f0[i], mass[i], wcol + i) for i in range(len(nodes))]
        m = wcol + len(self.contacts)
        self.Abar = np.zeros((m, m))
        self.Abar[:n, :n] = A
        self.Abar[:n, n:n + n_in] = B.reshape(n, -1)
        self.Abar[n:n + n_in, n + n_in:wcol] = np.eye(n_in)
        for c in self.contacts:
            self.Abar[c.node, c.wcol] = -1.0 / c.mass
        norm = np.abs(self.Abar).sum(axis=1).max() * h
        self.J = MIN_LEVELS
        while norm / 2.0**self.J > 1.0 / 16.0:
            self.J += 1
        self._exp = {}

    def mode(self):
        return tuple(c.stuck for c in self.contacts)

    def matrix(self):
        """A_S: the stuck contacts' velocity rows zeroed."""
        As = self.Abar.copy()
        for c in self.contacts:
            if c.stuck:
                As[c.node] = 0.0
        return As

    def step(self, z, ticks):
        key = (self.mode(), ticks)
        if key not in self._exp:
            self._exp[key] = expm(self.matrix() * (ticks * self.h / 2.0**self.J))
        return self._exp[key] @ z

    def holding(self, contact, z):
        """The force that holds the contact's node at rest: its mass times its acceleration
        without its own Coulomb force."""
        row = self.Abar[contact.node].copy()
        row[contact.wcol] = 0.0
        return contact.mass * row @ z

    def guard(self, contact, z):
        """The contact's guard value at z and its rate."""
        As = self.matrix()
        if contact.stuck:
            return self.holding(contact, z), self.holding(contact, As @ z)
        return z[contact.node], As[contact.node] @ z

    def crossed(self, za, zb, ticks):
        T = ticks * self.h / 2.0**self.J
        for c in self.contacts:
            lo, hi = c.band()
            (va, da), (vb, db) = self.guard(c, za), self.guard(c, zb)
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
            for c in self.contacts:
                c.switch(z, self.holding)
            stats[0] += self.mode() != before
            events += 1
            if events > max_events:
                return None
        return z

    def run(self, inputs, z_init=None, out_node=0, max_events=200):
        """(accel, vel, states, ok, stats) as the kernel returns them."""
        n, n_in = self.n, self.n_in
        inputs = np.asarray(inputs, dtype=float).reshape(len(inputs), n_in)
        K = len(inputs)
        z = np.zeros(self.Abar.shape[0])
        z[:n] = 0.0 if z_init is None else z_init
        z[n:n + n_in] = inputs[0]
        for c in self.contacts:  # at rest: stuck, if it can be
            c.stuck = z[c.node] == 0.0
            if not c.stuck:
                c.slide(z, np.sign(z[c.node]))
            c.switch(z, self.holding)
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
