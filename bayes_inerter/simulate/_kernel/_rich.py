"""Compiled helpers of the kernels for piecewise-linear friction laws and dead zones.

The network has *elements*: friction contacts (e = 0 .. nc - 1) and links with a dead
zone (e = nc .. nc + nl - 1). The augmented state is ``z = [x (n), u, du (n_in each),
w_c (nc), w_l (nl)]``: w_c the contacts' constant forces (N; sgn a_s while sliding in
piece s of their law, whose force there is sgn (a_s + c_s |v|)), w_l the links' offsets
(m; +-g while a link is closed on that side, its spring then acting on d -+ g).

An element's *state*: a contact's piece (0 .. S - 1), or S when it sticks; a link's 0
(open: inside the gap, no force) or 1 (closed). Only the state changes the matrix (a
piece its slope, a stuck contact's zero row, a closed link its spring and damper); the
directions and sides enter through w and the guards' bands. A mode is the mixed-radix
number of the states, and its tables are made when it is first entered: there can be
many modes (a contact's pieces times the others'), few of which a record visits.

A guard is a value that must stay within a band [lo, hi]: a sliding contact's velocity
within its piece's speeds (signed), a stuck contact's holding force within +-f_s, a
link's deflection d within the gap or beyond it on its side.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ._compiled import fill1, fill2, levels


class Net(NamedTuple):
    """A network with piecewise-linear contacts and dead zones, as the kernel reads it."""

    Abar: np.ndarray  # (m, m): every link with a gap open, every contact at its law's slope c
    L: np.ndarray  # (max(nl, 1), m, m): what closing each link adds (its spring, damper, offset)
    node: np.ndarray  # (nc,) int: the contacts' nodes
    mass: np.ndarray  # (nc,): their masses, kg
    bound: np.ndarray  # (nc,): their static bounds f_s, N
    knots: np.ndarray  # (nc, S_max + 1): the pieces' first speeds, m/s, then inf
    force: np.ndarray  # (nc, S_max): a_s, N
    dslope: np.ndarray  # (nc, S_max): -(c_s - c) / mass, the node's diagonal change in piece s
    col: np.ndarray  # (ne,) int: each element's guard column (node; deflection)
    gap: np.ndarray  # (max(nl, 1),): the links' half-widths g, m
    radix: np.ndarray  # (ne,) int: each element's number of states
    stride: np.ndarray  # (ne,) int: its place in the mode number
    n: int
    n_in: int
    out_node: int
    h: float


@njit(cache=True)
def setup(net):
    """Room for every mode's tables (filled when first entered): (J, F, VD, RD, OUT, R,
    ready) as in ``_compiled.setup``, R and RD per mode (a link's state changes them)."""
    m, nc, ne = net.Abar.shape[0], net.node.shape[0], net.col.shape[0]
    n_modes = 1
    for e in range(ne):
        n_modes *= net.radix[e]
    envelope = np.abs(net.Abar)  # no mode's matrix is larger, row by row
    for q in range(ne - nc):
        envelope += np.abs(net.L[q])
    for i in range(nc):
        envelope[net.node[i], net.node[i]] += np.max(np.abs(net.dslope[i]))
    J = levels(envelope, net.h)
    F = np.empty((n_modes, J + 1, net.n, m))
    VD = np.empty((n_modes, max(ne, 1), m))
    RD = np.empty((n_modes, max(nc, 1), m))
    R = np.empty((n_modes, max(nc, 1), m))
    OUT = np.empty((n_modes, m))
    return J, F, VD, RD, OUT, R, np.zeros(n_modes, dtype=np.bool_)


@njit(cache=True)
def top_tables(As, n, h, J, F):
    """F[j] = the n state rows of exp(As h / 2^j) - I, j = 0..J: a Taylor series at J, then
    squaring (as ``_compiled.tables``), on the state rows alone. The other rows of As
    (the inputs' u' = du; the slopes and offsets constant) square to zero, so those rows
    of exp(As t) - I are As t, and a squaring needs only their nonzero entries."""
    m = As.shape[0]
    lower = [(p, k) for p in range(n, m) for k in range(m) if As[p, k] != 0.0]
    t = h / 2.0**J
    X = As * t
    term = X[:n].copy()
    G = F[J]
    fill2(G, term)
    for q in range(2, 30):
        nxt = np.zeros((n, m))
        for i in range(n):
            for p in range(m):
                a = term[i, p]
                if a != 0.0:
                    for k in range(m):
                        nxt[i, k] += a * X[p, k]
        term = nxt / q
        G += term
        if np.max(np.abs(term)) < 1e-300 or np.max(np.abs(term)) < 1e-18 * np.max(np.abs(G)):
            break
    for j in range(J - 1, -1, -1):
        G, out = F[j + 1], F[j]
        tj = h / 2.0 ** (j + 1)  # the step of level j + 1, squared into level j
        for i in range(n):
            for k in range(m):
                out[i, k] = 2.0 * G[i, k]
            for p in range(n):
                a = G[i, p]
                for k in range(m):
                    out[i, k] += a * G[p, k]
            for p, k in lower:
                out[i, k] += G[i, p] * As[p, k] * tj


@njit(cache=True)
def state(mode, e, net):
    return (mode // net.stride[e]) % net.radix[e]


@njit(cache=True)
def enter(mode, net, tabs):
    """Make mode's tables and rows, unless made already."""
    J, F, VD, RD, OUT, R, ready = tabs
    if ready[mode]:
        return
    nc, ne = net.node.shape[0], net.col.shape[0]
    wcol = net.n + 2 * net.n_in
    As = net.Abar.copy()
    for e in range(nc, ne):
        if state(mode, e, net) == 1:
            As += net.L[e - nc]
    for i in range(nc):
        s = state(mode, i, net)
        if s < net.radix[i] - 1:
            As[net.node[i], net.node[i]] += net.dslope[i, s]
    for i in range(nc):  # the holding force: the node's mass times its acceleration
        fill1(R[mode, i], net.mass[i] * As[net.node[i]])  # without its own (any contact's) force
        for q in range(nc):
            R[mode, i, wcol + q] = 0.0
    for i in range(nc):
        if state(mode, i, net) == net.radix[i] - 1:
            As[net.node[i], :] = 0.0
    top_tables(As, net.n, net.h, J, F[mode])
    for e in range(ne):
        fill1(VD[mode, e], As[net.col[e]])
    for i in range(nc):
        fill1(RD[mode, i], R[mode, i] @ As)
    fill1(OUT[mode], As[net.out_node])
    ready[mode] = True


@njit(cache=True)
def bands(st, sgn, lo, hi, net):
    """Each element's band from its state, direction or side."""
    nc, ne = net.node.shape[0], net.col.shape[0]
    for i in range(nc):
        s = st[i]
        if s == net.radix[i] - 1:  # stuck: the holding force within +-f_s
            lo[i], hi[i] = -net.bound[i], net.bound[i]
        elif sgn[i] > 0:  # sliding in piece s: the speed within its knots
            lo[i], hi[i] = net.knots[i, s], net.knots[i, s + 1]
        else:
            lo[i], hi[i] = -net.knots[i, s + 1], -net.knots[i, s]
    for e in range(nc, ne):
        g = net.gap[e - nc]
        if st[e] == 0:  # open: inside the gap
            lo[e], hi[e] = -g, g
        elif sgn[e] > 0:  # closed, d beyond +g
            lo[e], hi[e] = g, np.inf
        else:
            lo[e], hi[e] = -np.inf, -g


@njit(cache=True)
def _slide(z, i, s, sign, st, sgn, net):
    st[i] = s
    sgn[i] = sign
    z[net.n + 2 * net.n_in + i] = sign * net.force[i, s]


@njit(cache=True)
def _holding(z, mode, i, tabs):
    R = tabs[5]
    s = 0.0
    for j in range(z.shape[0]):
        s += R[mode, i, j] * z[j]
    return s


@njit(cache=True)
def switch(z, mode, st, sgn, lo, hi, net, tabs):
    """Apply the switches due at z (the tick after a crossing) and enter the new mode.

    A stuck contact breaks away into piece 0 in the direction of its holding force when
    that exceeds f_s; a sliding one whose velocity has crossed zero stops, and sticks if
    the holding force is within f_s, else slides the other way (a reversal); one whose
    speed has left its piece moves to the next piece. A link closes on the side its
    deflection has passed +-g, and opens when it comes back inside."""
    nc, ne = net.node.shape[0], net.col.shape[0]
    for i in range(nc):
        S, v = net.radix[i] - 1, z[net.node[i]]
        if st[i] == S:
            r = _holding(z, mode, i, tabs)
            if abs(r) > net.bound[i]:
                _slide(z, i, 0, 1.0 if r > 0 else -1.0, st, sgn, net)
        elif sgn[i] * v < 0.0:
            z[net.node[i]] = 0.0
            r = _holding(z, mode, i, tabs)
            if abs(r) <= net.bound[i]:
                st[i] = S
            else:
                _slide(z, i, 0, 1.0 if r > 0 else -1.0, st, sgn, net)
        else:
            s = st[i]
            while s > 0 and sgn[i] * v < net.knots[i, s]:
                s -= 1
            while sgn[i] * v > net.knots[i, s + 1]:
                s += 1
            _slide(z, i, s, sgn[i], st, sgn, net)
    for e in range(nc, ne):
        d, g, w = z[net.col[e]], net.gap[e - nc], net.n + 2 * net.n_in + e
        if st[e] == 0 and abs(d) > g:
            st[e], sgn[e] = 1, (1.0 if d > 0 else -1.0)
            z[w] = sgn[e] * g
        elif st[e] == 1 and sgn[e] * d < g:
            st[e], z[w] = 0, 0.0
    new = 0
    for e in range(ne):
        new += st[e] * net.stride[e]
    enter(new, net, tabs)
    bands(st, sgn, lo, hi, net)
    return new


@njit(cache=True)
def start(z_init, inputs, net, tabs):
    """The augmented state at the first sample and the elements' states: contacts at rest
    stick if they can, others slide in the piece of their speed; links are open inside
    their gap. Returns (z, st, sgn, lo, hi, mode)."""
    nc, ne, m = net.node.shape[0], net.col.shape[0], net.Abar.shape[0]
    n, n_in = net.n, net.n_in
    z = np.zeros(m)
    fill1(z[:n], z_init)
    for q in range(n_in):
        z[n + q] = inputs[0, q]
    st = np.zeros(max(ne, 1), dtype=np.int64)
    sgn = np.ones(max(ne, 1))
    mode = 0
    for i in range(nc):
        v = z[net.node[i]]
        if v == 0.0:
            st[i] = net.radix[i] - 1
        else:  # piece 0 in the right direction; switch moves it to its piece
            _slide(z, i, 0, 1.0 if v > 0 else -1.0, st, sgn, net)
        mode += st[i] * net.stride[i]
    lo, hi = np.empty(max(ne, 1)), np.empty(max(ne, 1))
    enter(mode, net, tabs)
    mode = switch(z, mode, st, sgn, lo, hi, net, tabs)  # break away, pieces, links closed
    return z, st, sgn, lo, hi, mode
