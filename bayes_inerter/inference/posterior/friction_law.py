"""The friction law's shape, marginalised: what a Coulomb and viscous law leaves out.

The two-port model's contacts rub by Coulomb's law plus a viscous term. A real contact's
force is some odd function of its sliding velocity: a break-away above the Coulomb force
that falls off with speed (Stribeck), a drag that grows faster than linearly. A fit that
has only f_0 sgn(v) + c_f v bends b, the masses and the damping to mimic the rest.

Here the plate's friction gets a deviation from the model's law that is an unknown odd
function of the measured plate velocity,

    delta(t) = sum_j beta_j phi_j(v(t)),   phi_j(v) = S(t) exp(-|v(t)| / (s_j v_max)),

S(t) the friction's sign (``reversals.switched_sign``), v_max the velocity's peak, and
s_j the widths in ``WIDTHS`` (**assumption**: shares of the peak velocity from a
Stribeck fall that ends almost at once to one that spans the stroke). Each beta_j is
normal with mean 0 and sd ``SD`` times the contacts' Coulomb forces (f1_0 + f2_0: the
rotation's friction reaches the plate through the nut), and the betas are marginalised
with the reversals' deviations (``reversals.reversal_correction``): the harmonics of
phi_j are columns of the same basis. Before they join it, the part of each column that
the model's own f1_0 sgn(v) + c_f1 v can make is taken out (:func:`beyond`,
``LikelihoodSettings.law_orthogonal``): the widest phi_j is almost the Coulomb square
wave minus a viscous force, and left in it lets the friction and the deviation trade.

Why it does not take b's place: for a sinusoidal motion v(t) = V cos(w t) every
function of v is even in t and so has only cosine harmonics, in phase with the
velocity, while the inertial force b a(t) is a sine. The law's deviation can explain
friction's shape; it cannot explain inertia.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WIDTHS", "SD", "law_basis", "beyond"]

#: **Assumption**: the widths of the law's deviations, shares of the peak plate velocity.
WIDTHS = (0.03, 0.1, 0.3, 1.0)
#: **Assumption**: each deviation's prior sd as a share of the Coulomb forces f1_0 + f2_0
#: (a break-away up to about 1.5 times the Coulomb force at two sd over all widths).
SD = 0.25


def law_basis(velocity: np.ndarray, sign: np.ndarray, K: int) -> np.ndarray:
    """U (2K, len(WIDTHS)): the harmonics 1..K (real parts, then imaginary parts) of each
    phi_j over one period, from the plate's velocity and the friction's sign sampled on
    the same uniform grid (module docstring)."""
    v = np.asarray(velocity, dtype=float)
    n = v.shape[0]
    peak = float(np.max(np.abs(v)))
    if not peak > 0:
        return np.zeros((2 * K, 0))
    cols = []
    for s in WIDTHS:
        phi = np.asarray(sign, dtype=float) * np.exp(-np.abs(v) / (s * peak))
        X = np.fft.rfft(phi)[1: K + 1] / n * 2.0
        cols.append(np.concatenate([X.real, X.imag]))
    return np.column_stack(cols)


def beyond(U: np.ndarray, *harmonics: np.ndarray) -> np.ndarray:
    """U with the span of ``harmonics`` taken out (each a (K,) complex array that a real
    parameter multiplies, as f1_0 does the sign's and c_f1 the velocity's): the part of
    the law's deviations that the model's own Coulomb and viscous terms cannot make.
    Left in, a deviation and the friction's parameters explain the same force, and the
    deviations' prior sd, which scales with the friction, pulls the friction low."""
    if U.shape[1] == 0:
        return U
    A = np.column_stack([np.concatenate([h.real, h.imag]) for h in harmonics])
    Q, _ = np.linalg.qr(A)
    return U - Q @ (Q.T @ U)
