"""Effects the paper's model lacks, as fitted parameters: Stribeck friction and nut backlash.

The richer models (``two-port-stribeck``, ``two-port-backlash``, ``two-port-rich``) are
the two-port model with some of these parameters added:

- ``r_s``: break-away over Coulomb force of both contacts' Stribeck law (one ratio for
  both), prior uniform on [1, 2] (1: no Stribeck hump; above 2 a ball screw's
  break-away is no longer "friction" but a jam);
- ``v_s``: their Stribeck velocity, m/s, prior log-uniform on [1e-4, 1e-1];
- ``gap``: the nut link's backlash half-width, m, prior uniform on [0, 100 um].

These priors are **assumptions** (what is physically plausible for a ball-screw
inerter, not measured), options like every prior (``priors=``). The friction law is
:class:`...friction.Stribeck` with shape exponent 2, simulated by the exact kernel in its
piecewise-linear form (``friction.STRIBECK_SEGMENTS`` segments); the backlash is a dead
zone in the nut's spring and damper (:class:`...network.Backlash`).
"""

from __future__ import annotations

from ...friction import STRIBECK_VELOCITY
from ...networks import device_network
from ...network import Network
from .priors import LogUniform, Uniform

__all__ = ["EFFECTS", "EFFECT_PRIORS", "NO_EFFECT", "effect_network"]

#: The effects each richer model fits.
EFFECTS = {
    "two-port-stribeck": ("r_s", "v_s"),
    "two-port-backlash": ("gap",),
    "two-port-rich": ("r_s", "v_s", "gap"),
}

#: Priors of the effects (see module docstring).
EFFECT_PRIORS = {
    "r_s": Uniform(1.0, 2.0),
    "v_s": LogUniform(1e-4, 1e-1),  # m/s
    "gap": Uniform(0.0, 1e-4),  # m
}

#: The effects' values in a model that does not fit them: the paper's Coulomb law and
#: no backlash.
NO_EFFECT = {"r_s": 1.0, "v_s": STRIBECK_VELOCITY, "gap": 0.0}


def effect_network(name: str, params, effects: dict) -> Network:
    """The network ``name`` at ``params`` with the ``effects`` (any of r_s, v_s, gap;
    the others as in :data:`NO_EFFECT`)."""
    e = {**NO_EFFECT, **effects}
    return device_network(name, params, "stribeck" if e["r_s"] > 1.0 else "coulomb", stribeck_ratio=e["r_s"],
                          stribeck_velocity=e["v_s"], backlash=e["gap"])
