"""Simulate a network driven by a sampled force record.

:func:`simulate` is the public entry point for the paper's networks;
:func:`simulate_network` takes any :class:`~bayes_inerter.network.Network`.

Two methods, chosen by ``method="auto"``:

- ``"exact"`` (event-driven kernel, ``_kernel/``): for networks whose friction laws are
  piecewise linear in the speed (set-valued sign, true stick-slip): Coulomb plus viscous,
  Stribeck in its piecewise-linear form (``Stribeck.piecewise``, ``STRIBECK_SEGMENTS``
  pieces), ``PiecewiseLinear``; and links with backlash as plain dead zones (see
  ``_piecewise``). Exact for the linear part at any stiffness, switch instants located
  to h / 2^20. Fast: with Coulomb laws and no backlash, this is the likelihood's
  simulator.
- ``"stiff"`` (``_stiff.py``, scipy's Radau): any friction law (Stribeck as it is, the
  smooth law) and backlash with its damper ramped in; set-valued signs are regularised
  as tanh(v / v_eps). Slower by orders of magnitude: for reference checks.

Between samples the force is interpolated linearly. The output is the acceleration of
the driven terminal, sampled in one of two ways (``sampling``):

- ``"instant"`` (default): its value just after each sample instant;
- ``"mean"``: its mean over the two intervals around each sample instant, the central
  difference of the (exact) velocity, (v[k+1] - v[k-1]) / 2h (one-sided at the ends).

Every Coulomb switch makes the acceleration jump (the plate's 732 N over 57 kg: about
13 m/s^2), so an instantaneous sample changes by that much when a switch moves across a
sample instant: the sampled output is then a discontinuous function of the parameters,
and a likelihood built on it is rough (measured on a generated A1 record: log-likelihood
steps of tens of nats for 0.05 % changes of the Coulomb force). The mean is continuous
in the parameters (the velocity is), is what an anti-aliased sensor sees rather than a
point value, and costs nothing more; its gain at 30 Hz is sinc(2 f h) = 0.996 at 1 kHz.
The likelihood uses it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from . import _kernel, _piecewise, _stiff
from ._stiff import run_stiff
from ..device import InerterParameters, validate_parameters
from ..networks import build_network
from ..network import CompiledNetwork, Network, compile_network

__all__ = [
    "simulate",
    "simulate_network",
    "check_record",
    "Drive",
    "run_piecewise_linear",
    "exact_applies",
    "run_stiff",
    "run_exact",
    "exact_runner",
    "piecewise_runner",
    "contacts",
    "SimulationError",
    "MAX_EVENTS_PER_STEP",
    "UNIFORM_RTOL",
    "SAMPLINGS",
]

#: Ways of sampling the output acceleration (see module docstring).
SAMPLINGS = ("instant", "mean")

#: Switches allowed within one sample interval before the exact kernel gives up.
MAX_EVENTS_PER_STEP = 200
#: Largest relative deviation of a sample interval from the mean one.
UNIFORM_RTOL = 1e-4


class SimulationError(RuntimeError):
    """The simulation could not be completed (for example, endless switching)."""


def check_record(time, *signals, names=("force",)) -> tuple[np.ndarray, tuple, float]:
    """Validate a uniformly sampled record; return (time, signals, sample interval h).

    Raises ValueError naming the problem: not one-dimensional, lengths that differ, fewer
    than two samples, NaN or infinite values, time not strictly increasing or not
    uniform (beyond ``UNIFORM_RTOL``).
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"time must be a one-dimensional array, got shape {t.shape}")
    if t.size < 2:
        raise ValueError(f"a record needs at least 2 samples, got {t.size}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"time has a NaN or infinite value at index {_first_bad(t)}")
    out = []
    for name, sig in zip(names, signals):
        x = np.asarray(sig, dtype=float)
        if x.shape != t.shape:
            raise ValueError(f"{name} has shape {x.shape} but time has shape {t.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{name} has a NaN or infinite value at index {_first_bad(x)}")
        out.append(x)
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise ValueError(f"time must be strictly increasing; it is not at index {i + 1}")
    h = (t[-1] - t[0]) / (t.size - 1)
    dev = np.max(np.abs(dt - h)) / h
    if dev > UNIFORM_RTOL:
        i = int(np.argmax(np.abs(dt - h)))
        raise ValueError(
            f"time must be uniformly sampled; interval {i + 1} is {dt[i]:.6g} s against a "
            f"mean of {h:.6g} s (relative deviation {dev:.2g} > {UNIFORM_RTOL:g})"
        )
    return t, tuple(out), float(h)


@dataclass(frozen=True)
class Drive:
    """A force record checked once (:func:`check_record`): time (s), force (N) and the
    sample interval h (s). A likelihood simulates one record for many parameter sets;
    given to :func:`simulate` or :func:`simulate_network` in place of time and force, it
    spares re-checking the arrays at every call (about 7 % of a 10 s record's
    log-probability evaluation). Make one with :meth:`of`."""

    time: np.ndarray
    force: np.ndarray
    h: float

    @classmethod
    def of(cls, time, force) -> "Drive":
        t, (f,), h = check_record(time, force)
        return cls(t, f, h)


def _drive(time, force) -> Drive:
    if isinstance(time, Drive):
        if force is not None:
            raise ValueError("give either a Drive or time and force, not both")
        return time
    if force is None:
        raise ValueError("the force record is missing")
    return Drive.of(time, force)


def _first_bad(x: np.ndarray) -> int:
    return int(np.argmax(~np.isfinite(x)))


def _check_sampling(sampling: str) -> None:
    if sampling not in SAMPLINGS:
        raise ValueError(f"unknown sampling {sampling!r}; choose one of {', '.join(SAMPLINGS)}")


def mean_acceleration(vel: np.ndarray, h: float) -> np.ndarray:
    """Mean acceleration over [t_k - h, t_k + h] from velocity samples (central
    differences; one-sided over one interval at the ends): ``np.gradient(vel, h)``'s
    arithmetic, without its general-purpose overhead."""
    v = np.asarray(vel, dtype=float)
    if v.ndim != 1 or v.size < 2:
        return np.gradient(v, h)  # its result or its error for what is not a 1-D series
    return _mean_acceleration(np.ascontiguousarray(v), float(h))


@njit(cache=True)
def _mean_acceleration(v, h):
    out = np.empty_like(v)
    two_h = 2.0 * h
    for k in range(1, v.shape[0] - 1):
        out[k] = (v[k + 1] - v[k - 1]) / two_h
    out[0] = (v[1] - v[0]) / h
    out[-1] = (v[-1] - v[-2]) / h
    return out


def _contacts(compiled: CompiledNetwork):
    return contacts(compiled.coulomb_bounds, compiled.masses)


def contacts(bounds, masses):
    """The exact kernel's contacts from per-node Coulomb bounds (N) and masses (kg): their
    nodes (those with a bound), bounds and masses."""
    nodes = np.flatnonzero(bounds > 0).astype(np.int64)
    return nodes, bounds[nodes].astype(float), masses[nodes].astype(float)


def run_piecewise_linear(
    compiled: CompiledNetwork,
    A: np.ndarray,
    B: np.ndarray,
    inputs: np.ndarray,
    h: float,
    *,
    x0: np.ndarray | None = None,
    store: bool = False,
    max_events: int = MAX_EVENTS_PER_STEP,
    sampling: str = "instant",
):
    """Run the exact kernel on x' = A x + B u(t) plus the network's contacts and dead zones.

    ``A`` (n, n) and ``B`` (n, n_in) must include the viscous parts and every link closed;
    ``inputs`` (K, n_in) are interpolated linearly. Returns (acceleration of node 0,
    sampled as ``sampling`` says, and the states (K, n) or an empty array).
    """
    _check_sampling(sampling)
    if compiled.all_coulomb:
        nodes, f0, mass = _contacts(compiled)
        return run_exact(A, B, nodes, f0, mass, inputs, h, x0=x0, store=store, max_events=max_events,
                         sampling=sampling)
    return piecewise_runner(compiled, A, B, h, max_events=max_events, sampling=sampling)(inputs, x0=x0, store=store)


def exact_applies(compiled: CompiledNetwork) -> bool:
    """Whether :func:`run_piecewise_linear` runs ``compiled``: every friction law Coulomb
    or piecewise linear (Stribeck, dead zones). Where not, :func:`run_stiff` does (Radau
    on the regularised laws)."""
    return compiled.all_coulomb or _piecewise.applies(compiled)


def run_exact(A, B, nodes, f0, mass, inputs, h, *, x0=None, store=False, max_events=MAX_EVENTS_PER_STEP,
              sampling="instant"):
    """:func:`run_piecewise_linear` given the contacts as arrays: their ``nodes`` (int),
    Coulomb bounds ``f0`` (N, > 0) and node masses (kg). The likelihood's entry point,
    which forms these without building a network (``networks.linear_chain``)."""
    return exact_runner(A, B, nodes, f0, mass, h, max_events=max_events, sampling=sampling)(inputs, x0=x0, store=store)


def exact_runner(A, B, nodes, f0, mass, h, *, max_events=MAX_EVENTS_PER_STEP, sampling="instant"):
    """:func:`run_exact` with everything but the inputs fixed: a callable
    ``run(inputs, x0=None, store=False)`` returning what :func:`run_exact` returns. The
    augmented matrix and the kernel are formed once, so a caller that simulates the same
    network piece by piece (a period at a time, each from the last one's end state) pays
    for them once."""
    n = A.shape[0]
    B = np.ascontiguousarray(B, dtype=float).reshape(n, -1)
    n_in = B.shape[1]
    nodes = np.asarray(nodes, dtype=np.int64)
    mass = np.asarray(mass, dtype=float)
    Abar = _piecewise.augmented(np.ascontiguousarray(A, dtype=float), B, nodes, mass)
    kernel = _kernel.kernel_for(n, n_in, nodes, 0, (Abar != 0).tobytes())
    h, max_events = float(h), int(max_events)

    def run(inputs, x0=None, store=False):
        out = kernel(Abar, n, n_in, nodes, f0, mass, _inputs(inputs, n_in), h, _initial(x0, n), 0, store, max_events)
        return _outputs(out, h, max_events, sampling)

    return run


def piecewise_runner(compiled: CompiledNetwork, A, B, h, *, max_events=MAX_EVENTS_PER_STEP, sampling="instant"):
    """:func:`run_piecewise_linear` with everything but the inputs fixed, as
    :func:`exact_runner` is :func:`run_exact`'s: a callable ``run(inputs, x0=None,
    store=False)``. The network's arrays and its kernel are formed once. ``A`` (n, n) may
    carry states beyond the network's own (after its 2 N - 1), driven through ``B``."""
    _check_sampling(sampling)
    if not exact_applies(compiled):
        raise ValueError("the exact kernel needs Coulomb laws or other piecewise-linear ones (Stribeck, "
                         "PiecewiseLinear); the smooth law runs on method='stiff'")
    shape, net = _piecewise.network_arrays(compiled, np.asarray(A, dtype=float), B, float(h))
    kernel = _kernel.rich_kernel_for(shape)
    max_events = int(max_events)

    def run(inputs, x0=None, store=False):
        out = kernel(net, _inputs(inputs, shape.n_in), _initial(x0, shape.n), store, max_events)
        return _outputs(out, h, max_events, sampling)

    return run


def _initial(x0, n):
    z0 = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float)
    if z0.shape != (n,):
        raise ValueError(f"initial state must have shape ({n},), got {z0.shape}")
    return z0


def _inputs(inputs, n_in):
    return np.ascontiguousarray(inputs, dtype=float).reshape(-1, n_in)


def _outputs(out, h, max_events, sampling):
    """(accel, states) from a kernel's results, or SimulationError where it gave up."""
    accel, vel, states, status, _ = out
    if status != _kernel.STATUS_OK:
        raise SimulationError(
            f"more than {max_events} friction switches within one sample interval; "
            "the record or the parameters make the contacts chatter"
        )
    if sampling == "mean":
        accel = mean_acceleration(vel, h)
    return accel, states


def simulate_network(
    network: Network | CompiledNetwork,
    time,
    force=None,
    *,
    method: str = "auto",
    x0=None,
    v_eps: float = _stiff.V_EPS,
    rtol: float = _stiff.RTOL,
    sampling: str = "instant",
) -> np.ndarray:
    """Acceleration (m/s^2) of the driven terminal of ``network`` under ``force`` (N).

    Parameters
    ----------
    network : a network of blocks, or its compiled form.
    time, force : shape (K,), s and N; uniformly sampled, linearly interpolated; or a
        :class:`Drive` as ``time`` (and no force).
    method : "auto", "exact" or "stiff" (see module docstring).
    x0 : initial state (see ``network.compile``); default at rest.
    v_eps, rtol : regularisation width (m/s) and relative tolerance of the stiff method.
    sampling : "instant" (default) or "mean" (see module docstring).
    """
    _check_sampling(sampling)
    drive = _drive(time, force)
    t, f, h = drive.time, drive.force, drive.h
    compiled = network if isinstance(network, CompiledNetwork) else compile_network(network)
    if method == "auto":
        method = "exact" if compiled.all_coulomb or _piecewise.applies(compiled) else "stiff"
    if method == "exact":
        A, B = compiled.state_space(viscous=True)
        accel, _ = run_piecewise_linear(compiled, A, B, f, h, x0=x0, sampling=sampling)
        return accel
    if method == "stiff":
        accel, states = _stiff.simulate_stiff(compiled, t, f, x0=x0, v_eps=v_eps, rtol=rtol)
        return mean_acceleration(states[:, 0], h) if sampling == "mean" else accel
    raise ValueError(f"unknown method {method!r}; choose auto, exact or stiff")


def simulate(
    params: InerterParameters,
    time,
    force=None,
    *,
    network: str = "reduced",
    friction="coulomb",
    method: str = "auto",
    x0=None,
    **options,
) -> np.ndarray:
    """Acceleration (m/s^2) of terminal 1 of the inerter under the force record (N).

    Parameters
    ----------
    params : the network's parameters (``paper_parameters(setting)`` or a variant).
    time, force : shape (K,), s and N; uniformly sampled, linearly interpolated between
        samples; or a :class:`Drive` as ``time`` (and no force).
    network : "reduced" (Fig. 5, default), "full" (Fig. 4), "linear" or "rigid".
    friction : "coulomb" (eq. 3, set-valued sign; default), "stribeck" or "smooth", or a
        callable mapping (Coulomb N, viscous N s/m) to a friction law.
    method : "auto" (exact kernel when it applies: every law but the smooth one), "exact"
        or "stiff".
    x0 : initial state; default at rest.
    options : passed to the network builder (``theta``, ``nut_share`` for "full"), to
        the stiff method (``v_eps``, ``rtol``), or ``sampling`` ("instant" or "mean",
        see module docstring).

    Returns
    -------
    accel : shape (K,), m/s^2, just after each sample instant (or its mean around it).
    """
    if not isinstance(params, InerterParameters):
        raise ValueError(f"params must be InerterParameters, got {type(params).__name__}")
    validate_parameters(params)
    solver_opts = {k: options.pop(k) for k in ("v_eps", "rtol", "sampling") if k in options}
    net = build_network(network, params, friction, **options)
    return simulate_network(net, time, force, method=method, x0=x0, **solver_opts)
