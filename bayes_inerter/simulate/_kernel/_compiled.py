"""The compiled helpers shared by every generated kernel (see ``generate.py``).

What is the same for every network lives here, compiled once: the levels and the
matrix-exponential tables of each mode, the Hermite range of a guard, and the contacts'
switching rules (where the kernel starts, and what a contact does when its guard is
crossed). The per-sample loop, the bisection and the guards are generated per network.

The augmented state is ``z = [x (n), u (n_in), du (n_in), w (nc)]``: the network's state,
the inputs and their slopes over the sample interval, and each contact's Coulomb force
on its node. A *mode* is a bit mask of the stuck contacts (bit i: contact i sticks).
"""

from __future__ import annotations

import numpy as np
from numba import njit

STATUS_OK = 0
STATUS_TOO_MANY_EVENTS = 1

MIN_LEVELS = 20  # event resolution h / 2^20
MAX_LEVELS = 60

#: The cubic Hermite interpolant on [0, 1] lies within HERMITE_SLACK (|d0| + |d1|) of the
#: range of its end values (its value basis functions are non-negative and sum to one;
#: each slope basis function is at most 4/27 in size).
HERMITE_SLACK = 4.0 / 27.0


@njit(cache=True)
def levels(Abar, h):
    """The number of halvings J of the sample interval: at least MIN_LEVELS (the events'
    resolution h / 2^J), and enough that ||Abar|| h / 2^J <= 1/16 (the Taylor series)."""
    norm = 0.0
    for i in range(Abar.shape[0]):
        s = 0.0
        for j in range(Abar.shape[1]):
            s += abs(Abar[i, j])
        norm = max(norm, s)
    scaled = norm * h
    J = MIN_LEVELS
    while J < MAX_LEVELS and scaled / 2.0**J > 1.0 / 16.0:
        J += 1
    return J


@njit(cache=True)
def tables(Abar, h, J):
    """F[j] = exp(Abar h / 2^j) - I for j = 0..J (Taylor at J, then squaring; keeping
    E - I loses no digits for small steps)."""
    m = Abar.shape[0]
    F = np.zeros((J + 1, m, m))
    X = Abar * (h / 2.0**J)
    term = X.copy()
    acc = X.copy()
    for q in range(2, 30):
        term = term @ X / q
        acc += term
        if np.max(np.abs(term)) < 1e-300 or np.max(np.abs(term)) < 1e-18 * np.max(np.abs(acc)):
            break
    fill2(F[J], acc)
    for j in range(J - 1, -1, -1):
        G = F[j + 1]
        fill2(F[j], 2.0 * G + G @ G)
    return F


@njit(cache=True)
def fill1(dst, src):
    """dst[:] = src for 1-d arrays of one length, element by element. Numba's own
    assignment of an array to a slice checks the shapes with an error message whose
    compilation took 4 to 6 s in every process that compiled a kernel; these loops take
    none of it."""
    for i in range(dst.shape[0]):
        dst[i] = src[i]


@njit(cache=True)
def fill2(dst, src):
    """dst[:, :] = src for 2-d arrays of one shape, element by element (see ``fill1``)."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True)
def cubic_range(y0, d0, y1, d1):
    """Min and max over s in [0, 1] of the cubic Hermite interpolant (d scaled by T)."""
    lo = min(y0, y1)
    hi = max(y0, y1)
    a = 2.0 * y0 - 2.0 * y1 + d0 + d1
    b = -3.0 * y0 + 3.0 * y1 - 2.0 * d0 - d1
    c = d0
    # extremes at the roots of 3 a s^2 + 2 b s + c inside (0, 1)
    A = 3.0 * a
    B = 2.0 * b
    if abs(A) < 1e-300:
        if abs(B) > 1e-300:
            s = -c / B
            if 0.0 < s < 1.0:
                p = ((a * s + b) * s + c) * s + y0
                lo = min(lo, p)
                hi = max(hi, p)
        return lo, hi
    disc = B * B - 4.0 * A * c
    if disc >= 0.0:
        sq = np.sqrt(disc)
        for s in ((-B - sq) / (2.0 * A), (-B + sq) / (2.0 * A)):
            if 0.0 < s < 1.0:
                p = ((a * s + b) * s + c) * s + y0
                lo = min(lo, p)
                hi = max(hi, p)
    return lo, hi


@njit(cache=True)
def _holding(R, i, z):
    """Contact i's holding force R[i] . z (summed in the order of j)."""
    s = 0.0
    for j in range(z.shape[0]):
        s += R[i, j] * z[j]
    return s


@njit(cache=True)
def switch(z, mode, nc, node, R, f0, sgn, wcol):
    """Apply the contact switches due at z; return the new mode (z, sgn changed in place).

    A stuck contact whose holding force exceeds its bound breaks away in the direction of
    that force; a sliding one whose velocity has crossed zero stops, and sticks if the
    holding force is within the bound, else slides on the other way (a reversal)."""
    for i in range(nc):
        bit = 1 << i
        if mode & bit:
            r = _holding(R, i, z)
            if abs(r) > f0[i]:  # break away in the direction of the holding force
                mode &= ~bit
                sgn[i] = 1.0 if r > 0 else -1.0
                z[wcol + i] = sgn[i] * f0[i]
        elif sgn[i] * z[node[i]] < 0.0:  # velocity reached zero: stick or reverse
            z[node[i]] = 0.0
            r = _holding(R, i, z)
            if abs(r) <= f0[i]:
                mode |= bit
            else:
                sgn[i] = 1.0 if r > 0 else -1.0
                z[wcol + i] = sgn[i] * f0[i]
    return mode


@njit(cache=True)
def setup(Abar, n, n_in, node, mass, h, out_node):
    """Per mode: the tables' n state rows F (a step needs no more: the inputs move linearly
    and their slopes and the Coulomb forces stay), the guards' derivative rows VD (a
    sliding contact's acceleration) and RD (a stuck one's holding-force rate), the output
    row OUT; and the stuck contacts' holding-force rows R (the node's mass times its
    acceleration without its own Coulomb force). Returns (J, F, VD, RD, OUT, R)."""
    m = Abar.shape[0]
    nc = node.shape[0]
    wcol = n + 2 * n_in
    n_modes = 1 << nc
    J = levels(Abar, h)
    F = np.zeros((n_modes, J + 1, n, m))
    VD = np.zeros((n_modes, max(nc, 1), m))
    RD = np.zeros((n_modes, max(nc, 1), m))
    OUT = np.zeros((n_modes, m))
    R = np.zeros((max(nc, 1), m))
    for i in range(nc):
        fill1(R[i], mass[i] * Abar[node[i]])
        for q in range(nc):
            R[i, wcol + q] = 0.0
    for mode in range(n_modes):
        As = Abar.copy()
        for i in range(nc):
            if (mode >> i) & 1:
                As[node[i], :] = 0.0
        T = tables(As, h, J)
        for lev in range(J + 1):
            fill2(F[mode, lev], T[lev][:n])
        for i in range(nc):
            fill1(VD[mode, i], As[node[i]])
            fill1(RD[mode, i], R[i] @ As)
        fill1(OUT[mode], As[out_node])
    return J, F, VD, RD, OUT, R


@njit(cache=True)
def start(z_init, inputs, n, n_in, m, node, R, f0):
    """The augmented state at the first sample, the sliding contacts' signs and the mode:
    contacts at rest stick if they can. Returns (z, sgn, mode)."""
    nc = node.shape[0]
    wcol = n + 2 * n_in
    z = np.zeros(m)
    fill1(z[:n], z_init)
    for q in range(n_in):
        z[n + q] = inputs[0, q]
    sgn = np.ones(max(nc, 1))
    mode = 0
    for i in range(nc):
        v = z[node[i]]
        if v == 0.0:
            mode |= 1 << i
        else:
            sgn[i] = 1.0 if v > 0 else -1.0
            z[wcol + i] = sgn[i] * f0[i]
    mode = switch(z, mode, nc, node, R, f0, sgn, wcol)
    return z, sgn, mode
