"""Independent references for the exact kernel, slow and for checks only: a test or a
benchmark compares the kernel with them (``tests/test_simulate.py``,
``benchmarks/bench_simulator.py``).

- :func:`moreau_reference`: implicit (Moreau) time stepping. Backward Euler on the
  linear part with the set-valued Coulomb friction solved exactly at each step (all
  3^nc contact states enumerated). First order in the step, so it converges slowly but
  surely: a fine step gives a reference that shares no code with the kernel.
- :func:`hybrid_reference`, :func:`hybrid_reference_rich`: scipy's Radau on each mode of
  the hybrid (stick-slip) system with scipy's own event location, the switching rules
  written out again.
- :func:`inverse_dynamics_force`: a smooth force record to drive them with.
"""

import numpy as np
from numba import njit

from . import contacts

__all__ = ["moreau_reference", "hybrid_reference", "hybrid_reference_rich", "inverse_dynamics_force"]


@njit(cache=True)
def _moreau(P, PB, node, f0, mass, t_fine, u_fine, h):
    n = P.shape[0]
    nc = node.shape[0]
    K = t_fine.shape[0]
    x = np.zeros(n)
    accel = np.zeros(K)
    W = np.zeros((nc, nc))
    for j in range(nc):
        for i in range(nc):
            W[j, i] = h * P[node[j], node[i]] / mass[i]
    n_comb = 3**nc
    lam = np.zeros(nc)
    for k in range(1, K):
        q = P @ x + h * PB * u_fine[k]
        found = False
        for comb in range(n_comb):
            c = comb
            state = np.zeros(nc, dtype=np.int64)  # 0 stick, 1 slip+, 2 slip-
            for i in range(nc):
                state[i] = c % 3
                c //= 3
            for i in range(nc):
                if state[i] == 1:
                    lam[i] = f0[i]
                elif state[i] == 2:
                    lam[i] = -f0[i]
                else:
                    lam[i] = 0.0
            # stuck contacts: solve W_ss lam_s = q_s - W_sf lam_f
            ns = 0
            for i in range(nc):
                if state[i] == 0:
                    ns += 1
            if ns > 0:
                idx = np.zeros(ns, dtype=np.int64)
                r = 0
                for i in range(nc):
                    if state[i] == 0:
                        idx[r] = i
                        r += 1
                M = np.zeros((ns, ns))
                rhs = np.zeros(ns)
                for a in range(ns):
                    rhs[a] = q[node[idx[a]]]
                    for i in range(nc):
                        if state[i] != 0:
                            rhs[a] -= W[idx[a], i] * lam[i]
                    for b in range(ns):
                        M[a, b] = W[idx[a], idx[b]]
                sol = np.linalg.solve(M, rhs)
                for a in range(ns):
                    lam[idx[a]] = sol[a]
            ok = True
            for j in range(nc):
                v = q[node[j]]
                for i in range(nc):
                    v -= W[j, i] * lam[i]
                if state[j] == 0 and abs(lam[j]) > f0[j] * (1 + 1e-12):
                    ok = False
                if state[j] == 1 and v <= 0:
                    ok = False
                if state[j] == 2 and v >= 0:
                    ok = False
            if ok:
                found = True
                break
        if not found:
            raise RuntimeError("no consistent contact state")
        xn = q.copy()
        for i in range(nc):
            for r in range(n):
                xn[r] -= h * P[r, node[i]] * lam[i] / mass[i]
        accel[k] = (xn[0] - x[0]) / h
        x = xn
    return accel


def moreau_reference(compiled, time, force, refine):
    """Acceleration of node 0 at the record's samples, by Moreau stepping at h / refine.

    The returned value at a sample is the mean acceleration over the fine step that ends
    there, which converges to the instantaneous value with the step.
    """
    A, B = compiled.state_space(viscous=True)
    h = (time[1] - time[0]) / refine
    t_fine = np.linspace(time[0], time[-1], (len(time) - 1) * refine + 1)
    u_fine = np.interp(t_fine, time, force)
    P = np.linalg.inv(np.eye(A.shape[0]) - h * A)
    nodes, f0, mass = contacts(compiled.coulomb_bounds, compiled.masses)
    a = _moreau(P, P @ B, nodes, f0, mass, t_fine, u_fine, h)
    return a[::refine]


def hybrid_reference(compiled, time, force, *, rtol=1e-10):
    """Acceleration of node 0 by scipy's Radau on each mode with event location.

    An independent implementation of the same hybrid (stick-slip) system as the kernel:
    scipy integrates each mode, finds the switches with its own root finder, and the
    switching rules are written out here again. Integrates one sample interval at a time.
    """
    from scipy.integrate import solve_ivp

    A, B = compiled.state_space(viscous=True)
    nodes, f0, mass = contacts(compiled.coulomb_bounds, compiled.masses)
    nc = len(nodes)
    n = A.shape[0]
    stuck = np.ones(nc, dtype=bool)
    sgn = np.ones(nc)
    x = np.zeros(n)
    accel = np.zeros(len(time))

    def holding(i, t0, t1, u0, u1, tt, xx):
        u = u0 + (u1 - u0) * (tt - t0) / (t1 - t0)
        return mass[i] * (A[nodes[i]] @ xx + B[nodes[i]] * u)

    def deriv(t0, t1, u0, u1):
        def f(tt, xx):
            u = u0 + (u1 - u0) * (tt - t0) / (t1 - t0)
            dx = A @ xx + B * u
            for i in range(nc):
                if stuck[i]:
                    dx[nodes[i]] = 0.0
                else:
                    dx[nodes[i]] -= sgn[i] * f0[i] / mass[i]
            return dx
        return f

    def switch(t0, t1, u0, u1, tt, xx):
        for i in range(nc):
            r = holding(i, t0, t1, u0, u1, tt, xx)
            if stuck[i]:
                if abs(r) > f0[i] * (1 - 1e-9):
                    stuck[i] = False
                    sgn[i] = np.sign(r)
            elif sgn[i] * xx[nodes[i]] <= 1e-15:
                xx[nodes[i]] = 0.0
                r = holding(i, t0, t1, u0, u1, tt, xx)
                if abs(r) <= f0[i]:
                    stuck[i] = True
                else:
                    sgn[i] = np.sign(r)

    switch(time[0], time[1], force[0], force[1], time[0], x)
    f = deriv(time[0], time[1], force[0], force[1])
    accel[0] = f(time[0], x)[0]
    for k in range(len(time) - 1):
        t0, t1, u0, u1 = time[k], time[k + 1], force[k], force[k + 1]
        tt = t0
        for _ in range(100):
            events = []
            for i in range(nc):
                if stuck[i]:
                    for side in (1.0, -1.0):
                        ev = (lambda i, side: lambda s, y: f0[i] - side * holding(i, t0, t1, u0, u1, s, y))(i, side)
                        ev.terminal = True
                        ev.direction = -1
                        events.append(ev)
                else:
                    ev = (lambda i: lambda s, y: sgn[i] * y[nodes[i]])(i)
                    ev.terminal = True
                    ev.direction = -1
                    events.append(ev)
            sol = solve_ivp(deriv(t0, t1, u0, u1), (tt, t1), x, method="Radau", rtol=rtol,
                            atol=1e-14, events=events or None)
            x = sol.y[:, -1].copy()
            tt = sol.t[-1]
            if sol.status == 1:
                switch(t0, t1, u0, u1, tt, x)
            if tt >= t1:
                break
        accel[k + 1] = deriv(t0, t1, u0, u1)(t1, x)[0]
    return accel


class _Hybrid:
    """The hybrid system with piecewise-linear friction and dead zones, written out again
    for :func:`hybrid_reference_rich`: its right-hand side in each mode, from the network's
    arrays (not the kernel's matrices), and the events that end a mode."""

    def __init__(self, compiled):
        from bayes_inerter.friction import PiecewiseLinear
        from bayes_inerter.network.compile import chain_state_space

        self.c = compiled
        self.N = compiled.n_nodes
        self.gaps = [j for j, g in enumerate(compiled.link_gap) if g > 0]
        c, k = compiled.link_c.copy(), compiled.link_k.copy()
        c[self.gaps], k[self.gaps] = 0.0, 0.0  # the gap links' forces are added by hand
        self.A, self.B = chain_state_space(compiled.masses, c, k, compiled.viscous)
        self.laws = {i: PiecewiseLinear.total(laws) for i, laws in enumerate(compiled.laws) if laws}
        self.pieces = {i: law.segments() for i, law in self.laws.items()}
        self.stuck = {i: True for i in self.laws}
        self.sign = {i: 1.0 for i in self.laws}
        self.piece = {i: 0 for i in self.laws}
        self.closed = {j: False for j in self.gaps}
        self.side = {j: 1.0 for j in self.gaps}

    def rhs(self, x, u, free=None):
        """x' at state x and force u; the contact ``free`` neither sticks nor rubs."""
        dx = self.A @ x + self.B * u
        m = self.c.masses
        for j in self.gaps:
            if self.closed[j]:
                T = self.c.link_c[j] * (x[j] - x[j + 1]) + self.c.link_k[j] * (x[self.N + j] - self.side[j] * self.c.link_gap[j])
                dx[j] -= T / m[j]
                dx[j + 1] += T / m[j + 1]
        for i, law in self.laws.items():
            if i == free:
                continue
            if self.stuck[i]:
                dx[i] = 0.0
            else:
                _, a, slopes = self.pieces[i]
                s = self.piece[i]
                dx[i] -= (self.sign[i] * a[s] + (slopes[s] - law.c) * x[i]) / m[i]
        return dx

    def holding(self, i, x, u):
        return self.c.masses[i] * self.rhs(x, u, free=i)[i]

    def events(self, u_of):
        """(event functions, what each one means)."""
        funcs, meaning = [], []

        def add(fn, direction, what):
            fn.terminal, fn.direction = True, direction
            funcs.append(fn)
            meaning.append(what)

        for i, law in self.laws.items():
            speeds = np.append(self.pieces[i][0], np.inf)
            s, sg = self.piece[i], self.sign[i]
            if self.stuck[i]:
                for side in (1.0, -1.0):
                    add(lambda t, y, i=i, side=side, f_s=law.f_s: f_s - side * self.holding(i, y, u_of(t)), -1,
                        ("break", i, side))
            else:
                add(lambda t, y, i=i, sg=sg, v=speeds[s]: sg * y[i] - v, -1, ("down", i))
                if np.isfinite(speeds[s + 1]):
                    add(lambda t, y, i=i, sg=sg, v=speeds[s + 1]: sg * y[i] - v, 1, ("up", i))
        for j in self.gaps:
            g, col = self.c.link_gap[j], self.N + j
            if self.closed[j]:
                add(lambda t, y, col=col, sd=self.side[j], g=g: sd * y[col] - g, -1, ("open", j))
            else:
                add(lambda t, y, col=col, g=g: y[col] - g, 1, ("close", j, 1.0))
                add(lambda t, y, col=col, g=g: y[col] + g, -1, ("close", j, -1.0))
        return funcs, meaning

    def switch(self, what, x, u):
        kind, e = what[0], what[1]
        if kind == "break":
            self.stuck[e], self.sign[e], self.piece[e] = False, what[2], 0
        elif kind == "down" and self.piece[e] > 0:
            self.piece[e] -= 1
        elif kind == "down":  # the velocity reached zero: stick or reverse
            x[e] = 0.0
            r = self.holding(e, x, u)
            if abs(r) <= self.laws[e].f_s:
                self.stuck[e] = True
            else:
                self.sign[e], self.piece[e] = np.sign(r), 0
        elif kind == "up":
            self.piece[e] += 1
        elif kind == "close":
            self.closed[e], self.side[e] = True, what[2]
        else:
            self.closed[e] = False
        self.settle(x, u)

    def settle(self, x, u):
        """A stuck contact whose holding force a switch has taken beyond its bound (a link
        closing on it, say) breaks away at once: no event shows a force that jumps."""
        for i, law in self.laws.items():
            if self.stuck[i]:
                r = self.holding(i, x, u)
                if abs(r) > law.f_s:
                    self.stuck[i], self.sign[i], self.piece[i] = False, np.sign(r), 0


def hybrid_reference_rich(compiled, time, force, *, rtol=1e-10):
    """Acceleration of node 0 by scipy's Radau in each mode, with scipy's event location,
    for piecewise-linear friction laws and dead zones (links with ``Backlash``): an
    implementation of the same hybrid system as the kernel that shares none of its code
    (the right-hand side is formed from the network's arrays, the switching rules are
    written out again). Integrates one sample interval at a time."""
    from scipy.integrate import solve_ivp

    hyb = _Hybrid(compiled)
    x = np.zeros(2 * hyb.N - 1)
    accel = np.zeros(len(time))
    hyb.settle(x, force[0])  # at rest: break away at once where the force is too large
    accel[0] = hyb.rhs(x, force[0])[0]
    for k in range(len(time) - 1):
        t0, t1, u0, u1 = time[k], time[k + 1], force[k], force[k + 1]

        def u_of(t, t0=t0, t1=t1, u0=u0, u1=u1):
            return u0 + (u1 - u0) * (t - t0) / (t1 - t0)

        tt = t0
        for _ in range(200):
            funcs, meaning = hyb.events(u_of)
            sol = solve_ivp(lambda t, y: hyb.rhs(y, u_of(t)), (tt, t1), x, method="Radau", rtol=rtol, atol=1e-14,
                            events=funcs or None)
            x, tt = sol.y[:, -1].copy(), sol.t[-1]
            if sol.status == 1:
                fired = [q for q, te in enumerate(sol.t_events) if len(te)]
                hyb.switch(meaning[fired[0]], x, u_of(tt))
            if tt >= t1:
                break
        accel[k + 1] = hyb.rhs(x, u1)[0]
    return accel


def inverse_dynamics_force(params, freq, *, amplitude=0.01, duration=3.0, fs=1000.0, ramp=1.0):
    """(time, force) of a record that drives the rigid device ``params`` (its masses,
    inertance and friction as a ``networks`` parameter set) roughly through a sinusoid
    of ``amplitude`` m at ``freq`` Hz, ramped in over ``ramp`` s.

    Not a realistic record (that is the generator's job): a smooth test input whose
    friction part switches sign at each reversal, so the network sticks and slips.
    """
    t = np.arange(int(round(duration * fs)) + 1) / fs
    w = 2 * np.pi * freq
    s = np.clip(t / ramp, 0, 1)
    env = s * s * (3 - 2 * s)
    x = amplitude * np.sin(w * t) * env
    v = np.gradient(x, t)
    a = np.gradient(v, t)
    m = params.m_B + params.m_s + params.b
    f = m * a + (params.f1_0 + params.f2_0) * np.tanh(v / 1e-3) + (params.c_f1 + params.c_f2) * v
    return t, f
