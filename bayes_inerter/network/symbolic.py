"""Symbolic parameters: a network built and compiled on linear forms of named
parameters in place of numbers.

A :class:`Linear` is ``coef @ values + const`` over a fixed tuple of parameter names. It
adds to another and to numbers, and multiplies by numbers; anything else (a product of
two, a comparison, ``float()``) raises TypeError, so a network whose arrays are not
linear in its parameters cannot pass for one. The blocks (``network.blocks``) keep a
Linear as it is, with their checks left to the numbers it will take; ``compile_network``
sums them into arrays of Linear; :class:`SymbolicCoulomb` is the Coulomb law on them.

``networks.linear_chain`` compiles each of the paper's networks once this way: the
coefficients of every node's mass and inertance, every link's damping and stiffness,
every node's viscous coefficient and Coulomb bound, read off exactly (the full
network's tan(theta) shares included), with no network compiled at numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..friction import FrictionLaw

__all__ = ["Linear", "SymbolicCoulomb", "symbols", "coefficients"]


class Linear:
    """``coef @ values + const`` over ``names`` (see module docstring)."""

    __slots__ = ("names", "coef", "const")

    def __init__(self, names: tuple[str, ...], coef, const: float = 0.0):
        self.names = tuple(names)
        self.coef = np.asarray(coef, dtype=float)
        self.const = float(const)
        if self.coef.shape != (len(self.names),):
            raise ValueError(f"a Linear over {len(self.names)} names needs as many coefficients, got {self.coef.shape}")

    def _other(self, other) -> Linear | None:
        if isinstance(other, Linear):
            if other.names != self.names:
                raise TypeError("Linear forms over different names")
            return other
        if isinstance(other, (int, float, np.integer, np.floating)):
            return Linear(self.names, np.zeros(len(self.names)), float(other))
        return None

    def __add__(self, other):
        o = self._other(other)
        if o is None:
            return NotImplemented
        return Linear(self.names, self.coef + o.coef, self.const + o.const)

    __radd__ = __add__

    def __neg__(self):
        return Linear(self.names, -self.coef, -self.const)

    def __sub__(self, other):
        o = self._other(other)
        return NotImplemented if o is None else self + (-o)

    def __rsub__(self, other):
        o = self._other(other)
        return NotImplemented if o is None else o + (-self)

    def __mul__(self, other):
        if isinstance(other, (int, float, np.integer, np.floating)):
            return Linear(self.names, self.coef * float(other), self.const * float(other))
        if isinstance(other, Linear):
            raise TypeError("a product of two parameters is not linear in them")
        return NotImplemented

    __rmul__ = __mul__

    def __truediv__(self, other):
        if isinstance(other, (int, float, np.integer, np.floating)):
            return self * (1.0 / float(other))
        raise TypeError("division by a parameter is not linear in it")

    def is_zero(self) -> bool:
        return not np.any(self.coef) and self.const == 0.0

    def __eq__(self, other):
        o = self._other(other)
        if o is None:
            return NotImplemented
        return bool(np.array_equal(self.coef, o.coef) and self.const == o.const)

    __hash__ = None

    def __float__(self):
        raise TypeError("a symbolic parameter has no number; evaluate it at values")

    def _compare(self, other):
        raise TypeError("a symbolic parameter cannot be compared; its checks wait for numbers")

    __lt__ = __le__ = __gt__ = __ge__ = _compare

    def __call__(self, values) -> float:
        """The form at ``values`` (in ``names``' order)."""
        return float(self.coef @ np.asarray(values, dtype=float) + self.const)

    def __repr__(self) -> str:
        terms = [f"{c:g} {n}" for c, n in zip(self.coef, self.names) if c]
        return " + ".join(terms + ([f"{self.const:g}"] if self.const or not terms else []))


def symbols(names) -> dict[str, Linear]:
    """Each of ``names`` as the Linear form of itself alone."""
    names = tuple(names)
    return {n: Linear(names, np.eye(len(names))[i]) for i, n in enumerate(names)}


def coefficients(values, names) -> tuple[np.ndarray, np.ndarray]:
    """(coef, const) of a sequence of Linear forms (or numbers) over ``names``: one row
    each, so that the values at ``x`` are ``coef @ x + const``."""
    names = tuple(names)
    rows, consts = [], []
    for v in values:
        if isinstance(v, Linear):
            if v.names != names:
                raise TypeError("Linear forms over different names")
            rows.append(v.coef)
            consts.append(v.const)
        else:
            rows.append(np.zeros(len(names)))
            consts.append(float(v))
    return np.array(rows, dtype=float).reshape(len(rows), len(names)), np.array(consts, dtype=float)


@dataclass(frozen=True)
class SymbolicCoulomb(FrictionLaw):
    """The Coulomb law (``friction.Coulomb``) with symbolic ``f0`` and ``c``: its bound
    and viscous part are those forms."""

    f0: object
    c: object = 0.0

    @property
    def viscous(self):
        return self.c

    @property
    def bound(self):
        return self.f0

    @property
    def is_coulomb(self) -> bool:
        return True
