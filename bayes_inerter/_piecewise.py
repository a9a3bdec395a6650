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

from ._kernel import Net, RichShape
from .friction import PiecewiseLinear
from .network import CompiledNetwork
from .network.compile import chain_state_space

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
    """The contacts' nodes, masses, bounds, knots, forces a_s and diagonal changes."""
    nodes = [i for i, law in enumerate(laws) if law is not None]
    pieces = [len(laws[i].speeds) for i in nodes]
    width = max(pieces, default=1)
    knots = np.full((max(len(nodes), 1), width + 1), np.inf)
    force = np.zeros((max(len(nodes), 1), width))
    dslope = np.zeros((max(len(nodes), 1), width))
    for k, i in enumerate(nodes):
        speeds, a, slopes = laws[i].segments()
        knots[k, :len(speeds)] = speeds
        force[k, :len(a)] = a
        dslope[k, :len(a)] = -(slopes - laws[i].c) / compiled.masses[i]
    mass = compiled.masses[nodes].astype(float)
    bound = np.array([laws[i].f_s for i in nodes], dtype=float)
    return np.array(nodes, dtype=np.int64), pieces, mass, bound, knots, force, dslope


def _link_parts(compiled, n):
    """Each gap link's part of A (its spring and damper, as state_space adds them)."""
    N, position = compiled.n_nodes, n == compiled.n_states(position=True)
    gaps = np.flatnonzero(compiled.link_gap > 0)
    zero = chain_state_space(compiled.masses, 0 * compiled.link_c, 0 * compiled.link_k, position=position)[0]
    parts = []
    for j in gaps:
        c, k = np.zeros_like(compiled.link_c), np.zeros_like(compiled.link_k)
        c[j], k[j] = compiled.link_c[j], compiled.link_k[j]
        parts.append(chain_state_space(compiled.masses, c, k, position=position)[0] - zero)
    return gaps, [N + j for j in gaps], parts


def network_arrays(compiled: CompiledNetwork, A, B, h: float, out_node: int = 0):
    """(shape, net): the kernel's shape and arrays for the network, its linear part
    x' = A x + B u given with every link closed and each node's viscous friction in."""
    n = A.shape[0]
    B = np.asarray(B, dtype=float).reshape(n, -1)
    n_in = B.shape[1]
    laws = _laws(compiled)
    nodes, pieces, mass, bound, knots, force, dslope = _contacts(compiled, laws)
    gaps, dcols, parts = _link_parts(compiled, n)
    nc, nl = len(nodes), len(gaps)
    wcol = n + 2 * n_in
    m = wcol + nc + nl
    Abar = np.zeros((m, m))
    Abar[:n, :n] = A - sum(parts, np.zeros_like(A))
    Abar[:n, n:n + n_in] = B
    Abar[n:n + n_in, n + n_in:wcol] = np.eye(n_in)
    Abar[nodes, wcol + np.arange(nc)] = -1.0 / mass
    L = np.zeros((max(nl, 1), m, m))
    for q, (part, col) in enumerate(zip(parts, dcols)):
        L[q, :n, :n] = part
        L[q, :n, wcol + nc + q] = -part[:, col]  # the offset: the spring acts on d - w
    radix = np.array([p + 1 for p in pieces] + [2] * nl, dtype=np.int64)  # the pieces, stuck; open, closed
    stride = np.cumprod(np.concatenate([[1], radix])).astype(np.int64)[:nc + nl]
    pattern = (Abar != 0) | (L != 0).any(axis=0)
    pattern[nodes, nodes] = True  # the pieces' slopes
    net = Net(Abar, L, nodes, mass, bound, knots, force, dslope, np.array(list(nodes) + dcols, dtype=np.int64),
              np.array([compiled.link_gap[j] for j in gaps] or [0.0]), radix, stride, n, n_in, int(out_node),
              float(h))
    shape = RichShape(n, n_in, tuple(int(i) for i in nodes), int(out_node), pattern.tobytes(), tuple(pieces),
                      tuple(int(c) for c in dcols))
    return shape, net
