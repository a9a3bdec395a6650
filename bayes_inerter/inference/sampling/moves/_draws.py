"""The check the fitted moves share: whether draws can define a proposal."""

from __future__ import annotations

import numpy as np


def usable_draws(draws) -> np.ndarray | None:
    """``draws`` as an (n, ndim) float array if a proposal can be fitted to them (finite,
    more draws than dimensions); else None."""
    draws = np.asarray(draws, dtype=float)
    if draws.ndim != 2 or len(draws) <= draws.shape[1] or not np.all(np.isfinite(draws)):
        return None
    return draws
