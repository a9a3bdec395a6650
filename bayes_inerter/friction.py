"""Friction laws: force (N) as a function of sliding velocity (m/s).

Three laws, each a frozen dataclass usable on any friction block of a network:

- :class:`Coulomb`: the paper's eq. (3), ``f0 sgn(v) + c v`` with the sign set-valued at
  rest (true stick-slip: a body at rest stays at rest while the other forces on it are
  within +-f0).
- :class:`Stribeck`: Li et al.'s law, a break-away force ``f_s`` at rest falling to the
  Coulomb level ``f_c`` as the speed grows, ``sgn(v) (f_c + (f_s - f_c) exp(-|v/v_s|^delta)) + c v``;
  set-valued at rest with bound ``f_s``.
- :class:`Smooth`: Simscape's smooth law (MODEL.md section 2),
  ``sqrt(2e) (f_brk - f_c) exp(-(v/v_St)^2) v/v_St + f_c tanh(v/v_Coul) + c v`` with
  ``v_St = v_brk sqrt(2)`` and ``v_Coul = v_brk / 10``; single-valued everywhere.

Each law gives its linear (viscous) part, its set-valued bound at rest, and a smooth
version of itself (``regularized``) for the general stiff solver, where ``sgn(v)`` becomes
``tanh(v / v_eps)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["FrictionLaw", "Coulomb", "Stribeck", "Smooth", "make_law", "LAW_NAMES"]

#: Assumptions for the laws the paper does not parameterise (options of `make_law`).
STRIBECK_RATIO = 1.3  # break-away / Coulomb force, dimensionless
STRIBECK_VELOCITY = 0.01  # m/s
SMOOTH_BREAKAWAY_VELOCITY = 1e-3  # m/s (so v_Coul = 1e-4 m/s)


def _check(name: str, value: float, *, positive: bool = False) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"friction parameter {name} must be finite, got {value}")
    if positive and value <= 0:
        raise ValueError(f"friction parameter {name} must be positive, got {value}")
    if value < 0:
        raise ValueError(f"friction parameter {name} must be non-negative, got {value}")
    return value


class FrictionLaw:
    """Interface shared by the laws (see module docstring)."""

    viscous: float  # N s/m, the linear part (what is left "with Coulomb terms off")

    @property
    def bound(self) -> float:
        """Largest force (N) the contact holds at rest; 0 for single-valued laws."""
        return 0.0

    @property
    def is_coulomb(self) -> bool:
        """True for the piecewise-linear law the exact event-driven kernel handles."""
        return False

    def force(self, v: np.ndarray) -> np.ndarray:
        """Friction force at sliding velocity v (v != 0 for set-valued laws), N."""
        raise NotImplementedError

    def regularized(self, v: np.ndarray, v_eps: float) -> tuple[np.ndarray, np.ndarray]:
        """Smooth force (N) and its slope dF/dv (N s/m), sgn(v) -> tanh(v / v_eps)."""
        raise NotImplementedError

    def without_coulomb(self) -> Coulomb:
        """The law's linear part alone (what the two-port view sees)."""
        return Coulomb(0.0, self.viscous)


@dataclass(frozen=True)
class Coulomb(FrictionLaw):
    """Coulomb plus viscous friction, eq. (3): ``f0 sgn(v) + c v``, sign set-valued.

    Parameters
    ----------
    f0 : Coulomb force, N (>= 0).
    c : viscous coefficient, N s/m (>= 0).
    """

    f0: float
    c: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "f0", _check("f0", self.f0))
        object.__setattr__(self, "c", _check("c", self.c))

    @property
    def viscous(self) -> float:
        return self.c

    @property
    def bound(self) -> float:
        return self.f0

    @property
    def is_coulomb(self) -> bool:
        return True

    def force(self, v):
        v = np.asarray(v, dtype=float)
        return self.f0 * np.sign(v) + self.c * v

    def regularized(self, v, v_eps):
        v = np.asarray(v, dtype=float)
        t = np.tanh(v / v_eps)
        return self.f0 * t + self.c * v, self.f0 * (1 - t * t) / v_eps + self.c


@dataclass(frozen=True)
class Stribeck(FrictionLaw):
    """Stribeck friction (Li et al.), set-valued at rest with bound ``f_s``.

    Parameters
    ----------
    f_c : Coulomb (sliding) force, N.
    f_s : static (break-away) force, N, >= f_c.
    v_s : Stribeck velocity, m/s (> 0).
    c : viscous coefficient, N s/m.
    delta : shape exponent (2: Gaussian), dimensionless.
    """

    f_c: float
    f_s: float
    v_s: float
    c: float = 0.0
    delta: float = 2.0

    def __post_init__(self) -> None:
        for name in ("f_c", "f_s", "c"):
            object.__setattr__(self, name, _check(name, getattr(self, name)))
        object.__setattr__(self, "v_s", _check("v_s", self.v_s, positive=True))
        object.__setattr__(self, "delta", _check("delta", self.delta, positive=True))
        if self.f_s < self.f_c:
            raise ValueError(f"Stribeck f_s ({self.f_s}) must be >= f_c ({self.f_c})")

    @property
    def viscous(self) -> float:
        return self.c

    @property
    def bound(self) -> float:
        return self.f_s

    def _level(self, v):
        return self.f_c + (self.f_s - self.f_c) * np.exp(-np.abs(v / self.v_s) ** self.delta)

    def force(self, v):
        v = np.asarray(v, dtype=float)
        return np.sign(v) * self._level(v) + self.c * v

    def regularized(self, v, v_eps):
        v = np.asarray(v, dtype=float)
        t = np.tanh(v / v_eps)
        level = self._level(v)
        x = np.abs(v / self.v_s)
        dlevel = -(self.f_s - self.f_c) * np.exp(-(x**self.delta)) * self.delta
        dlevel = dlevel * np.where(x > 0, x ** (self.delta - 1), 0.0) * np.sign(v) / self.v_s
        return t * level + self.c * v, (1 - t * t) / v_eps * level + t * dlevel + self.c


@dataclass(frozen=True)
class Smooth(FrictionLaw):
    """Simscape's smooth friction law (single-valued; no true sticking).

    Parameters
    ----------
    f_brk : break-away force, N (>= f_c).
    f_c : Coulomb force, N.
    v_brk : break-away velocity, m/s (> 0); v_St = v_brk sqrt(2), v_Coul = v_brk / 10.
    c : viscous coefficient, N s/m.
    """

    f_brk: float
    f_c: float
    v_brk: float
    c: float = 0.0

    def __post_init__(self) -> None:
        for name in ("f_brk", "f_c", "c"):
            object.__setattr__(self, name, _check(name, getattr(self, name)))
        object.__setattr__(self, "v_brk", _check("v_brk", self.v_brk, positive=True))
        if self.f_brk < self.f_c:
            raise ValueError(f"Smooth f_brk ({self.f_brk}) must be >= f_c ({self.f_c})")

    @property
    def viscous(self) -> float:
        return self.c

    def _parts(self, v):
        v_st = self.v_brk * math.sqrt(2)
        v_coul = self.v_brk / 10
        a = math.sqrt(2 * math.e) * (self.f_brk - self.f_c)
        x = v / v_st
        g = np.exp(-x * x)
        t = np.tanh(v / v_coul)
        force = a * g * x + self.f_c * t + self.c * v
        slope = a * g * (1 - 2 * x * x) / v_st + self.f_c * (1 - t * t) / v_coul + self.c
        return force, slope

    def force(self, v):
        return self._parts(np.asarray(v, dtype=float))[0]

    def regularized(self, v, v_eps):
        return self._parts(np.asarray(v, dtype=float))


LAW_NAMES = ("coulomb", "stribeck", "smooth")


def make_law(
    name: str,
    f0: float,
    c: float,
    *,
    stribeck_ratio: float = STRIBECK_RATIO,
    stribeck_velocity: float = STRIBECK_VELOCITY,
    breakaway_velocity: float = SMOOTH_BREAKAWAY_VELOCITY,
) -> FrictionLaw:
    """Map the paper's (Coulomb f0, viscous c) pair onto the law called ``name``.

    **Assumptions** (the paper parameterises only eq. (3)): ``stribeck`` takes f0 as its
    sliding level and ``stribeck_ratio * f0`` as its break-away force at
    ``stribeck_velocity``; ``smooth`` (Simscape) takes f_brk = f_c = f0 (no hump) and
    ``breakaway_velocity``, so its tanh width is ``breakaway_velocity / 10``.
    """
    if name == "coulomb":
        return Coulomb(f0, c)
    if name == "stribeck":
        return Stribeck(f0, stribeck_ratio * f0, stribeck_velocity, c)
    if name == "smooth":
        return Smooth(f0, f0, breakaway_velocity, c)
    raise ValueError(f"unknown friction law {name!r}; choose one of {', '.join(LAW_NAMES)}")
