"""The impedance coordinates' map (``coordinates``): a record's driving-point impedance
at its drive frequency walked instead of the inertance (and the viscous sum).

**Domain** (an assumption of these coordinates, not of the model). The map is one to
one only where the nut and the bearing pass the inerter's impedance on to the drive
nearly as it is. Where the nut is soft beside the inerter's own impedance (c_n and
k_n / omega small against omega b) it hides the inertance: M rises with b and falls
again, and two b give one M. Where a soft bearing resonates near omega, M has a pole in
b. The impedance coordinates therefore cover the part of the prior where the rotation
node's sensitivity G = dZ / dZ_theta stays within |G - 1| < 1/2 for every inertance
(then dM / db lies between 1/2 and 3/2, and the 2 x 2 determinant where C is walked too
exceeds 1/4), with M and C positive: **the prior restricted to that domain**, an
assumption of these coordinates. It cuts off much of the default prior box of the
unidentified deformations (at B2 and 1.5 Hz, a bearing stiffness k_B below 1.1e7 N/m
leaves it, 6 x below the paper's; c_n below half the paper's), none of the paper's
devices: they have |G - 1| <= 0.19 at 0.5-1.5 Hz (the largest at B2, 1.5 Hz, where
omega b is 9 % of the nut's damping c_n), and the full study's posteriors stay well
inside (``fit.json`` records the largest |G - 1| over the kept draws; the command line
warns above ``EDGE_WARNING``). The sampler sees -inf outside; start walkers drawn
outside are drawn again, and a start outside is refused. The
"unconstrained" and "physical" coordinates cover the whole prior. The maps are exact
to rounding inside the domain (round trips and Jacobians are tested against finite
differences across the prior box).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numba import njit

__all__ = ["ImpedanceMap", "driving_point", "MAX_SENSITIVITY_CHANGE", "EDGE_WARNING"]

_NEWTON_ITERATIONS = 30
_NEWTON_RTOL = 1e-13
#: The domain: |G - 1| below this for every inertance (see module docstring).
MAX_SENSITIVITY_CHANGE = 0.5
#: A posterior whose draws reach |G - 1| above this may be cut by the domain: warn.
EDGE_WARNING = 0.4


def driving_point(omega, m_B, m_s, b, c_f1, c_f2, c_n, k_n, c_B, k_B):
    """Driving-point impedance Z = F / v (complex, N s/m) of the reduced network's linear
    part at omega (rad/s), and G = dZ / dZ_theta, the sensitivity to the impedance
    jw b + c_f2 of the rotation node. Plate m_B with c_f1; bearing c_B + k_B / jw;
    screw m_s; nut c_n + k_n / jw; inertance b with c_f2 (the paper's Fig. 5 with the
    Coulomb terms off). Works on scalars and on arrays alike."""
    jw = 1j * omega
    z_th = jw * b + c_f2
    z_n = c_n + k_n / jw
    z_nb = 1.0 / (1.0 / z_n + 1.0 / z_th)
    z_s = jw * m_s + z_nb
    z_b = c_B + k_B / jw
    z_p = 1.0 / (1.0 / z_b + 1.0 / z_s)
    z = jw * m_B + c_f1 + z_p
    g = (z_p / z_s) ** 2 * (z_nb / z_th) ** 2
    return z, g


@njit(cache=True, error_model="numpy")
def _div(a, b):
    """Complex a / b, as numpy divides: by zero, (Re a / 0, Im a / 0), infinite or NaN
    (numba's own complex division raises there)."""
    if b.real == 0.0 and b.imag == 0.0:
        return complex(a.real / 0.0, a.imag / 0.0)
    return a / b


@njit(cache=True, error_model="numpy")
def _source_value(row, idx, log, value):
    """One network entry of a row of v: sampled (its index and whether in log scale) or
    fixed (``value``, where ``idx`` < 0)."""
    if idx < 0:
        return value
    return np.exp(row[idx]) if log else row[idx]


@njit(cache=True, error_model="numpy")  # a division by zero gives inf or NaN, as numpy's
def _damping_rows(v, i_b, i_c, idx, log, value, omega, m_B, m_s, iterations, rtol):
    """:meth:`ImpedanceMap.inverse` and :meth:`ImpedanceMap.log_jacobian` of the damping
    map for each row of ``v`` (rows x ndim): (theta, log |det d theta_map / d u_map|),
    both NaN in rows outside the domain. ``idx``, ``log``, ``value``: where c_share, c_n,
    k_n, c_B and k_B come from (:meth:`ImpedanceMap._sources`). The same Newton iteration
    and formulas as the array code, each row stopped at its own convergence; the results
    agree with it to rounding."""
    n = v.shape[0]
    theta = v.copy()
    logj = np.full(n, np.nan)
    jw = 1j * omega
    ONE = 1.0 + 0j
    for r in range(n):
        row = v[r]
        sr = _source_value(row, idx[0], log[0], value[0])
        c_n = _source_value(row, idx[1], log[1], value[1])
        k_n = _source_value(row, idx[2], log[2], value[2])
        c_B = _source_value(row, idx[3], log[3], value[3])
        k_B = _source_value(row, idx[4], log[4], value[4])
        z_n = c_n + _div(k_n + 0j, jw)
        z_b = c_B + _div(k_B + 0j, jw)
        C = np.exp(row[i_c])
        target = C + jw * np.exp(row[i_b])
        c_f = C
        for _ in range(iterations):
            w_p = target - jw * m_B - sr * c_f
            z_s = _div(ONE, _div(ONE, w_p) - _div(ONE, z_b))
            z_nb = z_s - jw * m_s
            z_th = _div(ONE, _div(ONE, z_nb) - _div(ONE, z_n))
            g = z_th.real - (1.0 - sr) * c_f
            q = _div(z_th, z_nb) * _div(z_s, w_p)
            dg = (-sr * q * q).real - (1.0 - sr)
            step = g / dg
            c_f = c_f - step
            if abs(step) <= rtol * abs(c_f):
                break
        w_p = target - jw * m_B - sr * c_f
        z_s = _div(ONE, _div(ONE, w_p) - _div(ONE, z_b))
        z_th = _div(ONE, _div(ONE, z_s - jw * m_s) - _div(ONE, z_n))
        b = z_th.imag / omega
        solved = abs(z_th.real - (1.0 - sr) * c_f) <= 1e-9 * abs(target)
        if solved and 0.0 < b < np.inf and 0.0 < c_f < np.inf:
            # the driving point at the solution: its sensitivity G decides the domain
            zt = jw * b + c_f * (1.0 - sr)
            z_nb = _div(ONE, _div(ONE, z_n) + _div(ONE, zt))
            z_s = jw * m_s + z_nb
            z_p = _div(ONE, _div(ONE, z_b) + _div(ONE, z_s))
            z = jw * m_B + c_f * sr + z_p
            a1 = _div(z_p, z_s)
            a2 = _div(z_nb, zt)
            gg = (a1 * a1) * (a2 * a2)
            if abs(gg - 1.0) < MAX_SENSITIVITY_CHANGE:
                det = sr * gg.real + (1.0 - sr) * abs(gg) ** 2
                theta[r, i_b] = np.log(b)
                theta[r, i_c] = np.log(c_f)
                logj[r] = np.log((z.imag / omega) * z.real / (b * c_f)) - np.log(abs(det))
                continue
        theta[r, :] = np.nan
    return theta, logj


def _blank(x, bad):
    """x with the rows flagged in ``bad`` (leading axes) set to NaN."""
    if np.ndim(bad):
        x[bad] = np.nan
    elif bad:
        x[...] = np.nan
    return x


@dataclass(frozen=True)
class ImpedanceMap:
    """Which entries of theta the impedance coordinates replace, and where the rest of
    the network's linear part comes from.

    Attributes
    ----------
    omega : reference angular frequency, rad/s.
    m_B : plate mass, kg.
    b_index : positions of log b (one per inertance: one record, or one per setting).
    m_s : screw mass of each inertance's setting, kg.
    damping : also walk C = Re Z instead of log c_f (one inertance, viscous sum and
        share sampled: the single-record two-port model).
    source : for c_f, c_share, c_f1, c_f2, c_n, k_n, c_B, k_B: (index in theta, log
        scale) or a fixed value (kg, N s/m, N/m). c_f and c_share, when present, give
        c_f1 = c_f c_share and c_f2 = c_f (1 - c_share).
    """

    omega: float
    m_B: float
    b_index: tuple
    m_s: tuple
    damping: bool
    source: dict = field(default_factory=dict)

    def _get(self, v, name):
        src = self.source[name]
        if isinstance(src, tuple):
            i, log = src
            return np.exp(v[..., i]) if log else v[..., i]
        return src

    def _viscous(self, v):
        """(c_f1, c_f2, the plate's share or None) at v."""
        if "c_f" in self.source:
            c = self._get(v, "c_f")
            s = self._get(v, "c_share")
            return c * s, c * (1.0 - s), s
        return self._get(v, "c_f1"), self._get(v, "c_f2"), None

    def _network(self, v):
        return [self._get(v, n) for n in ("c_n", "k_n", "c_B", "k_B")]

    @staticmethod
    def _inside(g):
        """Whether a point whose rotation node has sensitivity g is in the domain."""
        return np.abs(g - 1.0) < MAX_SENSITIVITY_CHANGE

    def sensitivity_change(self, theta):
        """max over the inertances of |G - 1| at theta (any leading axes): how near the
        domain's edge (``MAX_SENSITIVITY_CHANGE``) a point lies."""
        theta = np.asarray(theta, dtype=float)
        c_n, k_n, c_B, k_B = self._network(theta)
        c1, c2, _ = self._viscous(theta)
        worst = np.zeros(theta.shape[:-1])
        for i, m_s in zip(self.b_index, self.m_s):
            _, g = driving_point(self.omega, self.m_B, m_s, np.exp(theta[..., i]), c1, c2, c_n, k_n, c_B, k_B)
            worst = np.maximum(worst, np.abs(g - 1.0))
        return worst

    def forward(self, theta):
        """u's impedance entries from theta (other entries copied); NaN rows outside the
        domain."""
        theta = np.asarray(theta, dtype=float)
        u = theta.copy()
        c_n, k_n, c_B, k_B = self._network(theta)
        c1, c2, s = self._viscous(theta)
        inside = np.ones(theta.shape[:-1], dtype=bool)
        with np.errstate(all="ignore"):
            for i, m_s in zip(self.b_index, self.m_s):
                z, g = driving_point(self.omega, self.m_B, m_s, np.exp(theta[..., i]), c1, c2, c_n, k_n, c_B, k_B)
                inside &= self._inside(g) & (z.imag > 0) & (z.real > 0 if self.damping else True)
                u[..., i] = np.log(z.imag / self.omega)
                if self.damping:
                    u[..., self.source["c_f"][0]] = np.log(z.real)
        return _blank(u, ~inside)

    def inverse(self, u):
        """theta from u (entries outside the map copied); NaN rows where the solution is
        not in the domain (or there is none)."""
        if self.damping:
            return self.inverse_with_jacobian(u)[0]
        th = np.array(u, dtype=float)
        c_n, k_n, c_B, k_B = self._network(th)
        jw = 1j * self.omega
        z_n, z_b = c_n + k_n / jw, c_B + k_B / jw
        bad = np.zeros(th.shape[:-1], dtype=bool)
        with np.errstate(all="ignore"):
            c1, c2, _ = self._viscous(th)
            for i, m_s in zip(self.b_index, self.m_s):
                b = self._solve_inertance(np.exp(th[..., i]), m_s, c1, c2, z_n, z_b)
                bad |= ~((b > 0) & np.isfinite(b))
                th[..., i] = np.log(b)
            for i, m_s in zip(self.b_index, self.m_s):
                _, g = driving_point(self.omega, self.m_B, m_s, np.exp(th[..., i]), c1, c2, c_n, k_n, c_B, k_B)
                bad |= ~self._inside(g)
        return _blank(th, bad)

    def inverse_with_jacobian(self, u):
        """(:meth:`inverse` at u, :meth:`log_jacobian` there) in one pass; the log-Jacobian
        is NaN where theta is. The damping map (one inertance, the viscous sum and share
        sampled: the single-record model) is solved by :func:`_damping_rows`, a compiled
        loop over the rows (about 15 times faster than numpy on 13 walkers)."""
        if not self.damping:
            theta = self.inverse(u)
            return theta, self.log_jacobian(theta)
        u = np.asarray(u, dtype=float)
        shape = u.shape
        idx, log, value = self._sources
        theta, logj = _damping_rows(np.ascontiguousarray(u.reshape(-1, shape[-1])), self.b_index[0],
                                    self.source["c_f"][0], idx, log, value, self.omega, self.m_B, self.m_s[0],
                                    _NEWTON_ITERATIONS, _NEWTON_RTOL)
        return theta.reshape(shape), logj.reshape(shape[:-1])

    @cached_property
    def _sources(self):
        """Where c_share, c_n, k_n, c_B and k_B come from, as :func:`_damping_rows` takes it:
        (indices in theta, -1 where fixed; whether in log scale; the fixed values)."""
        idx, log, value = [], [], []
        for name in ("c_share", "c_n", "k_n", "c_B", "k_B"):
            src = self.source[name]
            sampled = isinstance(src, tuple)
            idx.append(src[0] if sampled else -1)
            log.append(bool(src[1]) if sampled else False)
            value.append(0.0 if sampled else float(src))
        return np.array(idx, dtype=np.int64), np.array(log, dtype=np.bool_), np.array(value, dtype=float)

    def _solve_inertance(self, M, m_s, c1, c2, z_n, z_b):
        """b with Im Z / omega = M, by Newton (d(Im Z / omega) / db = Re G, about 1)."""
        w, jw = self.omega, 1j * self.omega

        def residual(b):  # (Im Z / omega - M, its derivative in b)
            z_th = jw * b + c2
            z_nb = 1.0 / (1.0 / z_n + 1.0 / z_th)
            z_s = jw * m_s + z_nb
            z_p = 1.0 / (1.0 / z_b + 1.0 / z_s)
            return z_p.imag / w + self.m_B - M, ((z_p / z_s) ** 2 * (z_nb / z_th) ** 2).real

        b = np.maximum(M - self.m_B - m_s, 1e-3 * M)
        for _ in range(_NEWTON_ITERATIONS):
            f, g = residual(b)
            step = f / g
            b = np.maximum(b - step, 0.1 * b)
            if np.all(np.abs(step) <= _NEWTON_RTOL * np.abs(b)):
                break
        converged = np.abs(residual(b)[0]) <= 1e-9 * np.abs(M)
        return np.where(converged, b, np.nan)

    def log_jacobian(self, theta):
        """log |det d theta_map / d u_map| at theta (the map's entries only; the others
        enter the impedance as constants, so the full Jacobian is block triangular)."""
        c_n, k_n, c_B, k_B = self._network(theta)
        c1, c2, s = self._viscous(theta)
        total = 0.0
        with np.errstate(all="ignore"):
            for i, m_s in zip(self.b_index, self.m_s):
                b = np.exp(theta[..., i])
                z, g = driving_point(self.omega, self.m_B, m_s, b, c1, c2, c_n, k_n, c_B, k_B)
                M = z.imag / self.omega
                if self.damping:
                    c_f = np.exp(theta[..., self.source["c_f"][0]])
                    det = s * g.real + (1.0 - s) * np.abs(g) ** 2
                    total = total + np.log(M * z.real / (b * c_f)) - np.log(np.abs(det))
                else:
                    total = total + np.log(M / b) - np.log(np.abs(g.real))
        return total
