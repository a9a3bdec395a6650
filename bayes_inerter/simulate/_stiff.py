"""General stiff solver (scipy Radau) for any friction law and for backlash.

Private; used by ``simulate(method="stiff")`` and by the record generator when the truth
is richer than the exact kernel handles. Set-valued signs are regularised as
tanh(v / v_eps) (**assumption**, default ``V_EPS``); Simscape's smooth law is used as is.

Backlash in a link of half-width g (**assumption** on its form): the spring acts on the
dead-zone deflection ``d - g sgn(d)`` when |d| > g and not at all inside the gap; the
damper acts on the relative velocity scaled by a contact factor that rises linearly from
0 at |d| = g to 1 at |d| = (1 + BACKLASH_RAMP) g, so that closing the gap is not an
infinite impulse. (The exact kernel takes the plain dead zone, the damper acting in full
from |d| = g on: a finite jump of the link force, which its events handle; the two
differ where the gap closes, see docs/simulator.md.)
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ..friction import Coulomb, FrictionLaw, Smooth, Stribeck
from ..network import CompiledNetwork

__all__ = ["simulate_stiff", "run_stiff", "V_EPS", "RTOL", "BACKLASH_RAMP"]

V_EPS = 1e-4  # m/s
RTOL = 1e-8
ATOL_SCALE = 1e-10  # absolute tolerance, in units of each state's scale
BACKLASH_RAMP = 0.1


def _scalar_law(law: FrictionLaw, v_eps: float):
    """A fast scalar (force, slope) function of v for one law: the same formulas as
    ``law.regularized``, with math instead of numpy (the solver calls it per step)."""
    if isinstance(law, Coulomb):
        f0, c = law.f0, law.c

        def coulomb(v):
            t = math.tanh(v / v_eps)
            return f0 * t + c * v, f0 * (1 - t * t) / v_eps + c

        return coulomb
    if isinstance(law, Stribeck):
        fc, df, vs, c, delta = law.f_c, law.f_s - law.f_c, law.v_s, law.c, law.delta

        def stribeck(v):
            t = math.tanh(v / v_eps)
            x = abs(v / vs)
            e = math.exp(-(x**delta))
            level = fc + df * e
            dlevel = -df * e * delta * (x ** (delta - 1) if x > 0 else 0.0) * math.copysign(1.0, v) / vs
            return t * level + c * v, (1 - t * t) / v_eps * level + t * dlevel + c

        return stribeck
    if isinstance(law, Smooth):
        v_st, v_coul = law.v_brk * math.sqrt(2), law.v_brk / 10
        a, fc, c = math.sqrt(2 * math.e) * (law.f_brk - law.f_c), law.f_c, law.c

        def smooth(v):
            x = v / v_st
            g = math.exp(-x * x)
            t = math.tanh(v / v_coul)
            force = a * g * x + fc * t + c * v
            return force, a * g * (1 - 2 * x * x) / v_st + fc * (1 - t * t) / v_coul + c

        return smooth
    return lambda v: tuple(float(y) for y in law.regularized(v, v_eps))


class _Model:
    """Right-hand side and Jacobian of the nonlinear network, vectorised over nodes."""

    def __init__(self, compiled: CompiledNetwork, A, B, t, inputs, v_eps):
        self.c = compiled
        self.A = A
        self.B = B.reshape(A.shape[0], -1)
        self.t = t
        self.inputs = inputs.reshape(len(t), -1)
        self.v_eps = v_eps
        self.N = compiled.n_nodes
        self.inv_m = 1.0 / compiled.masses
        self.gap_links = np.flatnonzero(compiled.link_gap > 0)
        self.laws = [(i, _scalar_law(law, v_eps)) for i, node in enumerate(compiled.laws) for law in node]
        self.h = (t[-1] - t[0]) / (len(t) - 1)

    def u(self, time):
        """Inputs interpolated linearly (uniform samples: the index is computed)."""
        s = (time - self.t[0]) / self.h
        k = min(max(int(s), 0), len(self.t) - 2)
        frac = s - k
        return self.inputs[k] + frac * (self.inputs[k + 1] - self.inputs[k])

    def nonlinear(self, x):
        """Extra state derivative and its Jacobian from frictions and dead zones."""
        n = self.A.shape[0]
        g = np.zeros(n)
        J = np.zeros((n, n))
        for i, law in self.laws:
            f, slope = law(x[i])
            g[i] -= f * self.inv_m[i]
            J[i, i] -= slope * self.inv_m[i]
        for j in self.gap_links:
            gap, c, k = self.c.link_gap[j], self.c.link_c[j], self.c.link_k[j]
            d, dv = x[self.N + j], x[j] - x[j + 1]
            ad = abs(d)
            dz = np.sign(d) * (ad - gap) if ad > gap else 0.0
            ddz = 1.0 if ad > gap else 0.0
            ramp = BACKLASH_RAMP * gap
            sigma = min(max((ad - gap) / ramp, 0.0), 1.0)
            dsigma = np.sign(d) / ramp if gap < ad < gap + ramp else 0.0
            corr = k * (dz - d) + c * dv * (sigma - 1.0)  # dead-zone force minus linear
            dcorr_dd = k * (ddz - 1.0) + c * dv * dsigma
            dcorr_dv = c * (sigma - 1.0)
            for node, sign in ((j, -1.0), (j + 1, 1.0)):
                w = sign * self.inv_m[node]
                g[node] += w * corr
                J[node, self.N + j] += w * dcorr_dd
                J[node, j] += w * dcorr_dv
                J[node, j + 1] -= w * dcorr_dv
        return g, J

    def rhs(self, time, x):
        g, _ = self.nonlinear(x)
        return self.A @ x + self.B @ self.u(time) + g

    def jac(self, time, x):
        _, J = self.nonlinear(x)
        return self.A + J


def run_stiff(compiled, A, B, t, inputs, *, x0=None, v_eps=V_EPS, rtol=RTOL, max_step=None):
    """Integrate x' = A x + B u + nonlinear(x); A excludes all friction (viscous too).

    ``max_step`` (s) defaults to the sample interval, so that no kink of the
    interpolated input is stepped over; smooth inputs may allow more.
    Returns (acceleration of node 0 at the samples, states (K, n)).
    """
    if not v_eps > 0:
        raise ValueError(f"v_eps must be positive, got {v_eps}")
    model = _Model(compiled, A, B, t, np.asarray(inputs, dtype=float), v_eps)
    n = A.shape[0]
    y0 = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float)
    h = t[1] - t[0]
    scale = np.abs(model.inputs).max() * h / compiled.masses.min() + 1e-12
    sol = solve_ivp(
        model.rhs, (t[0], t[-1]), y0, method="Radau", t_eval=t, rtol=rtol,
        atol=ATOL_SCALE * scale, jac=model.jac, max_step=h if max_step is None else max_step,
    )
    if not sol.success:
        raise RuntimeError(f"stiff solver failed: {sol.message}")
    states = sol.y.T
    accel = np.array([model.rhs(ti, xi)[0] for ti, xi in zip(t, states)])
    return accel, states


def simulate_stiff(compiled: CompiledNetwork, t, force, *, x0=None, v_eps=V_EPS, rtol=RTOL):
    """Acceleration of node 0 under a force record, by the stiff solver, and the states."""
    A, B = compiled.state_space(viscous=False)
    return run_stiff(compiled, A, B, t, force, x0=x0, v_eps=v_eps, rtol=rtol)
