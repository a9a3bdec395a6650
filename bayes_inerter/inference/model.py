"""The statistical model: parameters, priors, and the likelihood of one record.

The data are the record's acceleration, compared with the simulated one (driven by the
record's force) through the same zero-phase low-pass (``records.lowpass``), on a grid
thinned to every ``stride``-th sample inside the record less ``edge`` seconds at each
end. The residual is modelled as

- ``"ar1"`` (default): a stationary AR(1) process, r_t = rho r_{t-1} + e_t, e_t ~ N(0, sigma^2),
  with sigma and rho unknown. Model error leaves residuals far from white; the AR(1)
  term lets the data say how correlated they are, which keeps intervals honest.
- ``"iid"``: independent N(0, sigma^2) (MODEL.md section 7 measured it overconfident).

Parameters are sampled as theta = log(value) (see ``priors``); sigma too; rho as is.
The fit accuracy phi (eq. 5, on the low-passed signals inside the window) is a derived
quantity of every evaluation.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy import signal

from ..device import TABLE_I, InerterParameters, apparent_inertance
from ..models import FIELDS, linear_chain
from ..network.compile import chain_state_space
from ..records.conditioning import lowpass
from ..masses import resolve_masses
from ..records.drive import resolve_drive, with_drive
from ..records.record import Record
from ..simulate import Drive, SimulationError, check_record, contacts, run_exact, simulate, simulate_network
from .effects import EFFECT_PRIORS, EFFECTS, NO_EFFECT, effect_network
from .likelihood import LikelihoodSettings
from .priors import DEFAULT_PRIORS, NOISE_PRIORS, SPLIT_PRIORS

__all__ = ["MODELS", "LikelihoodSettings", "PosteriorModel", "record_masses"]

PHYSICAL = ("b", "f1_0", "c_f1", "f2_0", "c_f2", "c_n", "k_n", "c_B", "k_B")
_F1, _C1, _F2, _C2 = (FIELDS.index(n) for n in ("f1_0", "c_f1", "f2_0", "c_f2"))


@njit(cache=True)
def _misfit(sim, grid, observed, w0, w1, measured):
    """(sim - observed on the grid, sum of (sim - measured)^2 over [w0, w1), all finite)."""
    ok = True
    for k in range(sim.shape[0]):
        if not np.isfinite(sim[k]):
            ok = False
    r = np.empty(grid.shape[0])
    for i in range(grid.shape[0]):
        r[i] = sim[grid[i]] - observed[i]
    sq = 0.0
    for k in range(w0, w1):
        d = sim[k] - measured[k]
        sq += d * d
    return r, sq, ok

#: The nested models: network and the parameters each one frees (the rest fixed).
#: In ``rigid`` one body carries one friction: f1_0 and c_f1 are the totals (f2 = 0).
#: The richer models add effects the paper's model lacks (:mod:`.effects`).
MODELS = {
    "two-port": ("reduced", PHYSICAL),
    "rigid": ("rigid", ("b", "f1_0", "c_f1")),
    "linear": ("linear", ("b", "c_n", "k_n", "c_B", "k_B")),
    **{name: ("reduced", PHYSICAL + extra) for name, extra in EFFECTS.items()},
}


#: ``b_app`` (the inertance seen through the nut, to first order in k_n / (omega c_n))
#: is reported only where k_n / (omega c_n) is below this: an assumption of this
#: package's reporting, not of the model.
B_APP_VALIDITY = 0.1


def record_masses(record: Record, m_s: float | None = None, m_B: float | None = None) -> tuple[float, float]:
    """m_s and m_B (kg) from the options, else the record's metadata (m_s, or setting),
    else (m_B) the paper's; :func:`..masses.resolve_masses` says where each came from."""
    found = resolve_masses(record, m_s=m_s, m_B=m_B)
    return found.m_s, found.m_B


@dataclass
class PosteriorModel:
    """Log-posterior of one record under one of :data:`MODELS`.

    ``log_prob(theta)`` returns (log posterior, phi); -inf and NaN where the parameters
    lie outside the prior or the simulation fails.

    Parametrisation (``split``, default True for the two-port model): the two Coulomb
    forces and the two viscous coefficients are sampled as sums and the plate's share,
    ``f_0 = f1_0 + f2_0``, ``f_share = f1_0 / f_0``, ``c_f = c_f1 + c_f2``,
    ``c_share = c_f1 / c_f``, because the data fix the sums well and the shares poorly
    (v_B and v_th are nearly equal: MODEL.md section 7), and walkers move freely along a
    share where they crawl along the curved ridge of the raw pair. The priors are then
    on the sums (log-uniform) and the shares (uniform): a documented choice. The four
    raw values are reported as derived quantities. ``split=False`` samples them directly.

    The drive frequency (``drive``, ``records.drive.DriveFrequency``) is the record's
    metadata's, else its own estimate; ``record`` holds it in its metadata from then on.
    """

    record: Record
    model: str = "two-port"
    m_s: float | None = None
    m_B: float | None = None
    priors: dict = field(default_factory=dict)
    likelihood: LikelihoodSettings = field(default_factory=LikelihoodSettings)
    split: bool | None = None

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise ValueError(f"unknown model {self.model!r}; choose one of {', '.join(MODELS)}")
        rec = self.record
        check_record(rec.time, rec.force, rec.accel, names=("force", "accel"))
        self.m_s, self.m_B = record_masses(rec, self.m_s, self.m_B)
        # settled once: every step that needs it reads the record's metadata
        self.drive = resolve_drive(rec)
        self.record = rec = with_drive(rec, self.drive)
        self.network, self.free = MODELS[self.model]
        self._set_parameters()
        self.fs = rec.fs
        self._set_data()
        self._set_simulation()

    def _set_parameters(self) -> None:
        """The sampled parameters (``names``, split or not), their priors, and the derived
        quantities."""
        pairs = {"f1_0", "f2_0", "c_f1", "c_f2"}
        can_split = pairs <= set(self.free)
        if self.split is None:
            self.split = can_split
        if self.split and not can_split:
            raise ValueError(f"the {self.model} model has no friction pair to split")
        known = set(PHYSICAL) | set(SPLIT_PRIORS) | set(NOISE_PRIORS) | set(EFFECT_PRIORS)
        unknown = set(self.priors) - known
        if unknown:
            raise ValueError(f"priors given for unknown parameters: {', '.join(sorted(unknown))}")
        self.all_priors = {**DEFAULT_PRIORS, **SPLIT_PRIORS, **NOISE_PRIORS, **EFFECT_PRIORS, **self.priors}
        self.effect_names = [n for n in self.free if n in EFFECT_PRIORS]
        if self.split:
            sampled = [n for n in self.free if n not in pairs]
            sampled[1:1] = ["f_0", "f_share", "c_f", "c_share"]
        else:
            sampled = list(self.free)
        self.n_phys = len(sampled)
        self.names = sampled + ["sigma"] + (["rho"] if self.likelihood.residual == "ar1" else [])
        self.derived_names = sorted(pairs, key=PHYSICAL.index) if self.split else []
        if {"b", "k_n", "c_n"} <= set(self.free):
            self.derived_names.append("b_app")
        self._log = np.array([self.all_priors[n].log_scale for n in self.names])

    def _set_data(self) -> None:
        """What the likelihood compares with: the low-passed measured acceleration, its
        window (the record less ``edge`` at each end) and the grid thinned by ``stride``."""
        rec, lk = self.record, self.likelihood
        if not lk.cutoff < self.fs / 2:
            raise ValueError(f"cut-off {lk.cutoff} Hz must be below half the sampling rate {self.fs:g} Hz")
        self.stride = lk.stride or max(1, int(self.fs / (2 * lk.cutoff)))
        n_edge = int(round(lk.edge * self.fs))
        window = np.arange(n_edge, len(rec.time) - n_edge)
        self.window = window
        self.grid = window[:: self.stride]
        if len(self.grid) < 10:
            raise ValueError(
                f"only {len(self.grid)} samples left for the likelihood; the record is too short "
                f"for edge {lk.edge} s and stride {self.stride}"
            )
        self.measured_lp = lowpass(rec.accel, self.fs, lk.cutoff)
        self.observed = self.measured_lp[self.grid]
        m = self.measured_lp[window]
        self._phi_norm = float(np.linalg.norm(m - m.mean()))

    def _set_simulation(self) -> None:
        """What every evaluation's simulation starts from: the drive (upsampled where
        asked), the fixed parameters, and where the sampled ones go in ``models.FIELDS``."""
        rec = self.record
        q = self.likelihood.upsample
        if q > 1:
            n = len(rec.time)
            self._sim_force = signal.resample_poly(rec.force, q, 1)[: (n - 1) * q + 1]
            self._sim_time = rec.time[0] + np.arange(len(self._sim_force)) / (self.fs * q)
        else:
            self._sim_force, self._sim_time = rec.force, rec.time
        self._drive = Drive.of(self._sim_time, self._sim_force)  # checked once, not at every evaluation
        self._force = np.ascontiguousarray(self._drive.force, dtype=float).reshape(-1, 1)
        fixed = dict(TABLE_I, m_s=self.m_s, m_B=self.m_B, b=1.0)
        if self.model == "rigid":
            fixed.update(f2_0=0.0, c_f2=0.0)
        self.fixed = fixed
        # The evaluation's short way (see simulate_lp): the network's arrays straight from
        # the parameters, with no network built; where there is none, simulate().
        self._chain = linear_chain(self.network) if q == 1 and not self.effect_names else None
        self._fixed_vector = np.array([float(fixed[f]) for f in FIELDS])
        pos = {n: i for i, n in enumerate(self.names)}
        direct = [n for n in self.free if n in pos and n in FIELDS]
        self._direct = (np.array([FIELDS.index(n) for n in direct], dtype=int),
                        np.array([pos[n] for n in direct], dtype=int))
        self._split_at = [pos[n] for n in ("f_0", "f_share", "c_f", "c_share")] if self.split else None
        self._positive = np.array([f in ("b", "m_s", "m_B") for f in FIELDS])

    # -- parameter vectors ---------------------------------------------------------
    @property
    def ndim(self) -> int:
        return len(self.names)

    def bounds(self) -> np.ndarray:
        """(ndim, 2) bounds of theta (log space for log-scale priors, else as is)."""
        return np.array([self.all_priors[n].bounds for n in self.names])

    def to_values(self, theta: np.ndarray) -> np.ndarray:
        """Sampled values in SI units (or as is for shares and rho); any leading axes."""
        theta = np.asarray(theta, dtype=float)
        return np.where(self._log, np.exp(np.where(self._log, theta, 0.0)), theta)

    def physical(self, values: dict) -> dict:
        """Raw network parameters (the free ones) from sampled values by name."""
        out = {n: values[n] for n in self.free if n in values}
        if self.split:
            out["f1_0"] = values["f_0"] * values["f_share"]
            out["f2_0"] = values["f_0"] * (1.0 - values["f_share"])
            out["c_f1"] = values["c_f"] * values["c_share"]
            out["c_f2"] = values["c_f"] * (1.0 - values["c_share"])
        return out

    def sampled_from_physical(self, phys: dict) -> dict:
        """Sampled quantities (by name) from raw parameters, where they can be formed."""
        out = {n: phys[n] for n in self.names if n in phys}
        if self.split and all(k in phys for k in ("f1_0", "f2_0", "c_f1", "c_f2")):
            f0, c = phys["f1_0"] + phys["f2_0"], phys["c_f1"] + phys["c_f2"]
            out.update(f_0=f0, c_f=c, f_share=phys["f1_0"] / f0 if f0 > 0 else 0.5,
                       c_share=phys["c_f1"] / c if c > 0 else 0.5)
        return out

    def derived(self, values: dict) -> dict:
        """The derived quantities (``derived_names``) from sampled values by name: the raw
        frictions of the split parametrisation and ``b_app``, the inertance seen through
        the nut (``device.apparent_inertance``), NaN where that first-order quantity is
        not defined: where the nut's spring is not small beside its damper at the drive,
        k_n / (omega c_n) >= :data:`B_APP_VALIDITY` (there it reached 5.8e7 kg on a
        paper-like record). Works on arrays."""
        out = {n: v for n, v in self.physical(values).items() if n in self.derived_names}
        if "b_app" in self.derived_names:
            b, k_n, c_n = (np.asarray(values[n], dtype=float) for n in ("b", "k_n", "c_n"))
            defined = k_n / (2.0 * math.pi * self.drive.hz * c_n) < B_APP_VALIDITY
            out["b_app"] = np.where(defined, apparent_inertance(b, k_n, c_n), np.nan)
            if out["b_app"].ndim == 0:
                out["b_app"] = float(out["b_app"])
        return out

    def values(self, theta) -> dict:
        """Sampled and derived parameter values at theta, by name; a derived quantity not
        defined there (``b_app``, see :meth:`derived`) is left out."""
        vals = dict(zip(self.names, map(float, self.to_values(theta))))
        vals.update(self.physical(vals))
        vals.update({n: v for n, v in self.derived(vals).items() if math.isfinite(v)})
        return vals

    def parameters(self, theta) -> InerterParameters:
        """The network's parameters at theta (the effects apart: :meth:`effects`)."""
        vals = dict(zip(self.names, map(float, self.to_values(theta))))
        phys = {n: v for n, v in self.physical(vals).items() if n in FIELDS}
        return InerterParameters(**{**self.fixed, **phys})

    def effects(self, theta) -> dict:
        """The richer models' effects at theta (``effects.EFFECTS``; empty for the others)."""
        vals = dict(zip(self.names, map(float, self.to_values(theta))))
        return {n: vals[n] for n in self.effect_names}

    def to_theta(self, params: InerterParameters, sigma: float, rho: float = 0.0,
                 effects: dict | None = None) -> np.ndarray:
        """theta at ``params`` and noise (``effects``: the richer models' effects, by
        default ``effects.NO_EFFECT``'s)."""
        phys = {n: getattr(params, n) for n in self.free if n in FIELDS}
        phys.update({n: {**NO_EFFECT, **(effects or {})}[n] for n in self.effect_names})
        vals = self.sampled_from_physical({**phys, "sigma": sigma, "rho": rho})
        theta = [math.log(vals[n]) if lg else vals[n] for n, lg in zip(self.names, self._log)]
        return np.array(theta, dtype=float)

    # -- densities -------------------------------------------------------------------
    def log_prior(self, theta) -> float:
        lp = 0.0
        for name, t in zip(self.names, theta):
            lp += self.all_priors[name].logpdf(t)
        return lp

    def field_vector(self, theta) -> np.ndarray:
        """The network's parameters at theta as a vector in ``models.FIELDS`` order (what
        :meth:`parameters` gives, without the dataclass); ValueError where one is not
        finite or out of its range."""
        v = self.to_values(theta)
        out = self._fixed_vector.copy()
        dst, src = self._direct
        out[dst] = v[src]
        if self._split_at is not None:
            f0, f_share, c, c_share = (float(v[i]) for i in self._split_at)
            out[_F1], out[_F2] = f0 * f_share, f0 * (1.0 - f_share)
            out[_C1], out[_C2] = c * c_share, c * (1.0 - c_share)
        if not (np.all(np.isfinite(out)) and np.all(out[self._positive] > 0) and np.all(out >= 0)):
            raise ValueError(f"parameters out of range at theta {np.asarray(theta).tolist()}")
        return out

    def simulate_raw(self, theta) -> np.ndarray:
        """Simulated acceleration over the whole record (before the low-pass), sampled as
        the likelihood says. With the network's :class:`~bayes_inerter.models.LinearChain`
        the arrays come straight from :meth:`field_vector` and the exact kernel runs on
        them (``simulate.run_exact``): the same simulation as ``simulate()``, without
        building and compiling a network at every evaluation (about a quarter of a 10 s
        record's evaluation before)."""
        lk = self.likelihood
        if self.effect_names:
            net = effect_network(self.network, self.parameters(theta), self.effects(theta))
            return simulate_network(net, self._drive, sampling=lk.sampling)
        if self._chain is None:
            return simulate(self.parameters(theta), self._drive, network=self.network, sampling=lk.sampling)
        masses, link_c, link_k, viscous, bounds = self._chain.arrays(self.field_vector(theta))
        A, B = chain_state_space(masses, link_c, link_k, viscous)
        a, _ = run_exact(A, B, *contacts(bounds, masses), self._force, self._drive.h, sampling=lk.sampling)
        return a

    def simulate_unfiltered(self, theta) -> np.ndarray:
        """Simulated acceleration at the record's samples, before the low-pass (back at
        the record's rate when the likelihood upsamples the force)."""
        a = self.simulate_raw(theta)
        q = self.likelihood.upsample
        if q > 1:
            a = signal.resample_poly(a, 1, q)[: len(self.record.time)]
        return a

    def simulate_lp(self, theta) -> np.ndarray:
        """Low-passed simulated acceleration over the whole record."""
        return lowpass(self.simulate_unfiltered(theta), self.fs, self.likelihood.cutoff)

    def phi(self, sim_lp: np.ndarray) -> float:
        w = self.window
        return 1.0 - float(np.linalg.norm(sim_lp[w] - self.measured_lp[w])) / self._phi_norm

    def pointwise_loglik(self, residual: np.ndarray, sigma: float, rho: float = 0.0) -> np.ndarray:
        """Log-likelihood of each kept residual (AR(1): conditional on the one before)."""
        if self.likelihood.residual == "iid" or rho == 0.0:
            var0 = sigma * sigma
            innov = residual
            out = -0.5 * (innov * innov / var0 + math.log(2 * math.pi * var0))
            return out
        out = np.empty_like(residual)
        var = sigma * sigma
        var0 = var / (1 - rho * rho)
        out[0] = -0.5 * (residual[0] ** 2 / var0 + math.log(2 * math.pi * var0))
        innov = residual[1:] - rho * residual[:-1]
        out[1:] = -0.5 * (innov * innov / var + math.log(2 * math.pi * var))
        return out

    def noise(self, theta) -> tuple[float, float]:
        sigma = math.exp(theta[self.n_phys])
        rho = float(theta[-1]) if self.likelihood.residual == "ar1" else 0.0
        return sigma, rho

    def _simulation(self, theta):
        """:meth:`simulate_lp` at theta, or None where the simulation fails or the
        parameters are out of range."""
        try:
            return self.simulate_lp(theta)
        except (SimulationError, ValueError):
            return None

    def evaluate(self, theta):
        """(log prior, pointwise log-likelihood, low-passed simulation) at theta."""
        lp = self.log_prior(theta)
        if not math.isfinite(lp):
            return lp, None, None
        sim = self._simulation(theta)
        if sim is None or not np.all(np.isfinite(sim)):
            return -math.inf, None, None
        sigma, rho = self.noise(theta)
        ll = self.pointwise_loglik(sim[self.grid] - self.observed, sigma, rho)
        return lp, ll, sim

    def misfit(self, theta):
        """(residual on the likelihood's grid, phi) of the simulation at theta; None where
        it fails or is not finite. What :meth:`log_prob` and the joint model need, in one
        compiled pass over the simulation (phi's norm summed in order, not by BLAS)."""
        sim = self._simulation(theta)
        if sim is None:
            return None
        w = self.window
        r, sq, ok = _misfit(sim, self.grid, self.observed, int(w[0]), int(w[-1]) + 1, self.measured_lp)
        if not ok:
            return None
        return r, 1.0 - math.sqrt(sq) / self._phi_norm

    def log_prob(self, theta):
        """(log posterior, phi) at theta."""
        theta = np.asarray(theta, dtype=float)
        lp = self.log_prior(theta)
        if not math.isfinite(lp):
            return -math.inf, math.nan
        got = self.misfit(theta)
        if got is None:
            return -math.inf, math.nan
        r, phi = got
        sigma, rho = self.noise(theta)
        total = lp + float(self.pointwise_loglik(r, sigma, rho).sum())
        if not math.isfinite(total):
            return -math.inf, math.nan
        return total, phi

    def replace(self, **changes) -> PosteriorModel:
        return dataclasses.replace(self, **changes)
