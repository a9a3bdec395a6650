"""Warnings about how a fit ended, beyond convergence: what a user must read before
trusting an interval.

- **b at a prior bound**: an end of an inertance's 94 % HDI lies within
  :data:`BOUND_LOG_TOL` (in log, about 1 %) of its prior's bound, or at least
  :data:`BOUND_SHARE` of its kept draws do. The data
  then push b out of the prior (a wrong unit or mass, another device), and its interval
  is the prior's wall, not a measurement. Only the inertances are checked: the
  parameters the records leave open (nut stiffness, bearing damping, the shares) are
  expected against their bounds.
- **poor fit**: the posterior median of phi (the paper's fit accuracy) below
  :data:`PHI_WARNING`: the model reproduces less than half of the record, and its
  intervals describe the model, not the device.

Both thresholds are assumptions of this package, module constants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["EndWarning", "end_state_warnings", "BOUND_LOG_TOL", "BOUND_SHARE", "PHI_WARNING"]

BOUND_LOG_TOL = 0.01
BOUND_SHARE = 0.03
PHI_WARNING = 0.5


@dataclass(frozen=True)
class EndWarning:
    """A warning about one summary row: the row's ``name``, a short ``flag`` for the
    summary's flag column and a one-line ``message``."""

    name: str
    flag: str
    message: str


def _inertances(names) -> list[int]:
    return [i for i, n in enumerate(names) if n == "b" or n.startswith("b_")]


def _hdi(x) -> tuple[float, float]:
    import warnings

    import arviz as az

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lo, hi = az.hdi(np.asarray(x), hdi_prob=0.94)
    return float(lo), float(hi)


def end_state_warnings(model, sample) -> list[EndWarning]:
    """The warnings of a finished fit's kept draws (``results.PosteriorSample``)."""
    out = []
    bounds = np.asarray(model.bounds(), dtype=float)
    for i in _inertances(sample.names):
        if not model.all_priors[sample.names[i]].log_scale:
            continue
        x = sample.theta[..., i].ravel()
        lo, hi = bounds[i]
        h_lo, h_hi = _hdi(x)
        for side, share, near, bound in (("lower", np.mean(x <= lo + BOUND_LOG_TOL), h_lo <= lo + BOUND_LOG_TOL, lo),
                                         ("upper", np.mean(x >= hi - BOUND_LOG_TOL), h_hi >= hi - BOUND_LOG_TOL, hi)):
            if share >= BOUND_SHARE or near:
                out.append(EndWarning(sample.names[i], f"at {side} prior bound",
                                      f"the 94 % interval of {sample.names[i]} reaches its prior's {side} bound "
                                      f"{np.exp(bound):g} kg: the data push it out of the prior; check "
                                      "the record's units and masses, or widen the prior"))
    phi = float(np.median(sample.phi))
    if not phi >= PHI_WARNING:
        out.append(EndWarning("phi", "poor fit",
                              f"the model reproduces the record poorly (median phi {phi:.1%}, below "
                              f"{PHI_WARNING:.0%}): its intervals describe the model, not the device"))
    return out
