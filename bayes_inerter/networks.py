"""The paper's networks, built from an :class:`InerterParameters` set.

- ``reduced`` (the paper's Fig. 5 / 6, default): plate m_B with friction f1, bearing
  deformation Q_B, screw translation m_s, nut deformation Q_n cos^2 theta, inertance b with
  rotational friction f2.
- ``full`` (Fig. 4): the reduced network plus the nut friction's sin(theta) component.
- ``linear``: the reduced network with every friction block bypassed (K_f1 = K_f2 = 0).
- ``rigid`` (Song et al.): one body m_B + m_s + b with the two frictions, no deformations.

Each builder takes the parameters and a friction law name (or a factory mapping the
paper's (Coulomb, viscous) pair to a law) and returns a :class:`Network`. A new
arrangement needs only a new builder: compilation and simulation are generic.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Callable

import numpy as np
from numba import njit

from .device import DEFAULT_GEOMETRY, InerterParameters
from .friction import STRIBECK_RATIO, STRIBECK_VELOCITY, FrictionLaw, make_law
from .network import Backlash, Deformation, Friction, Inerter, Mass, Network, cascade, compile_network
from .network.symbolic import SymbolicCoulomb, coefficients, symbols

__all__ = ["NETWORKS", "build_network", "with_backlash", "device_network", "lead_angle", "NUT_SHARE", "FIELDS", "LinearChain", "linear_chain"]

#: The parameters in :class:`InerterParameters`' order (the vectors of :class:`LinearChain`).
FIELDS = tuple(f.name for f in dataclasses.fields(InerterParameters))

LawFactory = Callable[[float, float], FrictionLaw]

#: **Assumption** (full network only): share of the rotational Coulomb and viscous
#: friction f2 that comes from the nut (the rest from the bearing), dimensionless.
NUT_SHARE = 1.0


def lead_angle(lead: float | None = None, screw_diameter: float | None = None) -> float:
    """Thread (lead) angle theta of the screw, rad: tan(theta) = lead / (pi d).

    **Assumption**: the paper does not give theta; defaults use the lead and the screw
    diameter implied by the paper's theoretical inertances (``Geometry.from_paper``):
    p = 19.84 mm, d = 49.6 mm, theta = 7.3 degrees.
    """
    lead = DEFAULT_GEOMETRY.lead if lead is None else lead
    d = 2 * DEFAULT_GEOMETRY.screw_radius() if screw_diameter is None else screw_diameter
    return math.atan(lead / (math.pi * d))


def _factory(friction: str | LawFactory) -> LawFactory:
    if callable(friction):
        return friction
    make_law(friction, 1.0, 0.0)  # validates the name
    return lambda f0, c: make_law(friction, f0, c)


def reduced(p: InerterParameters, friction: str | LawFactory = "coulomb") -> Network:
    law = _factory(friction)
    return cascade(
        Mass(p.m_B),
        Friction(law(p.f1_0, p.c_f1)),
        Deformation(p.c_B, p.k_B),
        Mass(p.m_s),
        Deformation(p.c_n, p.k_n),
        Inerter(p.b),
        Friction(law(p.f2_0, p.c_f2)),
        name="reduced",
    )


def full(
    p: InerterParameters,
    friction: str | LawFactory = "coulomb",
    *,
    theta: float | None = None,
    nut_share: float = NUT_SHARE,
) -> Network:
    """Fig. 4: adds the nut friction's sin(theta) part on the screw translation node.

    **Assumptions**: f2 = f_B + f_n cos(theta) with f_n cos(theta) = nut_share * f2, so the
    sin(theta) part is nut_share * tan(theta) times f2 (Coulomb and viscous alike); in the
    ladder it is a shunt at the screw translation node, which moves with the rotation
    coordinate up to the (stiff) nut deformation.
    """
    if not 0 <= nut_share <= 1:
        raise ValueError(f"nut_share must lie in [0, 1], got {nut_share}")
    law = _factory(friction)
    t = math.tan(lead_angle() if theta is None else theta) * nut_share
    return cascade(
        Mass(p.m_B),
        Friction(law(p.f1_0, p.c_f1)),
        Deformation(p.c_B, p.k_B),
        Mass(p.m_s),
        Friction(law(t * p.f2_0, t * p.c_f2)),
        Deformation(p.c_n, p.k_n),
        Inerter(p.b),
        Friction(law(p.f2_0, p.c_f2)),
        name="full",
    )


def linear(p: InerterParameters, friction: str | LawFactory = "coulomb") -> Network:
    """The paper's linear model: every friction block bypassed (K_f1 = K_f2 = 0)."""
    return cascade(
        Mass(p.m_B),
        Deformation(p.c_B, p.k_B),
        Mass(p.m_s),
        Deformation(p.c_n, p.k_n),
        Inerter(p.b),
        name="linear",
    )


def rigid(p: InerterParameters, friction: str | LawFactory = "coulomb") -> Network:
    """Song et al.: one rigid body m_B + m_s + b with both frictions acting on it."""
    law = _factory(friction)
    return cascade(
        Mass(p.m_B),
        Friction(law(p.f1_0, p.c_f1)),
        Mass(p.m_s),
        Inerter(p.b),
        Friction(law(p.f2_0, p.c_f2)),
        name="rigid",
    )


NETWORKS = {"reduced": reduced, "full": full, "linear": linear, "rigid": rigid}


def build_network(name: str, params: InerterParameters, friction="coulomb", **options) -> Network:
    """The network called ``name`` (reduced, full, linear, rigid) for ``params``."""
    try:
        builder = NETWORKS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown network {name!r}; choose one of {', '.join(NETWORKS)}"
        ) from None
    return builder(params, friction, **options)


def with_backlash(net: Network, gap: float) -> Network:
    """``net`` with a dead zone of half-width ``gap`` (m) in its nut link, the last
    deformation of the chain (:class:`.network.Backlash`)."""
    blocks = list(net.blocks)
    j = max(i for i, b in enumerate(blocks) if isinstance(b, Deformation))
    blocks[j] = dataclasses.replace(blocks[j], backlash=Backlash(gap))
    return Network(tuple(blocks), net.name + "+backlash")


def device_network(name: str, params: InerterParameters, friction="coulomb", *,
                   stribeck_ratio: float = STRIBECK_RATIO, stribeck_velocity: float = STRIBECK_VELOCITY,
                   backlash: float = 0.0) -> Network:
    """The network ``name`` at ``params`` with the effects a device may have beyond the
    paper's model: ``friction`` "stribeck" for a Stribeck law on every contact (break-away
    ``stribeck_ratio`` times the Coulomb force, falling over ``stribeck_velocity``, m/s;
    :func:`.friction.make_law`), any other law by name or factory as
    :func:`build_network` takes it, and a dead zone of half-width ``backlash`` (m) in the
    nut link (none at 0). The one place such a device is built: the generator's truth
    and the richer models' fits both come here."""
    if friction == "stribeck":
        def friction(f0, c):
            return make_law("stribeck", f0, c, stribeck_ratio=stribeck_ratio, stribeck_velocity=stribeck_velocity)
    net = build_network(name, params, friction)
    return with_backlash(net, backlash) if backlash > 0 else net


@dataclass(frozen=True)
class LinearChain:
    """One of the paper's networks with Coulomb friction, as the linear map it is from the
    parameters (a vector in :data:`FIELDS` order) to its compiled arrays: each node's mass
    plus inertance, each link's damping and stiffness, each node's viscous coefficient and
    Coulomb bound is a linear form of the parameters (``coef @ values + const``), read off
    by compiling the network once on symbolic parameters (:func:`linear_chain`). The
    likelihood forms the arrays from it at every evaluation instead of building and
    compiling the network (the same arrays)."""

    name: str
    coef: np.ndarray  # (rows, len(FIELDS))
    sizes: tuple[int, ...]  # masses, link_c, link_k, viscous, bounds
    const: np.ndarray | None = None  # (rows,); None where every form has none

    def arrays(self, values: np.ndarray) -> tuple[np.ndarray, ...]:
        """(masses, link_c, link_k, viscous, bounds) at ``values`` (FIELDS order)."""
        flat = _sums(self.coef, np.asarray(values, dtype=float))
        if self.const is not None:
            flat = flat + self.const
        out, at = [], 0
        for size in self.sizes:
            out.append(flat[at : at + size])
            at += size
        return tuple(out)


@njit(cache=True)
def _sums(coef, values):
    """coef @ values, each row summed in the parameters' order."""
    out = np.zeros(coef.shape[0])
    for r in range(coef.shape[0]):
        s = 0.0
        for k in range(coef.shape[1]):
            s += coef[r, k] * values[k]
        out[r] = s
    return out


@functools.lru_cache(maxsize=None)
def linear_chain(name: str) -> LinearChain | None:
    """The :class:`LinearChain` of network ``name`` (Coulomb friction): the network built
    and compiled once on symbolic parameters (``network.symbolic``), every array's
    entries read off as linear forms. None where the network needs more than the exact
    kernel's Coulomb form, or is not linear in its parameters (a builder that multiplies
    two of them raises TypeError there)."""
    p = SimpleNamespace(**symbols(FIELDS))
    try:
        compiled = compile_network(build_network(name, p, SymbolicCoulomb))
    except TypeError:
        return None
    if not compiled.all_coulomb:
        return None
    parts = (compiled.masses, compiled.link_c, compiled.link_k, compiled.viscous, compiled.coulomb_bounds)
    coef, const = coefficients([v for part in parts for v in part], FIELDS)
    return LinearChain(name, coef, tuple(len(part) for part in parts), const if np.any(const) else None)
