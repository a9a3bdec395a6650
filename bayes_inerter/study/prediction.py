"""Leave-one-frequency-out prediction: does the model predict a drive frequency it was
not fitted at?

A setting's records at two frequencies are fitted together (the joint model,
``inference.fit_joint(all_draws=True)``: one b, shared frictions and deformations); the
third record's low-passed acceleration is then predicted from its own measured force,
draw by draw. :func:`predict_record` gives the 94 % predictive band (each draw's
simulation plus a normal noise draw whose sd is the fitted records' residual sd about
their median simulation: **assumption**, the held-out record's noise and misfit are, in
m/s^2, the fitted ones'),
how much of the held-out record (its likelihood window, low-passed) the band covers,
and phi (eq. 5 on the low-passed record) of the median prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..inference.posterior import friction_law
from ..inference.posterior.model import PosteriorModel

__all__ = ["Prediction", "predict_record", "residual_sd", "LEVEL"]

#: The predictive band's probability.
LEVEL = 0.94


@dataclass(frozen=True)
class Prediction:
    """The held-out record's prediction (see module docstring): ``time`` and
    ``measured`` (low-passed, in the window), the band's ``lo``, ``median``, ``hi``
    (noise included) and ``lo_model``, ``hi_model`` (the parameters' spread alone);
    ``coverage`` and ``coverage_model``: the share of the window's samples inside each;
    ``phi``: eq. 5 of the median simulation; ``noise_sd``: the noise added."""

    time: np.ndarray
    measured: np.ndarray
    lo: np.ndarray
    median: np.ndarray
    hi: np.ndarray
    lo_model: np.ndarray
    hi_model: np.ndarray
    coverage: float
    coverage_model: float
    phi: float
    noise_sd: float
    draws: int


#: The likelihood's own parameters (``LikelihoodSettings.hyper_names``), which a
#: simulation does not use, at values inside their priors: the time-domain residual's
#: sigma and rho, the harmonic likelihoods' discrepancy and gain, the channels' delay.
UNUSED = {"sigma": 1.0, "rho": 0.0, "tau": 1.0, "alpha": 0.0, "gain": 1.0, "delay": 0.0, "law": friction_law.SD}


def _theta(model: PosteriorModel, values: dict) -> np.ndarray:
    """``model``'s theta from parameter values by name (b, the shared ones); the
    likelihood's own entries, which a simulation does not use, at :data:`UNUSED`'s."""
    out = []
    own = set(model.names[model.n_phys:])
    for name in model.names:
        v = UNUSED[name] if name in own else values.get(name)
        if v is None:
            raise ValueError(f"the draws have no {name!r}")
        out.append(np.log(v) if model.all_priors[name].log_scale else v)
    return np.array(out, dtype=float)


def _values(draws: dict, setting: str, i: int) -> dict:
    """Draw ``i`` of a joint fit's draws (flattened), with b its setting's."""
    got = {k: float(np.ravel(v)[i]) for k, v in draws.items()}
    got["b"] = got[f"b_{setting}"]
    return got


def residual_sd(models: list[PosteriorModel], draws: dict, setting: str, picks) -> float:
    """The root mean square over ``models``' windows (the fitted records) of the
    low-passed residual of the median simulation over the draws ``picks``: the noise and
    misfit the fit leaves where it was fitted."""
    sq, n = 0.0, 0
    for m in models:
        w = m.window
        sims = np.array([m.simulate_lp(_theta(m, _values(draws, setting, int(i))))[w] for i in picks])
        r = np.median(sims, axis=0) - m.measured_lp[w]
        sq, n = sq + float(np.sum(r * r)), n + len(w)
    return float(np.sqrt(sq / n))


def predict_record(held_out: PosteriorModel, fitted: list[PosteriorModel], draws: dict, setting: str, *,
                   n_draws: int = 200, rng: np.random.Generator) -> Prediction:
    """Predict ``held_out``'s low-passed acceleration from ``n_draws`` of a joint fit's
    ``draws`` (name -> array, every sampled parameter; ``fitted``: the records it was
    fitted to, for the noise's sd) of flywheel ``setting``; see module docstring."""
    if not (isinstance(n_draws, int) and n_draws >= 20):
        raise ValueError(f"n_draws must be a whole number of at least 20, got {n_draws!r}")
    total = np.ravel(draws[f"b_{setting}"]).size
    picks = rng.choice(total, size=min(n_draws, total), replace=False)
    w = held_out.window
    sims = np.array([held_out.simulate_lp(_theta(held_out, _values(draws, setting, int(i))))[w] for i in picks])
    sd = residual_sd(fitted, draws, setting, picks)
    noisy = sims + sd * rng.standard_normal(sims.shape)
    q = [(1 - LEVEL) / 2, 0.5, (1 + LEVEL) / 2]
    lo, med, hi = np.quantile(noisy, q, axis=0)
    lo_m, hi_m = np.quantile(sims, [q[0], q[2]], axis=0)
    measured = held_out.measured_lp[w]
    full = np.zeros(len(held_out.record.time))
    full[w] = np.median(sims, axis=0)
    return Prediction(held_out.record.time[w], measured, lo, med, hi, lo_m, hi_m,
                      float(np.mean((measured >= lo) & (measured <= hi))),
                      float(np.mean((measured >= lo_m) & (measured <= hi_m))), held_out.phi(full), sd, len(picks))
