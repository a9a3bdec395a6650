"""Networks as cascades of two-port blocks, and their frequency response."""

from __future__ import annotations

from dataclasses import dataclass
from functools import reduce

import numpy as np

from .blocks import Block

__all__ = ["Network", "cascade", "abcd", "accel_response"]


@dataclass(frozen=True)
class Network:
    """An ordered chain of two-port blocks, from the driven terminal to the far end.

    The far end is free (no force passes out of the last block); every connection to
    ground is a shunt block (inerter, friction) inside the chain.
    """

    blocks: tuple[Block, ...]
    name: str = "network"

    def __post_init__(self) -> None:
        blocks = tuple(self.blocks)
        for blk in blocks:
            if not isinstance(blk, Block):
                raise ValueError(f"a network holds blocks, got {blk!r}")
        if not blocks:
            raise ValueError("a network needs at least one block")
        object.__setattr__(self, "blocks", blocks)


def cascade(*parts: Block | Network, name: str = "network") -> Network:
    """Chain blocks (or whole networks) in order into one network."""
    blocks: list[Block] = []
    for part in parts:
        blocks.extend(part.blocks if isinstance(part, Network) else [part])
    return Network(tuple(blocks), name)


def abcd(network: Network, s: np.ndarray) -> np.ndarray:
    """Transmission matrix of the whole chain at complex frequencies s, shape (len(s), 2, 2)."""
    s = np.atleast_1d(np.asarray(s, dtype=complex))
    return reduce(np.matmul, (blk.abcd(s) for blk in network.blocks))


def accel_response(network: Network, omega: np.ndarray) -> np.ndarray:
    """Driving-point accelerance a1/F1 (1/kg) at angular frequencies omega (rad/s).

    With the far end free (F2 = 0): v1 = T22 v2 and F1 = T12 v2, so
    a1 / F1 = s T22 / T12. Only the linear part of each block enters (friction blocks
    contribute their viscous part: "Coulomb terms off").
    """
    s = 1j * np.atleast_1d(np.asarray(omega, dtype=float))
    t = abcd(network, s)
    return s * t[:, 1, 1] / t[:, 0, 1]
