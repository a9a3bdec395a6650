"""Sampler coordinates: where emcee walks, apart from the model's named parameters.

A model's parameters theta (``model.names``: log b, log f_0, f_share, ...) are what a
user reads, what the priors are written on, and what every output reports. The sampler
may walk in other coordinates u, with theta = T(u), in which the posterior is rounder;
its target there is the same posterior carried over with its Jacobian,

    log p_u(u) = log p(T(u)) + log |det dT/du|,

so the choice changes how fast a chain mixes, not what it converges to, within the
coordinates' domain (the impedance coordinates restrict the prior to it:
:mod:`..posterior.impedance`). Two changes from theta, used together by default
(:func:`default_coordinates`):

- **impedance**: a record fixes the driving-point impedance Z = F / v of the network's
  linear part at its drive frequency omega very tightly, and not the parameters that
  make it up. Its inertial part M = Im Z / omega (kg) and resistive part C = Re Z
  (N s/m) are walked instead of b and the viscous sum c_f; given M, C and the other
  parameters, b and c_f follow exactly (c_f by a Newton iteration in one unknown, b in
  closed form). The nut's stiffness, the bearing and the viscous split then move without
  dragging b and c_f along the curved ridges they make in theta (b against k_n / c_n^2
  through the nut, against k_B through the bearing's compliance; c_f against k_n where
  the nut's spring takes over from its damper). In the joint model each setting's b is
  walked as that setting's M at one reference frequency (its c_f is shared, so C is not
  walked).
- **unconstrained**: every other coordinate, bounded by its prior's box [lo, hi], is
  walked as the logit of its position in the box, so the prior's hard walls (which the
  unidentified nut stiffness, bearing damping and friction shares pile against) become
  smooth tails that ensemble moves do not overshoot.

A third, **series** (``kind="series"``: the impedance coordinates and this), walks the
nut's and the bearing's stiffnesses as their series stiffness and the ratio of the two,

    s = log k_s = -log(1/k_n + 1/k_B),    d = log k_B - log k_n,

each as the logit of its place in the range the prior box leaves it (d's range depends
on s). The records fix the compliance between the plate and the rotation, 1/k_n + 1/k_B,
and not how it is shared: in theta the two stiffnesses lie on a bent ridge (measured on
a paper-like A3 record at 1 Hz: log k_n against log k_B correlated -0.79, the series
stiffness within +-11 % while the nut's share of the compliance spanned 0.55 to 0.99),
which in (s, d) is an axis. The map (log k_n, log k_B) -> (s, d) keeps volume (its
Jacobian determinant is 1); the logits add theirs. Not the default: measured side by
side (``benchmarks/bench_coordinates.py``, laboratory 11, 4,000 steps, one seed) it
halved k_n's and k_B's autocorrelation times on A3 at 1 Hz but the slowest parameter's
went to 0.83, 1.39 and 3.40 times the impedance coordinates' on A3 at 1 and 0.5 Hz and
B1 at 1.5 Hz (the nut's damper c_n, and on B1 every parameter, slower).

A fourth, **compliance** (``kind="compliance"``: the impedance coordinates and this),
walks log c_n, log k_n and log k_B as the nut and bearing's series impedance at the
drive frequency, the nut's phase and the bearing's share (:class:`SeriesCompliance`):
the records fix that impedance, spring- or damper-like. Not the default: measured side
by side on four records at 1 Hz and two laboratories, the slowest parameter's tau was
0.67 to 1.55 times the impedance coordinates' (median 0.96; docs/inference.md).

Measured on the full study's A3 1 Hz record (3,000 steps, 24 walkers, the same start,
seed and moves): the largest integrated autocorrelation time (in theta) fell from 180
steps in theta (with the nut-ridge move) to 108 with the impedance coordinates and 94
with both; R-hat of the last three quarters from 1.97 to 1.09 and 1.06.

The impedance map, and the domain it restricts the prior to: :mod:`..posterior.impedance`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..posterior.impedance import EDGE_WARNING, MAX_SENSITIVITY_CHANGE, ImpedanceMap, driving_point

__all__ = ["Coordinates", "ImpedanceMap", "SeriesStiffness", "SeriesCompliance", "driving_point", "default_coordinates", "COORDINATES",
           "drive_omega", "reference_tolerance", "continue_at",
           "MAX_SENSITIVITY_CHANGE", "EDGE_WARNING"]

#: The coordinate systems a fit can use (``--coordinates``).
COORDINATES = ("impedance", "unconstrained", "physical", "series", "compliance")


@dataclass(frozen=True)
class Coordinates:
    """The map theta = T(u) of one model (see module docstring).

    Attributes
    ----------
    kind : one of :data:`COORDINATES`.
    lo, hi : shape (ndim,), the prior box of theta (where ``logit`` is true).
    logit : shape (ndim,), which entries are walked as the logit of their place in the box.
    impedance : the impedance map, or None.
    series : the indices in theta of log k_n and log k_B where they are walked as their
        series stiffness and ratio (:class:`SeriesStiffness`), or None.
    compliance : the indices in theta of log c_n, log k_n and log k_B and the angular
        frequency where they are walked as the nut and bearing's series compliance there,
        the nut's phase and the bearing's share (:class:`SeriesCompliance`), or None.
    """

    kind: str
    lo: np.ndarray
    hi: np.ndarray
    logit: np.ndarray
    impedance: ImpedanceMap | None = None
    series: tuple | None = None
    compliance: tuple | None = None

    def _pair(self):
        i, j = self.series
        return SeriesStiffness(self.lo[i], self.hi[i], self.lo[j], self.hi[j])

    def _unbox(self, u):
        """u with the logit entries carried back into the prior box, and their log |dT/du|."""
        u = np.array(u, dtype=float)
        logj = np.zeros(u.shape[:-1])
        if self.logit.any():
            u[..., self.logit], lj = _from_logit(u[..., self.logit], self.lo[self.logit], self.hi[self.logit])
            logj = logj + np.sum(lj, axis=-1)
        if self.series is not None:
            i, j = self.series
            a, c, lj = self._pair().to_logs(u[..., i], u[..., j])
            u[..., i], u[..., j] = a, c
            logj = logj + lj
        if self.compliance is not None:
            i, j, k, omega = self.compliance
            u[..., i], u[..., j], u[..., k] = SeriesCompliance(omega).to_logs(u[..., i], u[..., j], u[..., k])
        return u, logj

    def to_theta(self, u) -> np.ndarray:
        """theta from u, any leading axes; NaN where u is outside the domain."""
        return self.transform(u)[0]

    def transform(self, u):
        """(theta, log |det d theta / d u|) at u, any leading axes; theta NaN and the
        log-Jacobian NaN or infinite where u is outside the domain."""
        v, logj = self._unbox(u)
        if self.impedance is None:
            return v, logj
        theta, map_logj = self.impedance.inverse_with_jacobian(v)
        return theta, logj + map_logj

    def to_u(self, theta) -> np.ndarray:
        """u from theta (strictly inside the prior box where walked as logits)."""
        theta = np.asarray(theta, dtype=float)
        u = theta.copy() if self.impedance is None else self.impedance.forward(theta)
        if self.logit.any():
            u[..., self.logit] = _to_logit(theta[..., self.logit], self.lo[self.logit], self.hi[self.logit])
        if self.series is not None:
            i, j = self.series
            u[..., i], u[..., j] = self._pair().from_logs(theta[..., i], theta[..., j])
        if self.compliance is not None:
            i, j, k, omega = self.compliance
            u[..., i], u[..., j], u[..., k] = SeriesCompliance(omega).from_logs(theta[..., i], theta[..., j],
                                                                               theta[..., k])
        return u

    def contains(self, theta) -> bool:
        """Whether every point of ``theta`` (..., ndim) lies in these coordinates' domain
        (its u finite): outside it, a walker cannot be placed there."""
        return bool(np.all(np.isfinite(self.to_u(np.asarray(theta, dtype=float)))))

    def log_jacobian(self, u) -> np.ndarray | float:
        """log |det d theta / d u| at u."""
        return self.transform(u)[1]

    def domain_edge(self, theta) -> float | None:
        """The largest |G - 1| over the draws ``theta`` (..., ndim), or None without an
        impedance map: near ``MAX_SENSITIVITY_CHANGE`` the domain may cut the posterior."""
        if self.impedance is None:
            return None
        return float(np.nanmax(self.impedance.sensitivity_change(theta)))

    def describe(self) -> str:
        """One line naming the coordinates (in fit.json; a checkpoint stores their fields)."""
        if self.impedance is None:
            return self.kind
        imp = self.impedance
        walked = "M, C" if imp.damping else f"M x{len(imp.b_index)}"
        if self.series is not None:
            walked += "; k_n, k_B as series stiffness and ratio"
        if self.compliance is not None:
            walked += "; c_n, k_n, k_B as series compliance, nut phase and bearing share"
        return f"{self.kind} ({walked} at {imp.omega / (2 * math.pi):.6g} Hz; logit elsewhere)"


def _from_logit(z, lo, hi):
    """The point at logit ``z`` of its place in [lo, hi], and log |dx/dz| (elementwise)."""
    with np.errstate(over="ignore"):
        x = lo + (hi - lo) / (1.0 + np.exp(-z))
    return x, np.log(hi - lo) - np.logaddexp(0.0, -z) - np.logaddexp(0.0, z)


def _to_logit(x, lo, hi):
    """The logit of ``x``'s place in [lo, hi] (infinite on its ends, NaN outside)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        p = (x - lo) / (hi - lo)
        return np.log(p) - np.log1p(-p)


def _log_expm1(x):
    """log(exp(x) - 1) for x > 0, without overflow."""
    x = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.where(x > 30.0, x + np.log1p(-np.exp(-np.minimum(x, 700.0))), np.log(np.expm1(x)))


@dataclass(frozen=True)
class SeriesStiffness:
    """The map between (log k_n, log k_B) in the box [a_lo, a_hi] x [c_lo, c_hi] and the
    walked pair (z_s, z_d): s = log k_s = -log(1/k_n + 1/k_B) as the logit of its place
    in [s_lo, s_hi], and d = log k_B - log k_n as the logit of its place in the range
    [d_lo(s), d_hi(s)] that the box leaves it at that s. Inverse: log k_n = s +
    log(1 + e^-d), log k_B = s + log(1 + e^d)."""

    a_lo: float
    a_hi: float
    c_lo: float
    c_hi: float

    @property
    def s_range(self):
        return -np.logaddexp(-self.a_lo, -self.c_lo), -np.logaddexp(-self.a_hi, -self.c_hi)

    def d_range(self, s):
        """The range of d the box leaves at series stiffness s (log k_n <= a_hi and
        log k_B >= c_lo bound it below, log k_B <= c_hi and log k_n >= a_lo above)."""
        s = np.asarray(s, dtype=float)
        with np.errstate(invalid="ignore"):
            lo = np.maximum(-_log_expm1(self.a_hi - s),
                            np.where(self.c_lo > s, _log_expm1(np.maximum(self.c_lo - s, 1e-300)), -np.inf))
            hi = np.minimum(_log_expm1(self.c_hi - s),
                            np.where(self.a_lo > s, -_log_expm1(np.maximum(self.a_lo - s, 1e-300)), np.inf))
        return lo, hi

    def to_logs(self, z_s, z_d):
        """(log k_n, log k_B, log |det d(log k_n, log k_B) / d(z_s, z_d)|)."""
        s, lj_s = _from_logit(z_s, *self.s_range)
        d, lj_d = _from_logit(z_d, *self.d_range(s))
        # (s, d) -> (log k_n, log k_B) keeps volume: only the logits' Jacobians remain
        return s + np.logaddexp(0.0, -d), s + np.logaddexp(0.0, d), lj_s + lj_d

    def from_logs(self, a, c):
        """(z_s, z_d) at log k_n = a, log k_B = c (NaN or infinite outside the box)."""
        s = -np.logaddexp(-a, -c)
        return _to_logit(s, *self.s_range), _to_logit(c - a, *self.d_range(s))


@dataclass(frozen=True)
class SeriesCompliance:
    """The map between (log c_n, log k_n, log k_B) and the walked (S, psi, rho) at the
    angular frequency ``omega``: the nut z_n = c_n + k_n / (i omega) in series with the
    bearing taken as its spring, k_B / (i omega),

        S = -log |1 / z_n + i omega / k_B|   (the pair's series impedance, log N s/m)
        psi = log(k_n / (omega c_n))         (the nut's phase: spring- or damper-like)
        rho = log(k_B / omega) - log |z_n|   (the bearing's impedance beside the nut's)

    A record fixes S and not the other two: on paper-like records at 1 Hz the posterior
    draws held S within 0.03 to 0.04 decades (sd) while c_n spanned up to 1.25 decades
    and k_n 0.55, the nut spring-like on A3 and damper-like on B2. The map is one to one
    on all of R^3 and keeps volume (its Jacobian determinant is 1: log |z_n| = S + log |g|
    with g = (1 + i e^psi) / sqrt(1 + e^(2 psi)) + i e^-rho, and the rest is a triangular
    shift), so it adds no Jacobian term; the prior box is not mapped (a walker outside it
    meets the prior's -inf)."""

    omega: float

    def to_logs(self, S, psi, rho):
        """(log c_n, log k_n, log k_B) at (S, psi, rho)."""
        h = 0.5 * np.logaddexp(0.0, 2.0 * np.asarray(psi, dtype=float))
        with np.errstate(over="ignore", invalid="ignore"):
            cos, sin = np.exp(-h), np.exp(psi - h)
            lz = S + 0.5 * np.log(cos ** 2 + (sin + np.exp(-np.asarray(rho, dtype=float))) ** 2)
        lw = math.log(self.omega)
        return lz - h, lw + lz + psi - h, lw + lz + rho

    def from_logs(self, a, k, c):
        """(S, psi, rho) at log c_n = a, log k_n = k, log k_B = c."""
        lw = math.log(self.omega)
        psi = k - lw - a
        lz = 0.5 * np.logaddexp(2.0 * np.asarray(a, dtype=float), 2.0 * (k - lw))
        rho = c - lw - lz
        h = 0.5 * np.logaddexp(0.0, 2.0 * psi)
        with np.errstate(over="ignore", invalid="ignore"):
            g2 = np.exp(-2.0 * h) + (np.exp(psi - h) + np.exp(-rho)) ** 2
        return lz - 0.5 * np.log(g2), psi, rho


def drive_omega(record) -> float:
    """Angular drive frequency of a record, rad/s: its metadata's, or else the record's
    own estimate (``records.drive.resolve_drive``, the same everywhere in a fit)."""
    from ...records.drive import resolve_drive

    return 2.0 * math.pi * resolve_drive(record).hz


def reference_tolerance(model) -> float:
    """rad/s: how far the impedance coordinates' reference frequency may move and still be
    the same drive to the model's records: half a bin of the shortest record's spectrum,
    pi / T (``records.drive.DriveFrequency.resolution_hz``). A drive frequency given in
    the metadata and the same estimated from the record differ by far less."""
    parts = getattr(model, "parts", None) or [model]
    return min(math.pi / p.record.duration for p in parts)


def continue_at(coords: Coordinates, stored: dict | None, tolerance: float) -> Coordinates:
    """``coords`` at the reference frequency of a checkpoint's coordinates ``stored``
    (its identity's "coordinates" entry) where that frequency is within ``tolerance``
    (rad/s) of this run's: the reference is a choice, not a measurement, and any
    frequency that near the drive makes an equally good map, so the chain is continued
    in the coordinates it was written in. Else ``coords`` as they are (a checkpoint that
    differs further, or in anything else, is refused as before)."""
    imp = coords.impedance
    then = ((stored or {}).get("impedance") or {}).get("omega")
    if imp is None or not isinstance(then, (int, float)) or then == imp.omega or abs(then - imp.omega) > tolerance:
        return coords
    compliance = coords.compliance and (*coords.compliance[:3], float(then))
    return dataclasses.replace(coords, impedance=dataclasses.replace(imp, omega=float(then)), compliance=compliance)


def _source(model, fixed: dict) -> dict:
    """Where each network entry comes from: (index, log scale) if sampled, else its value."""
    names = list(model.names)
    out = {}
    for n in ("c_f", "c_share", "c_f1", "c_f2", "c_n", "k_n", "c_B", "k_B"):
        if n in names:
            i = names.index(n)
            out[n] = (i, bool(model.all_priors[n].log_scale))
        elif n in fixed and n not in ("c_f", "c_share"):
            out[n] = float(fixed[n])
    if "c_f" not in out:
        out.pop("c_share", None)
    return out


def _impedance_map(model) -> ImpedanceMap | None:
    """The impedance map of a single-record or joint model, or None where it does not
    apply (networks other than the reduced and linear ones; b, k_n, c_n not in log scale)."""
    parts = getattr(model, "parts", None)
    first = parts[0] if parts else model
    if first.network not in ("reduced", "linear"):
        return None
    fixed = dict(first.fixed)
    if first.network == "linear":  # every friction block bypassed: no viscous terms either
        fixed.update(c_f1=0.0, c_f2=0.0)
    source = _source(model, fixed)
    if not all(k in source for k in ("c_n", "k_n", "c_B", "k_B")):
        return None
    if "c_f" not in source and not ("c_f1" in source and "c_f2" in source):
        return None
    names = list(model.names)
    if parts:
        b_names = [f"b_{s}" for s in model.settings]
        m_s = [next(p.m_s for p, s in zip(parts, model.setting_of) if s == name) for name in model.settings]
        omega = 2.0 * math.pi * float(np.median(model.freq_of))
        m_B = {p.m_B for p in parts}
        if len(m_B) != 1:
            return None
        m_B = m_B.pop()
    else:
        b_names, m_s, omega, m_B = ["b"], [model.m_s], drive_omega(model.record), model.m_B
    if not all(n in names and model.all_priors[n].log_scale for n in b_names):
        return None
    damping = not parts and "c_f" in source and source["c_f"][1]
    return ImpedanceMap(omega=omega, m_B=float(m_B), b_index=tuple(names.index(n) for n in b_names),
                        m_s=tuple(float(x) for x in m_s), damping=bool(damping), source=source)


def default_coordinates(model, kind: str = "impedance") -> Coordinates:
    """The coordinates ``kind`` (one of :data:`COORDINATES`) for ``model``: "impedance"
    falls back to "unconstrained" where the model has no impedance map (the rigid
    model) and for the linear model under the motion-in likelihood; "physical" walks
    theta itself."""
    if kind not in COORDINATES:
        raise ValueError(f"unknown coordinates {kind!r}; choose one of {', '.join(COORDINATES)}")
    bounds = np.asarray(model.bounds(), dtype=float)
    lo, hi = bounds[:, 0].copy(), bounds[:, 1].copy()
    ndim = len(lo)
    if kind == "physical":
        return Coordinates("physical", lo, hi, np.zeros(ndim, dtype=bool))
    imp = _impedance_map(model) if kind in ("impedance", "series", "compliance") else None
    if getattr(model, "motion", None) is not None and getattr(model, "model", "") == "linear":
        # measured: on the quick study's A3 record at 1 Hz the linear model's motion-in
        # optimum lay outside the map's domain, so its walkers could not start there
        imp = None
    logit = np.ones(ndim, dtype=bool)
    if imp is not None:
        logit[list(imp.b_index)] = False
        if imp.damping:
            logit[imp.source["c_f"][0]] = False
    series = _series_pair(model) if kind == "series" and imp is not None else None
    if series is not None:
        logit[list(series)] = False
    compliance = _compliance_triple(model, imp) if kind == "compliance" and imp is not None else None
    if compliance is not None:
        logit[list(compliance[:3])] = False
    name = ("unconstrained" if imp is None else "series" if series is not None
            else "compliance" if compliance is not None else "impedance")
    return Coordinates(name, lo, hi, logit, imp, series, compliance)


def _compliance_triple(model, imp: ImpedanceMap) -> tuple | None:
    """(index of log c_n, of log k_n, of log k_B, omega) for one record's model whose
    three are sampled in log scale, else None."""
    names = list(model.names)
    if getattr(model, "parts", None) or not all(n in names and model.all_priors[n].log_scale
                                                for n in ("c_n", "k_n", "k_B")):
        return None
    return names.index("c_n"), names.index("k_n"), names.index("k_B"), float(imp.omega)


def _series_pair(model) -> tuple | None:
    """The indices of k_n and k_B in theta where both are sampled in log scale."""
    names = list(model.names)
    if not all(n in names and model.all_priors[n].log_scale for n in ("k_n", "k_B")):
        return None
    return names.index("k_n"), names.index("k_B")
