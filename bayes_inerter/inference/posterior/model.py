"""The statistical model: parameters, priors, and the likelihood of one record.

``PosteriorModel`` is the log posterior of one record under one of the likelihoods of
``likelihood.RESIDUALS`` (``LikelihoodSettings.residual``):

- ``"motion"`` (the default): motion in, force out, at the drive's harmonics
  (:mod:`.motion`, whose docstring derives it);
- ``"harmonic"``: the same harmonics the paper's way round, the model driven by the
  measured force (:mod:`.harmonic`);
- ``"ar1"`` and ``"iid"``: the time-domain residuals. The record's acceleration is
  compared with the simulated one (driven by the record's force) through the same
  zero-phase low-pass (``records.lowpass``), on a grid thinned to every ``stride``-th
  sample inside the record less ``edge`` seconds at each end; the residual is a
  stationary AR(1) process, r_t = rho r_{t-1} + e_t, e_t ~ N(0, sigma^2), with sigma
  and rho unknown, or independent N(0, sigma^2) (MODEL.md section 7 measured it
  overconfident).

Parameters are sampled as theta = log(value) (see ``priors``), the likelihood's
hyper-parameters with them. The fit accuracy phi is a derived quantity of every
evaluation (for the time-domain residuals eq. 5 on the low-passed signals inside the
window; for the harmonic ones the force's at the harmonics, see :mod:`.motion`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy import signal

from ...device import TABLE_I, InerterParameters, apparent_inertance
from ...networks import FIELDS, linear_chain
from ...network.compile import chain_state_space
from ...records.conditioning import lowpass
from ...masses import resolve_masses
from ...records.drive import resolve_drive, with_drive
from ...records.record import Record
from ...simulate import Drive, SimulationError, check_record, contacts, run_exact, simulate_network
from .effects import EFFECT_PRIORS, EFFECTS, NO_EFFECT, effect_network
from . import friction_law
from .harmonic import harmonic_data, harmonic_loglik, harmonic_variance, linear_transfer
from .likelihood import LikelihoodSettings, ar1_marginal, ar1_pointwise
from .motion import (fundamental_misfit, input_noise_shapes, input_noise_variance, motion_data, motion_loglik,
                     motion_variance, with_input_noise, with_input_shapes, form_shape, form_columns)
from .parameters import FRICTION_PAIRS, ParameterMap
from .priors import (DEFAULT_PRIORS, DISCREPANCY_PRIORS, MODAL_PRIORS, MOTION_DISCREPANCY_PRIORS, NOISE_PRIORS,
                     SPLIT_PRIORS, TRUNCATIONS, delay_prior, gain_prior)

__all__ = ["MODELS", "MOTION_MODELS", "LikelihoodSettings", "PosteriorModel", "record_masses", "refusal"]

PHYSICAL = ("b", "f1_0", "c_f1", "f2_0", "c_f2", "c_n", "k_n", "c_B", "k_B")


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
#: The models the motion-in likelihood knows: the two-port network, its limits and the
#: richer models (their plate's Stribeck friction a function of the measured motion,
#: the rotation's and the nut's dead zone in the simulated drivetrain, ``motion``).
MOTION_MODELS = ("two-port", "rigid", "linear", *EFFECTS)


def refusal(model: str, likelihood: LikelihoodSettings) -> str | None:
    """Why ``model`` cannot be fitted under ``likelihood`` (None: it can)."""
    if model not in MODELS:
        return f"unknown model {model!r}; choose one of {', '.join(MODELS)}"
    if likelihood.residual == "motion" and model not in MOTION_MODELS:
        return (f"the motion-in likelihood does not know the {model} model; "
                f"fit it with --residual harmonic or ar1")
    return None


#: The motion-in likelihood's algebra (``motion``) is the two-port network's; the nested
#: networks are its limits: the rigid body's links stiff and damped beyond any drive
#: (1e12 N s/m, 1e14 N/m; the rotation's friction is already off), the linear network's
#: friction blocks bypassed.
MOTION_LIMITS = {
    "rigid": {"c_n": 1e12, "k_n": 1e14, "c_B": 1e12, "k_B": 1e14},
    "linear": {"f1_0": 0.0, "c_f1": 0.0, "f2_0": 0.0, "c_f2": 0.0},
}

#: The harmonic likelihood's parameters where :meth:`PosteriorModel.to_theta` is not
#: told them: a discrepancy of 0.01 (m/s^2 for the force-in likelihood, N for motion in,
#: inside both priors) decaying as 1/k, and equal gains.
HYPER_START = {"tau": 1e-2, "alpha": 1.0, "gain": 1.0, "delay": 0.0, "law": friction_law.SD}

#: ``b_app`` (the inertance seen through the nut, to first order in k_n / (omega c_n))
#: is reported only where k_n / (omega c_n) is below this: an assumption of this
#: package's reporting, not of the model.
B_APP_VALIDITY = 0.1


def record_masses(record: Record, m_s: float | None = None, m_B: float | None = None) -> tuple[float, float]:
    """m_s and m_B (kg) from the options, else the record's metadata (m_s, or setting),
    else (m_B) the paper's; :func:`...masses.resolve_masses` says where each came from."""
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

    ``modal``: c_B is sampled as the plate mode's damping ratio ``zeta_B`` under a
    physical prior (``parameters.ParameterMap``, ``priors.MODAL_PRIORS``) and reported
    as derived. Default (None): with the harmonic likelihood wherever the bearing's
    damper and spring are free; the time-domain likelihoods keep c_B log-uniform, as
    their published results were made.

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
    modal: bool | None = None
    #: theta at which the motion-in likelihood's normaliser takes the noise
    #: (``LikelihoodSettings.normaliser``; :meth:`with_reference`)
    reference: tuple | None = None

    def __post_init__(self) -> None:
        why = refusal(self.model, self.likelihood)
        if why is not None:
            raise ValueError(why)
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
        self._set_reference()

    def _set_reference(self) -> None:
        self.reference_noise = None
        self.deviation_at = None
        if self.reference is not None and self._takes_reference:
            theta = np.asarray(self.reference, dtype=float)
            if len(theta) != self.ndim:
                raise ValueError(f"the reference has {len(theta)} parameters; the model samples {self.ndim}")
            h, x = self.hyper(theta), self.field_vector(theta)
            draws = self.likelihood.input_noise_draws()
            if draws and self.motion is not None and self.likelihood.input_noise_form == "shapes":
                shapes = input_noise_shapes(self.motion, x, h["gain"], h["delay"], draws=draws,
                                            effects=self.effects(theta))
                self.motion = with_input_shapes(self.motion, shapes)
            elif draws and self.motion is not None:
                extra = input_noise_variance(self.motion, x, h["gain"], h["delay"], draws=draws,
                                             effects=self.effects(theta))
                self.motion = with_input_noise(self.motion, extra)
                self.harmonic = self.motion.harmonic
            if (self.likelihood.form_sd > 0 or self.likelihood.form_friction > 0) and self.motion is not None:
                shape = form_shape(self.motion, x, h["gain"], h["delay"], effects=self.effects(theta))
                self.motion = with_input_shapes(self.motion, form_columns(shape, self.likelihood.form_sd,
                                                                          self.likelihood.form_friction, x))
            if self.likelihood.normaliser == "reference":
                self.reference_noise = motion_variance(self.motion, x, 0.0, 0.0, h["gain"], h["delay"])[0]
            if self.likelihood.deviation_scale == "reference":
                self.deviation_at = x

    def _set_parameters(self) -> None:
        """The sampled parameters (``names``, split or not), their priors, and the derived
        quantities."""
        pairs = set(FRICTION_PAIRS)
        can_split = pairs <= set(self.free)
        if self.split is None:
            self.split = can_split
        if self.split and not can_split:
            raise ValueError(f"the {self.model} model has no friction pair to split")
        can_modal = {"c_B", "k_B"} <= set(self.free)
        if self.modal is None:  # the harmonic configuration's; the time-domain ones' kept as they were
            self.modal = can_modal and self.likelihood.residual in ("harmonic", "motion")
        if self.modal and not can_modal:
            raise ValueError(f"the {self.model} model has no bearing damper to sample as a damping ratio")
        self.map = ParameterMap(split=self.split, modal=self.modal, m_B=self.m_B)
        discrepancy = MOTION_DISCREPANCY_PRIORS if self.likelihood.residual == "motion" else DISCREPANCY_PRIORS
        hyper = {**NOISE_PRIORS, **discrepancy, "gain": gain_prior(self.likelihood.gain_sd or 0.01),
                 "delay": delay_prior(self.likelihood.sampled_delay_sd or 1e-4)}
        known = set(PHYSICAL) | set(SPLIT_PRIORS) | set(MODAL_PRIORS) | set(hyper) | set(EFFECT_PRIORS) | set(TRUNCATIONS)
        unknown = set(self.priors) - known
        if unknown:
            raise ValueError(f"priors given for unknown parameters: {', '.join(sorted(unknown))}")
        self.all_priors = {**DEFAULT_PRIORS, **SPLIT_PRIORS, **MODAL_PRIORS, **hyper, **EFFECT_PRIORS, **self.priors}
        self.effect_names = [n for n in self.free if n in EFFECT_PRIORS]
        sampled = self.map.sampled_names(self.free)
        self.n_phys = len(sampled)
        self.names = sampled + list(self.likelihood.hyper_names)
        self.derived_names = sorted(pairs, key=PHYSICAL.index) if self.split else []
        if self.modal:
            self.derived_names.append("c_B")
        if {"b", "k_n", "c_n"} <= set(self.free):
            self.derived_names.append("b_app")
        self._log = np.array([self.all_priors[n].log_scale for n in self.names])
        self._set_truncations()

    def _set_truncations(self) -> None:
        """The truncations of the prior asked for in ``priors`` (``priors.TRUNCATIONS``):
        (prior, function, positions of its arguments in theta) each."""
        self.truncations = []
        for name in (n for n in self.priors if n in TRUNCATIONS):
            args, fn = TRUNCATIONS[name]
            missing = [a for a in args if a not in self.names]
            if missing:
                raise ValueError(f"the truncation {name} needs {', '.join(missing)} sampled; "
                                 f"the {self.model} model samples {', '.join(self.names)}")
            self.truncations.append((self.priors[name], fn, [self.names.index(a) for a in args]))

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
        self.motion = (motion_data(rec, self.drive.hz, cutoff=lk.cutoff, pool=lk.pool, settle=lk.settle, law=lk.law,
                                  law_orthogonal=lk.law_orthogonal, law_beyond_viscous=lk.law_beyond_viscous,
                                  reversal_scale=lk.reversal_scale, reversals=lk.reversals)
                       if lk.residual == "motion" else None)
        self.harmonic = (self.motion.harmonic if self.motion is not None else
                         harmonic_data(rec, self.drive.hz, cutoff=lk.cutoff, pool=lk.pool, settle=lk.settle)
                         if lk.residual == "harmonic" else None)
        m = self.measured_lp[window]
        self._phi_norm = float(np.linalg.norm(m - m.mean()))

    def _set_simulation(self) -> None:
        """What every evaluation's simulation starts from: the drive (upsampled where
        asked), the fixed parameters, and where the sampled ones go in ``networks.FIELDS``."""
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
        # The paper's networks (Coulomb friction) run from their arrays, formed straight
        # from the parameters (``networks.linear_chain``); the richer models' effects make
        # a network of their own at each evaluation (simulate_raw).
        self._chain = None if self.effect_names else linear_chain(self.network)
        if self._chain is None and not self.effect_names:
            raise ValueError(f"network {self.network!r} has no linear map from the parameters to its arrays")
        if self.motion is not None:
            # the motion-in algebra is the two-port network's: the nested networks are its limits
            fixed.update(MOTION_LIMITS.get(self.network, {}))
        self._fixed_vector = np.array([float(fixed[f]) for f in FIELDS])
        pos = {n: i for i, n in enumerate(self.names)}
        direct = [n for n in self.free if n in pos and n in FIELDS]
        self._direct = (np.array([FIELDS.index(n) for n in direct], dtype=int),
                        np.array([pos[n] for n in direct], dtype=int))
        self._mapped = [n for n in self.names[: self.n_phys] if n not in FIELDS]  # what the map turns into fields
        self._mapped_at = [pos[n] for n in self._mapped]
        self._mapped_fields = [(FIELDS.index(n), n) for n in self.derived_names if n in FIELDS]
        self._needs = [n for n in ("k_B",) if self.modal and n in pos]  # fields the map reads too
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
        """Raw network parameters (the free ones) from sampled values by name
        (``parameters.ParameterMap``)."""
        out = self.map.physical(values)
        return {n: out[n] for n in self.free if n in out}

    def sampled_from_physical(self, phys: dict) -> dict:
        """Sampled quantities (by name) from raw parameters, where they can be formed."""
        out = self.map.sampled(phys)
        return {n: out[n] for n in self.names if n in out}

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

    def to_theta(self, params: InerterParameters, sigma: float = 1e-3, rho: float = 0.0,
                 effects: dict | None = None, hyper: dict | None = None) -> np.ndarray:
        """theta at ``params`` and noise (``effects``: the richer models' effects, by
        default ``effects.NO_EFFECT``'s; ``hyper``: the harmonic likelihood's, by default
        :data:`HYPER_START`'s)."""
        phys = {n: getattr(params, n) for n in self.free if n in FIELDS}
        phys.update({n: {**NO_EFFECT, **(effects or {})}[n] for n in self.effect_names})
        phys.update({**HYPER_START, **(hyper or {})})
        vals = self.sampled_from_physical({**phys, "sigma": sigma, "rho": rho})
        theta = [math.log(vals[n]) if lg else vals[n] for n, lg in zip(self.names, self._log)]
        return np.array(theta, dtype=float)

    # -- densities -------------------------------------------------------------------
    def log_prior(self, theta) -> float:
        """The sampled parameters' priors' log density at theta; -inf outside a
        truncation (``priors.TRUNCATIONS``), which adds nothing inside."""
        lp = 0.0
        for name, t in zip(self.names, theta):
            lp += self.all_priors[name].logpdf(t)
        if self.truncations and math.isfinite(lp):
            values = self.to_values(theta)
            for prior, fn, at in self.truncations:
                q = float(fn(*values[at]))
                x = (math.log(q) if q > 0 else -math.inf) if prior.log_scale else q
                lo, hi = prior.bounds
                if not lo <= x <= hi:
                    return -math.inf
        return lp

    def field_vector(self, theta) -> np.ndarray:
        """The network's parameters at theta as a vector in ``networks.FIELDS`` order (what
        :meth:`parameters` gives, without the dataclass); ValueError where one is not
        finite or out of its range."""
        v = self.to_values(theta)
        out = self._fixed_vector.copy()
        dst, src = self._direct
        out[dst] = v[src]
        if self._mapped:
            given = {n: float(v[i]) for n, i in zip(self._mapped, self._mapped_at)}
            given.update({n: float(out[FIELDS.index(n)]) for n in self._needs})
            phys = self.map.physical(given)
            for i, n in self._mapped_fields:
                out[i] = phys[n]
        if not (np.all(np.isfinite(out)) and np.all(out[self._positive] > 0) and np.all(out >= 0)):
            raise ValueError(f"parameters out of range at theta {np.asarray(theta).tolist()}")
        return out

    def simulate_raw(self, theta) -> np.ndarray:
        """Simulated acceleration over the whole record (before the low-pass), sampled as
        the likelihood says. Two routes, one per kind of model: the paper's networks take
        their arrays straight from :meth:`field_vector` through the network's
        :class:`~bayes_inerter.networks.LinearChain` (compiled once on symbolic
        parameters), and the exact kernel runs on them (``simulate.run_exact``: the same
        simulation as ``simulate()``, bit for bit, without a network built at every
        evaluation); the richer models build their effects' network
        (``networks.device_network``) and run it (``simulate.simulate_network``)."""
        lk = self.likelihood
        if self.effect_names:
            net = effect_network(self.network, self.parameters(theta), self.effects(theta))
            return simulate_network(net, self._drive, sampling=lk.sampling)
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
        return ar1_pointwise(residual, sigma, 0.0 if self.likelihood.residual == "iid" else rho)

    def noise(self, theta) -> tuple[float, float]:
        """(sigma, rho) of the time-domain residual at theta."""
        sigma = math.exp(theta[self.n_phys])
        rho = float(theta[-1]) if self.likelihood.residual == "ar1" else 0.0
        return sigma, rho

    def hyper(self, theta) -> dict:
        """The likelihood's own parameters at theta (``LikelihoodSettings.hyper_names``),
        in their units, by name; ``gain`` 1, ``alpha`` and ``delay`` 0 where they are not
        sampled."""
        vals = dict(zip(self.names[self.n_phys:], map(float, self.to_values(theta)[self.n_phys:])))
        if self.harmonic is not None:
            vals.setdefault("gain", 1.0)
            vals.setdefault("alpha", 0.0)
            vals.setdefault("delay", 0.0)
        return vals

    def motion_terms(self, theta):
        """(each harmonic's term, phi of the force) of the motion-in likelihood
        (``motion.motion_loglik``) at theta; None where the parameters are out of range or
        the drivetrain's simulation fails."""
        try:
            x = self.field_vector(theta)
            h = self.hyper(theta)
            terms, phi = motion_loglik(self.motion, x, h["tau"], h["alpha"], h["gain"], pointwise=True,
                                       reference=self.reference_noise, delay=h["delay"],
                                       deviation_at=self.deviation_at, law=h.get("law"), effects=self.effects(theta))
        except (SimulationError, ValueError):
            return None
        return (terms, phi) if np.all(np.isfinite(terms)) else None

    def fundamental_misfit(self, theta) -> float:
        """The motion-in fit's in-phase residual at the fundamental, as a share of the
        model's inertial force there, after what the marginalised deviations explain
        (``motion.fundamental_misfit``)."""
        h = self.hyper(theta)
        return fundamental_misfit(self.motion, self.field_vector(theta), h["gain"], h["tau"], h["alpha"], h["delay"],
                                  deviation_at=self.deviation_at, law=h.get("law"), effects=self.effects(theta))

    def accel_error_variance(self, theta) -> np.ndarray:
        """The variance of each harmonic's error as the likelihood sees it (noise and
        discrepancy), in m/s^2 (the motion-in likelihood's force error through the
        model's transfer), for predictive bands."""
        if self.motion is None:
            return self.harmonic_variance(theta)
        h = self.hyper(theta)
        V, Y = motion_variance(self.motion, self.field_vector(theta), h["tau"], h["alpha"], h["gain"], h["delay"])
        return V / np.abs(Y) ** 2

    def transfer(self, theta) -> np.ndarray:
        """The model's force-to-acceleration transfer at the harmonic likelihood's
        harmonics, the network linearised with its Coulomb forces out
        (``harmonic.linear_transfer``; for the richer models, their two-port part's)."""
        masses, link_c, link_k, viscous, _ = linear_chain(self.network).arrays(self.field_vector(theta))
        A, B = chain_state_space(masses, link_c, link_k, viscous)
        return linear_transfer(A, B, self.harmonic.omega)

    def harmonic_terms(self, theta, sim_raw: np.ndarray) -> float:
        """The harmonic log-likelihood at theta of the unfiltered simulation ``sim_raw``."""
        return float(self.harmonic_pointwise(theta, sim_raw).sum())

    def harmonic_pointwise(self, theta, sim_raw: np.ndarray) -> np.ndarray:
        """Each harmonic's term of the harmonic log-likelihood (``harmonic.harmonic_loglik``)."""
        h = self.hyper(theta)
        return harmonic_loglik(self.harmonic, sim_raw, self.transfer(theta), h["tau"], h["alpha"], h["gain"],
                               pointwise=True)

    def harmonic_variance(self, theta) -> np.ndarray:
        """V_k at theta: the variance of each harmonic's residual (noise and discrepancy)."""
        h = self.hyper(theta)
        return harmonic_variance(self.harmonic, self.transfer(theta), h["tau"], h["alpha"], h["gain"])

    def _raw_simulation(self, theta):
        """:meth:`simulate_unfiltered` at theta, or None where the simulation fails, the
        parameters are out of range or the result is not finite."""
        try:
            raw = self.simulate_unfiltered(theta)
        except (SimulationError, ValueError):
            return None
        return raw if np.all(np.isfinite(raw)) else None

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
        if self.motion is not None:
            got, sim = self.motion_terms(theta), self._simulation(theta)
            if got is None or sim is None or not np.all(np.isfinite(sim)):
                return -math.inf, None, None
            return lp, got[0], sim
        if self.harmonic is not None:
            raw = self._raw_simulation(theta)
            if raw is None:
                return -math.inf, None, None
            return lp, self.harmonic_pointwise(theta, raw), lowpass(raw, self.fs, self.likelihood.cutoff)
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

    def log_likelihood(self, theta, *, marginal_scale: bool = False):
        """(log-likelihood, phi) at theta, or None where the simulation fails or is not
        finite: the one interface the single-record and the joint model share.
        ``marginal_scale``: the time-domain residual's scale sigma marginalised under
        p(sigma) ~ 1/sigma (``likelihood.ar1_marginal``; what the joint model uses, its
        sigma entry then ignored); the harmonic likelihoods have no such scale. The
        motion-in likelihood's phi is the force's at the harmonics (``motion``)."""
        if self.motion is not None:
            got = self.motion_terms(theta)
            return None if got is None else (float(got[0].sum()), got[1])
        if self.harmonic is not None:
            raw = self._raw_simulation(theta)
            if raw is None:
                return None
            return self.harmonic_terms(theta, raw), self.phi(lowpass(raw, self.fs, self.likelihood.cutoff))
        got = self.misfit(theta)
        if got is None:
            return None
        r, phi = got
        sigma, rho = self.noise(theta)
        if marginal_scale:
            return ar1_marginal(r, rho), phi
        return float(self.pointwise_loglik(r, sigma, rho).sum()), phi

    def log_prob(self, theta):
        """(log posterior, phi) at theta."""
        theta = np.asarray(theta, dtype=float)
        lp = self.log_prior(theta)
        if not math.isfinite(lp):
            return -math.inf, math.nan
        got = self.log_likelihood(theta)
        if got is None:
            return -math.inf, math.nan
        total = lp + got[0]
        if not math.isfinite(total):
            return -math.inf, math.nan
        return total, got[1]

    def replace(self, **changes) -> PosteriorModel:
        return dataclasses.replace(self, **changes)

    @property
    def needs_reference(self) -> bool:
        """True where the likelihood waits for a reference point (:meth:`with_reference`):
        the motion-in likelihood with ``normaliser="reference"`` or
        ``deviation_scale="reference"``."""
        return self._takes_reference and self.reference is None

    @property
    def _takes_reference(self) -> bool:
        lk = self.likelihood
        return self.motion is not None and (lk.normaliser == "reference" or lk.deviation_scale == "reference")

    def with_reference(self, theta) -> PosteriorModel:
        """This model with the normaliser's noise, and the deviations' prior sd, taken at
        ``theta`` where its likelihood settings ask (``motion``'s module docstring); the
        model itself where they ask neither."""
        if not self._takes_reference:
            return self
        return self.replace(reference=tuple(float(v) for v in np.asarray(theta, dtype=float)))
