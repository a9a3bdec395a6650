"""Compile a network of blocks into flat arrays: nodes, links, contacts, state space.

Walking the chain: shunt blocks (mass, inerter, friction) attach to the current node; a
:class:`Deformation` closes the current node and opens a new one behind it. Blocks with
no deformation between them therefore move together (a rigid chain is one body).

State vector (n = 2 N - 1 for N nodes, plus one optional entry)::

    x = [v_0 ... v_{N-1}, d_0 ... d_{N-2}, (x_0)]

v_i: node velocities (m/s); d_j = x_j - x_{j+1}: deflection of link j (m); x_0: the
driven node's position (m), only when asked for (it feeds back into nothing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..friction import FrictionLaw
from .blocks import Deformation, Friction, Inerter, Mass
from .symbolic import Linear
from .twoport import Network

__all__ = ["CompiledNetwork", "compile_network", "chain_state_space"]


@dataclass(frozen=True)
class CompiledNetwork:
    """The flat description of a chain network (see module docstring).

    Attributes
    ----------
    masses : shape (N,), kg; mass plus inertance of each node.
    link_c, link_k : shape (N - 1,), N s/m and N/m.
    link_gap : shape (N - 1,), m; half-width of each link's dead zone (0: none).
    laws : per node, the friction laws acting between it and ground.
    """

    masses: np.ndarray
    link_c: np.ndarray
    link_k: np.ndarray
    link_gap: np.ndarray
    laws: tuple[tuple[FrictionLaw, ...], ...]
    name: str = "network"

    @property
    def n_nodes(self) -> int:
        return len(self.masses)

    def n_states(self, position: bool = False) -> int:
        return 2 * self.n_nodes - 1 + int(position)

    @property
    def viscous(self) -> np.ndarray:
        """Sum of the laws' viscous coefficients per node, N s/m (linear forms for a
        network on symbolic parameters)."""
        return np.array([sum(law.viscous for law in node) for node in self.laws], dtype=self.masses.dtype)

    @property
    def all_coulomb(self) -> bool:
        """True when the Coulomb kernel (the likelihood's) applies: Coulomb laws only, no
        dead zone. Other piecewise-linear laws and dead zones take the exact kernel's
        general form (``simulate``)."""
        laws_ok = all(law.is_coulomb for node in self.laws for law in node)
        return laws_ok and not np.any(self.link_gap > 0)

    @property
    def coulomb_bounds(self) -> np.ndarray:
        """Set-valued bound at rest per node (sum of the laws' bounds), N (linear forms
        for a network on symbolic parameters)."""
        return np.array([sum(law.bound for law in node) for node in self.laws], dtype=self.masses.dtype)

    def state_space(self, *, viscous: bool = True, position: bool = False):
        """Linear part as x' = A x + B F (force on node 0), shape (n, n) and (n,).

        Links are taken closed (no dead zone). With ``viscous`` the friction laws'
        linear parts are in A; without, all friction is left to the caller.
        """
        return chain_state_space(self.masses, self.link_c, self.link_k, self.viscous if viscous else None,
                                 position=position)


def chain_state_space(masses, link_c, link_k, viscous=None, *, position: bool = False):
    """:meth:`CompiledNetwork.state_space` from the arrays alone (``viscous``: the
    per-node viscous coefficients, or None to leave friction out)."""
    masses = np.ascontiguousarray(masses, dtype=float)
    use = viscous is not None
    visc = np.ascontiguousarray(viscous, dtype=float) if use else np.zeros(len(masses))
    return _state_space(masses, np.ascontiguousarray(link_c, dtype=float), np.ascontiguousarray(link_k, dtype=float),
                        visc, use, bool(position))


@njit(cache=True)
def _state_space(masses, link_c, link_k, viscous, use_viscous, position):
    """The state space's arithmetic (compiled: the likelihood forms it at every evaluation)."""
    N = masses.shape[0]
    n = 2 * N - 1 + (1 if position else 0)
    A = np.zeros((n, n))
    B = np.zeros(n)
    inv_m = 1.0 / masses
    if use_viscous:
        for i in range(N):
            A[i, i] -= viscous[i] * inv_m[i]
    for j in range(N - 1):
        c, k, d = link_c[j], link_k[j], N + j
        # T_j = c (v_j - v_{j+1}) + k d_j pulls node j back and node j+1 forward
        for node, sign in ((j, -1.0), (j + 1, 1.0)):
            A[node, j] += sign * c * inv_m[node]
            A[node, j + 1] -= sign * c * inv_m[node]
            A[node, d] += sign * k * inv_m[node]
        A[d, j] = 1.0
        A[d, j + 1] = -1.0
    if position:
        A[n - 1, 0] = 1.0
    B[0] = inv_m[0]
    return A, B


def compile_network(network: Network) -> CompiledNetwork:
    """Flatten a :class:`Network` into nodes, links and contacts. A network built on
    symbolic parameters (``network.symbolic``) compiles into arrays of their linear
    forms (its nodes' masses unchecked: they have no number yet)."""
    masses: list[float] = [0.0]
    laws: list[list[FrictionLaw]] = [[]]
    link_c: list[float] = []
    link_k: list[float] = []
    link_gap: list[float] = []
    for blk in network.blocks:
        if isinstance(blk, Mass):
            masses[-1] += blk.m
        elif isinstance(blk, Inerter):
            masses[-1] += blk.b
        elif isinstance(blk, Friction):
            laws[-1].append(blk.law)
        elif isinstance(blk, Deformation):
            link_c.append(blk.c)
            link_k.append(blk.k)
            link_gap.append(blk.backlash.gap if blk.backlash else 0.0)
            masses.append(0.0)
            laws.append([])
        else:
            raise ValueError(f"cannot compile block {blk!r}")
    symbolic = any(isinstance(v, Linear) for v in (*masses, *link_c, *link_k))
    for i, m in enumerate(masses):
        if not symbolic and m <= 0:
            raise ValueError(
                f"network {network.name!r}: node {i} has no mass or inertance "
                "(every node between deformations needs a Mass or an Inerter)"
            )
    kind = object if symbolic else float  # symbolic: arrays of ``symbolic.Linear``
    return CompiledNetwork(
        masses=np.array(masses, dtype=kind),
        link_c=np.array(link_c, dtype=kind),
        link_k=np.array(link_k, dtype=kind),
        link_gap=np.array(link_gap, dtype=float),
        laws=tuple(tuple(node) for node in laws),
        name=network.name,
    )
