"""Convergence diagnostics of an emcee chain (arviz's R-hat and ESS, walkers as chains)."""

from __future__ import annotations

import warnings

import numpy as np

from ... import arviz_import

__all__ = ["rhat_ess"]


def rhat_ess(chain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rank-normalised split R-hat and bulk ESS per parameter.

    ``chain`` has emcee's shape (steps, walkers, ndim). The walkers are treated as chains;
    they are not independent (each move uses the others), which arviz assumes they are:
    read R-hat as a check that no walker is stuck apart, and take the autocorrelation
    time from emcee.
    """
    az = arviz_import.module()

    steps, walkers, ndim = chain.shape
    if steps < 4:
        return np.full(ndim, np.inf), np.zeros(ndim)
    data = np.transpose(chain, (1, 0, 2))  # (chain, draw, ndim)
    rhat = np.empty(ndim)
    ess = np.empty(ndim)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(ndim):
            rhat[i] = float(az.rhat(data[:, :, i]))
            ess[i] = float(az.ess(data[:, :, i], method="bulk"))
    return rhat, ess
