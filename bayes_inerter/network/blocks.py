"""Two-port blocks on (force, velocity) and their transmission matrices.

Convention (stated once, used everywhere): each block is a two-port with port 1 towards
the driven terminal and port 2 towards the far end. Its transmission (ABCD) matrix maps
the far port to the near one::

    [F1]   [T11 T12] [F2]
    [v1] = [T21 T22] [v2]

F1 is the force pushed into port 1, F2 the force passed on out of port 2, v1 and v2 the
port velocities (N, m/s). A chain of blocks is the product of their matrices in order
(:func:`bayes_inerter.network.cascade`). In the force-current (mobility) reading:

- a *shunt* element connects the node to ground and takes force ``Y(s) v`` from it:
  ``T = [[1, Y], [0, 1]]`` (a mass: Y = m s; an inerter to ground: Y = b s; the linear
  part of a friction block: Y = c);
- a *series* deformation ``Q = c + k/s`` carries ``F = Q (v1 - v2)``:
  ``T = [[1, 0], [1/Q, 1]]``.

This is not the paper's notation for eq. (2), which the paper does not define; the tests
prove this one right against the time-domain model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..friction import FrictionLaw
from .symbolic import Linear

__all__ = ["Block", "Mass", "Inerter", "Deformation", "Friction", "Backlash"]


def _positive(kind: str, name: str, value: float) -> float:
    if isinstance(value, Linear):  # a symbolic parameter: checked where it takes a number
        return value
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"{kind}: {name} must be positive and finite, got {value}")
    return value


def _non_negative(kind: str, name: str, value: float) -> float:
    if isinstance(value, Linear):
        return value
    value = float(value)
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"{kind}: {name} must be non-negative and finite, got {value}")
    return value


def _shunt(admittance: np.ndarray) -> np.ndarray:
    one, zero = np.ones_like(admittance), np.zeros_like(admittance)
    return np.stack([np.stack([one, admittance], -1), np.stack([zero, one], -1)], -2)


class Block:
    """A two-port element; ``abcd(s)`` gives its matrices, shape (len(s), 2, 2)."""

    def abcd(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError


@dataclass(frozen=True)
class Mass(Block):
    """A mass (kg) moving with the current node: a shunt of admittance m s."""

    m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "m", _positive("Mass", "m", self.m))

    def abcd(self, s):
        return _shunt(self.m * np.asarray(s, dtype=complex))


@dataclass(frozen=True)
class Inerter(Block):
    """An inerter (kg) between the current node and ground: a shunt of admittance b s.

    In the paper's network the nut is grounded, so the rotation coordinate
    x_th = p theta / (2 pi) carries the inertance b exactly as a mass would.
    """

    b: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "b", _positive("Inerter", "b", self.b))

    def abcd(self, s):
        return _shunt(self.b * np.asarray(s, dtype=complex))


@dataclass(frozen=True)
class Friction(Block):
    """A friction contact between the current node and ground, with any friction law.

    The two-port view (frequency response, "Coulomb terms off") sees only the law's
    viscous part, a shunt of admittance c.
    """

    law: FrictionLaw

    def __post_init__(self) -> None:
        if not isinstance(self.law, FrictionLaw):
            raise ValueError(f"Friction: law must be a FrictionLaw, got {self.law!r}")

    def abcd(self, s):
        s = np.asarray(s, dtype=complex)
        return _shunt(np.full_like(s, self.law.viscous))


@dataclass(frozen=True)
class Backlash:
    """A dead zone of total width ``2 gap`` (m) in a deformation: no force inside it.

    A nonlinear option of :class:`Deformation`; the two-port view takes the contact
    closed (gap = 0), which is the small-signal behaviour once the gap is taken up.
    """

    gap: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "gap", _non_negative("Backlash", "gap", self.gap))


@dataclass(frozen=True)
class Deformation(Block):
    """A series deformation Q = c + k/s between the current node and a new one.

    Parameters
    ----------
    c : damping, N s/m (>= 0).
    k : stiffness, N/m (>= 0); c + k > 0.
    backlash : optional dead zone (see :class:`Backlash`), simulated by the exact kernel.
    """

    c: float
    k: float
    backlash: Backlash | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "c", _non_negative("Deformation", "c", self.c))
        object.__setattr__(self, "k", _non_negative("Deformation", "k", self.k))
        if self.c == 0 and self.k == 0:
            raise ValueError("Deformation: c and k cannot both be zero (that is no link)")

    def abcd(self, s):
        s = np.asarray(s, dtype=complex)
        inv_q = s / (self.c * s + self.k)
        one, zero = np.ones_like(s), np.zeros_like(s)
        return np.stack([np.stack([one, zero], -1), np.stack([inv_q, one], -1)], -2)
