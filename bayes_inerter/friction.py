"""Friction laws: force (N) as a function of sliding velocity (m/s).

Four laws, each a frozen dataclass usable on any friction block of a network:

- :class:`Coulomb`: the paper's eq. (3), ``f0 sgn(v) + c v`` with the sign set-valued at
  rest (true stick-slip: a body at rest stays at rest while the other forces on it are
  within +-f0).
- :class:`Stribeck`: Li et al.'s law, a break-away force ``f_s`` at rest falling to the
  Coulomb level ``f_c`` as the speed grows, ``sgn(v) (f_c + (f_s - f_c) exp(-|v/v_s|^delta)) + c v``;
  set-valued at rest with bound ``f_s``.
- :class:`Smooth`: Simscape's smooth law (MODEL.md section 2),
  ``sqrt(2e) (f_brk - f_c) exp(-(v/v_St)^2) v/v_St + f_c tanh(v/v_Coul) + c v`` with
  ``v_St = v_brk sqrt(2)`` and ``v_Coul = v_brk / 10``; single-valued everywhere.
- :class:`PiecewiseLinear`: a force linear in the speed between knots (a break-away force
  falling to the Coulomb level in a few segments, say), set-valued at rest with its own
  static bound.

Each law gives its linear (viscous) part, its set-valued bound at rest, a smooth version
of itself (``regularized``) for the general stiff solver, where ``sgn(v)`` becomes
``tanh(v / v_eps)``, and, where it has one, its piecewise-linear form (``piecewise``),
which the exact event-driven kernel simulates: Coulomb's is itself, Stribeck's an
approximation in ``STRIBECK_SEGMENTS`` segments, the smooth law has none.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["FrictionLaw", "Coulomb", "Stribeck", "Smooth", "PiecewiseLinear", "make_law", "LAW_NAMES",
           "STRIBECK_SEGMENTS"]

#: Assumptions for the laws the paper does not parameterise (options of `make_law`).
STRIBECK_RATIO = 1.3  # break-away / Coulomb force, dimensionless
STRIBECK_VELOCITY = 0.01  # m/s
SMOOTH_BREAKAWAY_VELOCITY = 1e-3  # m/s (so v_Coul = 1e-4 m/s)
#: **Assumption**: segments of Stribeck's piecewise-linear form (``Stribeck.piecewise``),
#: the form the exact kernel simulates; with the default shape (delta = 2) the fall is
#: then within 2.7 % of f_s - f_c of the law's (6 segments: 1.5 %).
STRIBECK_SEGMENTS = 4


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

    def piecewise(self) -> PiecewiseLinear | None:
        """The law's piecewise-linear form, which the exact kernel simulates, or None."""
        return None


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

    def piecewise(self) -> PiecewiseLinear:
        """One segment: the force f0 from rest on, slope c."""
        return PiecewiseLinear((0.0,), (self.f0,), self.c, self.f0)


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

    @functools.lru_cache(maxsize=64)  # noqa: B019 (frozen, hashable; a likelihood asks again and again)
    def piecewise(self, segments: int = STRIBECK_SEGMENTS) -> PiecewiseLinear:
        """The law in ``segments`` linear pieces (2 to 8; default ``STRIBECK_SEGMENTS``).

        The knots interpolate the law, but for the last, from which on the force is the
        Coulomb level plus the viscous part (the last piece runs to infinity); they are
        placed so that every piece deviates from the law by the same largest amount
        (built greedily, see ``stribeck_knots``): ``stribeck_knots(delta, segments)[1]``
        times f_s - f_c. The static bound and the force just after break-away are f_s.
        """
        if self.f_s == self.f_c:
            return PiecewiseLinear((0.0,), (self.f_c,), self.c, self.f_s)
        x, _ = stribeck_knots(self.delta, segments)
        speeds = tuple(float(xi * self.v_s) for xi in x)
        forces = [float(self._level(v)) + self.c * v for v in speeds[:-1]]
        forces.append(self.f_c + self.c * speeds[-1])
        return PiecewiseLinear(speeds, tuple(forces), self.c, self.f_s)


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


@dataclass(frozen=True)
class PiecewiseLinear(FrictionLaw):
    """Friction linear in the sliding speed between knots, set-valued at rest.

    Sliding at speed |v| in piece i (``speeds[i] <= |v| < speeds[i + 1]``, the last piece
    running on to infinity), the force is ``sgn(v) (a_i + c_i |v|)``: linear between the
    knots' forces, continuous across them, with slope ``c`` beyond the last knot. At rest
    the contact holds any force within +-``f_s``.

    Parameters
    ----------
    speeds : the knots, m/s: 0 = speeds[0] < speeds[1] < ...
    forces : the sliding force at each knot, N (>= 0); forces[0] follows a break-away.
    c : slope beyond the last knot, N s/m (>= 0): the law's viscous part.
    f_s : static (break-away) bound, N, >= forces[0]; default forces[0].
    """

    speeds: tuple
    forces: tuple
    c: float = 0.0
    f_s: float | None = None

    def __post_init__(self) -> None:
        speeds = tuple(_check("speeds", v) for v in self.speeds)
        forces = tuple(_check("forces", f) for f in self.forces)
        if not speeds or len(speeds) != len(forces):
            raise ValueError(f"PiecewiseLinear needs as many forces as speeds (>= 1), got {len(forces)}, {len(speeds)}")
        if speeds[0] != 0.0 or any(b <= a for a, b in zip(speeds, speeds[1:])):
            raise ValueError(f"PiecewiseLinear speeds must start at 0 and increase, got {speeds}")
        object.__setattr__(self, "speeds", speeds)
        object.__setattr__(self, "forces", forces)
        object.__setattr__(self, "c", _check("c", self.c))
        f_s = forces[0] if self.f_s is None else _check("f_s", self.f_s)
        if f_s < forces[0]:
            raise ValueError(f"PiecewiseLinear f_s ({f_s}) must be >= forces[0] ({forces[0]})")
        object.__setattr__(self, "f_s", f_s)

    @property
    def viscous(self) -> float:
        return self.c

    @property
    def bound(self) -> float:
        return self.f_s

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(speeds, a, slopes): piece i's force is a_i + slopes_i |v| from speeds_i on."""
        v, f = np.array(self.speeds), np.array(self.forces)
        slopes = np.append(np.diff(f) / np.diff(v), self.c)
        return v, f - slopes * v, slopes

    def _parts(self, v):
        """sgn(v), the force's size at |v| and its slope there (pieces as ``segments``)."""
        v = np.asarray(v, dtype=float)
        speeds, a, slopes = self.segments()
        piece = np.searchsorted(speeds, np.abs(v), side="right") - 1
        return np.sign(v), a[piece] + slopes[piece] * np.abs(v), slopes[piece]

    def force(self, v):
        sign, size, _ = self._parts(v)
        return sign * size

    def regularized(self, v, v_eps):
        v = np.asarray(v, dtype=float)
        _, size, slope = self._parts(v)
        t = np.tanh(v / v_eps)
        rest = size - self.c * np.abs(v)  # all but the viscous part, which is not smoothed
        return t * rest + self.c * v, (1 - t * t) / v_eps * rest + t * np.sign(v) * (slope - self.c) + self.c

    def piecewise(self) -> PiecewiseLinear:
        return self

    @staticmethod
    def total(laws) -> PiecewiseLinear | None:
        """The sum of laws on one node as one piecewise-linear law, or None if one has none."""
        forms = [law.piecewise() for law in laws]
        if any(form is None for form in forms) or len(forms) == 1:
            return forms[0] if len(forms) == 1 else None
        speeds = tuple(sorted({v for form in forms for v in form.speeds}))
        forces = tuple(float(sum(form._parts(v)[1] for form in forms)) for v in speeds)
        return PiecewiseLinear(speeds, forces, sum(f.c for f in forms), sum(f.f_s for f in forms))


@functools.lru_cache(maxsize=None)
def stribeck_knots(delta: float, segments: int) -> tuple[tuple[float, ...], float]:
    """Knots x_0 = 0 < ... < x_{S-1} (in units of v_s) of the piecewise-linear form of the
    fall g(x) = exp(-x^delta) in S = ``segments`` pieces, and the largest deviation from it.

    The pieces interpolate g at their knots but the last, where the form drops to 0 and
    stays (the tail). For a target deviation e, each piece is made as long as it can be
    within e, the last knot is where the tail is within e, and e is bisected for the
    smallest that S pieces reach: an equal-error construction, within a few percent of
    the best one (delta = 2, 4 pieces: 0.0265 against 0.0255 by a numerical search).
    """
    if not 2 <= segments <= 8:
        raise ValueError(f"segments must be 2 to 8, got {segments}")

    def g(x):
        return np.exp(-np.abs(x) ** delta)

    def deviation(a, b, gb):  # of the chord from (a, g(a)) to (b, gb) over [a, b]
        if b <= a:
            return 0.0
        x = np.linspace(a, b, 97)
        return float(np.max(np.abs(g(x) - (g(a) + (gb - g(a)) * (x - a) / (b - a)))))

    def reach(e):
        """The knots for deviation e, or None where S pieces fall short."""
        tail = (-math.log(e)) ** (1.0 / delta)
        x = [0.0]
        for _ in range(segments - 2):
            lo, hi = x[-1], tail
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if deviation(x[-1], mid, g(mid)) <= e else (lo, mid)
            x.append(lo)
        ends = [end for end in np.linspace(tail, 3.0 * tail, 161) if deviation(x[-1], end, 0.0) <= e]
        return x + [float(ends[0])] if ends else None

    lo, hi = 1e-6, 0.9
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if reach(mid) is not None else (mid, hi)
    return tuple(reach(hi)), hi


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
