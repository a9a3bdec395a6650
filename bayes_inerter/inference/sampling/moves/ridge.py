"""A jump along the nut's ridge (:class:`NutRidgeMove`), for walkers that move in theta.

The nut's deformation (c_n + k_n / s) sits in series with the inertance b s; at the
drive frequencies the pair acts as a damper in series with an inerter of
1 / b_app = 1 / b - k_n / c_n^2 (``device.apparent_inertance``). The records fix b_app
tightly and leave k_n free over decades (a plateau of the log posterior, then a cliff):
a ridge, curved in the sampled log coordinates, that the ensemble moves cross only by
creeping (docs/inference.md).

Each walker draws a step delta of log k_n from a zero-mean normal whose sd is itself
drawn log-uniformly between ``scale_min`` and ``scale_max`` (a symmetric mixture: short
steps near the cliff, long ones across the plateau) and moves every inertance so that
1 / b - k_n / c_n^2 stays as it was:

    log k_n' = log k_n + delta,    1 / b' = 1 / b + (k_n' - k_n) / c_n^2.

The map is its own inverse with -delta, and its Jacobian in the sampled coordinates
(log b, log k_n) is the product of b' / b over the inertances, which enters the
acceptance ratio (Green 1995). So the move leaves any posterior invariant, whatever
the model: the ridge only decides how often it is accepted. 1 / b' is always positive
(1 / b_app > 0 and k_n' > 0 wherever the step starts from a point with b_app > 0).
"""

from __future__ import annotations

import numpy as np
from emcee.moves import MHMove

__all__ = ["NutRidgeMove", "ridge_indices"]


def ridge_indices(names, log_scale) -> tuple[int, int, list[int]] | None:
    """(index of k_n, index of c_n, indices of the inertances) in a parameter vector
    named ``names``, or None if it has no nut ridge (a model without b, k_n or c_n, or
    with any of them not sampled in log scale)."""
    names = list(names)
    b_idx = [i for i, n in enumerate(names) if n == "b" or n.startswith("b_")]
    if "k_n" not in names or "c_n" not in names or not b_idx:
        return None
    k, c = names.index("k_n"), names.index("c_n")
    if not all(log_scale[i] for i in [k, c, *b_idx]):
        return None
    return k, c, b_idx


class NutRidgeMove(MHMove):
    """Jump along log k_n keeping every 1 / b - k_n / c_n^2 (see the module docstring).

    Parameters
    ----------
    k_index, c_index : positions of log k_n and log c_n in the sampled vector.
    b_indices : positions of the log inertances (one per record, or per setting).
    scale_min, scale_max : range (natural log units) of the step's sd, drawn
        log-uniformly per walker and step. Defaults 0.1 and 4 (a step of a few
        percent to about two decades of k_n).
    """

    def __init__(self, k_index: int, c_index: int, b_indices, *, scale_min: float = 0.1, scale_max: float = 4.0):
        if not 0 < scale_min <= scale_max:
            raise ValueError(f"ridge step sds must satisfy 0 < min <= max, got {scale_min}, {scale_max}")
        self.k_index, self.c_index = int(k_index), int(c_index)
        self.b_indices = np.asarray(b_indices, dtype=int)
        if self.b_indices.size == 0:
            raise ValueError("the ridge move needs at least one inertance")
        self.scale_min, self.scale_max = float(scale_min), float(scale_max)
        super().__init__(self._propose)

    def _propose(self, coords, random):
        coords = np.asarray(coords, dtype=float)
        n = len(coords)
        sd = np.exp(random.uniform(np.log(self.scale_min), np.log(self.scale_max), size=n))
        delta = sd * random.randn(n)
        q = coords.copy()
        log_k = coords[:, self.k_index]
        inv_c2 = np.exp(-2.0 * coords[:, self.c_index])
        dkappa = (np.exp(log_k + delta) - np.exp(log_k)) * inv_c2
        log_b = coords[:, self.b_indices]
        inv_b = np.exp(-log_b) + dkappa[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            new_log_b = -np.log(inv_b)  # inv_b > 0 on the ridge; NaN elsewhere is rejected below
        q[:, self.k_index] = log_k + delta
        q[:, self.b_indices] = new_log_b
        factors = np.sum(new_log_b - log_b, axis=1)  # log |Jacobian|: sum of log(b' / b)
        bad = ~np.all(np.isfinite(q), axis=1)
        q[bad] = coords[bad]
        factors[bad] = -np.inf
        return q, factors
