"""The exact kernel's arrays for a network with piecewise-linear friction and dead zones.

Private; ``simulate`` runs these networks through ``_kernel.rich_kernel_for``. A node's
friction laws are summed into one piecewise-linear law (``PiecewiseLinear.total``); a
node with any force or static bound is a contact. A link with a gap (``Backlash``) is a
plain dead zone: no force while |d| < g; outside, its spring and damper act on d -+ g and
the relative velocity, k (d - sgn(d) g) + c (v_j - v_j+1). Closing the gap is not
smoothed (``_stiff`` ramps the damper in over 10 % of the gap; see docs/simulator.md).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernel import Net, RichShape
from ..friction import PiecewiseLinear
from ..network import CompiledNetwork

__all__ = ["applies", "network_arrays"]


def _laws(compiled: CompiledNetwork):
    """Per node, its friction laws' sum as one piecewise-linear law (None: no contact)."""
    out = []
    for laws in compiled.laws:
        law = PiecewiseLinear.total(laws) if laws else None
        out.append(law if law is not None and (law.f_s > 0 or max(law.forces) > 0) else None)
    return out


def applies(compiled: CompiledNetwork) -> bool:
    """True when every friction law has a piecewise-linear form (the exact kernel then
    simulates the network, dead zones included)."""
    return all(PiecewiseLinear.total(laws) is not None for laws in compiled.laws if laws)


def _contacts(compiled, laws):
    """The contacts' nodes, pieces, masses, bounds, knots, forces a_s and diagonal changes
    (the arithmetic of ``PiecewiseLinear.segments`` on floats: these are a few numbers)."""
    nodes = [i for i, law in enumerate(laws) if law is not None]
    pieces = [len(laws[i].speeds) for i in nodes]
    width, rows = max(pieces, default=1), max(len(nodes), 1)
    knots, force, dslope = np.full((rows, width + 1), np.inf), np.zeros((rows, width)), np.zeros((rows, width))
    for k, i in enumerate(nodes):
        law, mass = laws[i], compiled.masses[i]
        v, f = law.speeds, law.forces
        slopes = [(f[s + 1] - f[s]) / (v[s + 1] - v[s]) for s in range(len(v) - 1)] + [law.c]
        knots[k, :len(v)] = v
        force[k, :len(v)] = [f[s] - slopes[s] * v[s] for s in range(len(v))]
        dslope[k, :len(v)] = [-(c - law.c) / mass for c in slopes]
    mass = compiled.masses[nodes].astype(float)
    bound = np.array([laws[i].f_s for i in nodes], dtype=float)
    return np.array(nodes, dtype=np.int64), pieces, mass, bound, knots, force, dslope


@njit(cache=True)
def _assemble(A, B, nodes, mass, gaps, link_c, link_k, masses):
    """The augmented matrix with every gap link open, what closing each adds (its spring
    and damper, T = c (v_j - v_j+1) + k (d_j - w) pulling node j back and node j + 1
    forward, as ``chain_state_space`` adds them, w its offset), and the pattern of them
    all. Compiled: a simulation forms them at every call."""
    n, n_in, nc, nl, N = A.shape[0], B.shape[1], nodes.shape[0], gaps.shape[0], masses.shape[0]
    wcol = n + 2 * n_in
    m = wcol + nc + nl
    Abar, L = np.zeros((m, m)), np.zeros((max(nl, 1), m, m))
    for i in range(n):  # element by element: an array assigned to a slice costs seconds to compile
        for k in range(n):
            Abar[i, k] = A[i, k]
        for q in range(n_in):
            Abar[i, n + q] = B[i, q]
    for q in range(nl):
        j = gaps[q]
        for node, sign in ((j, -1.0), (j + 1, 1.0)):
            c, k = sign * link_c[j] / masses[node], sign * link_k[j] / masses[node]
            L[q, node, j] += c
            L[q, node, j + 1] -= c
            L[q, node, N + j] += k
            L[q, node, wcol + nc + q] -= k
        for i in range(n):
            for k in range(n):
                Abar[i, k] -= L[q, i, k]
    for q in range(n_in):
        Abar[n + q, n + n_in + q] = 1.0
    pattern = Abar != 0
    for i in range(nc):
        Abar[nodes[i], wcol + i] = -1.0 / mass[i]
        pattern[nodes[i], wcol + i] = pattern[nodes[i], nodes[i]] = True  # the pieces' slopes
    for q in range(nl):
        pattern |= L[q] != 0
    return Abar, L, pattern


_NO_GAPS, _NO_LINKS = np.zeros(0, dtype=np.int64), np.zeros(0)


def augmented(A, B, nodes, mass):
    """The kernel's augmented matrix for a network without gaps: z = [x, u, du, w] (see
    ``_kernel``), w the contacts' Coulomb forces acting on their ``nodes`` of ``mass``
    (kg). :func:`_assemble`'s matrix with no gap links, so the two kernels' matrices are
    built in one place."""
    return _assemble(A, B, nodes, mass, _NO_GAPS, _NO_LINKS, _NO_LINKS, _NO_LINKS)[0]


def network_arrays(compiled: CompiledNetwork, A, B, h: float, out_node: int = 0):
    """(shape, net): the kernel's shape and arrays for the network, its linear part
    x' = A x + B u given with every link closed and each node's viscous friction in."""
    n = A.shape[0]
    B = np.ascontiguousarray(B, dtype=float).reshape(n, -1)
    laws = _laws(compiled)
    nodes, pieces, mass, bound, knots, force, dslope = _contacts(compiled, laws)
    gaps = np.flatnonzero(compiled.link_gap > 0)
    Abar, L, pattern = _assemble(np.ascontiguousarray(A, dtype=float), B, nodes, mass, gaps, compiled.link_c,
                                 compiled.link_k, compiled.masses)
    dcols = [compiled.n_nodes + int(j) for j in gaps]
    radix = np.array([p + 1 for p in pieces] + [2] * len(gaps), dtype=np.int64)  # the pieces, stuck; open, closed
    stride = np.cumprod(np.concatenate(([1], radix))).astype(np.int64)[:len(radix)]
    net = Net(Abar, L, nodes, mass, bound, knots, force, dslope, np.array(list(nodes) + dcols, dtype=np.int64),
              compiled.link_gap[gaps] if len(gaps) else np.zeros(1), radix, stride, n, B.shape[1], int(out_node),
              float(h))
    shape = RichShape(n, B.shape[1], tuple(int(i) for i in nodes), int(out_node), pattern.tobytes(), tuple(pieces),
                      tuple(dcols))
    return shape, net
