"""From a finished chain to arviz's InferenceData, a summary table and predictive draws.

- burn-in: the chain's warm-up (``SamplerRun.warmup``: its transient, the steps before
  its walkers reach equilibrium, or the convergence rule's warm-up share of it, whichever
  is longer) and 2 x the largest autocorrelation time after it (or half the chain if tau
  is not estimable); thinning: half the smallest tau;
- the posterior (values in SI units, not logs) and phi, the fit accuracy, for every kept
  draw; sample_stats holds the log posterior;
- for at most ``max_draws`` of those draws (further thinned): the pointwise
  log-likelihood (so models compare by LOO) and the posterior predictive acceleration on
  the likelihood's grid (simulation plus AR(1) noise); observed_data is the low-passed
  measured acceleration on that grid.

Summary columns are written by this package from arviz's numbers, so they do not change
with the arviz line: name, kind (sampled, derived, or phi's fit accuracy), mean, sd,
hdi_3%, hdi_97%, r_hat, ess_bulk, ess_tail, and flag (empty, or the flags of the
warnings of :mod:`.end_state` that name that row).
"""

from __future__ import annotations

import csv
import math
import warnings
from dataclasses import dataclass

import numpy as np

from ... import arviz_import
from ..posterior.harmonic import at_times
from ..posterior.model import PosteriorModel

__all__ = ["PosteriorSample", "ar1_noise", "loo_data", "posterior_sample", "contraction", "to_inference_data",
           "summary_rows", "write_summary", "loo_summary", "write_loo", "LOO_FILE", "SUMMARY_COLUMNS", "NUMBER_COLUMNS",
           "MAX_DRAWS", "every_nth", "hdi", "HDI_PROB"]

#: The probability of the highest-density intervals the package reports (the summaries'
#: hdi_3% and hdi_97%).
HDI_PROB = 0.94


def hdi(x, prob: float = HDI_PROB) -> tuple[float, float]:
    """The ``prob`` highest-density interval of the draws ``x`` (any shape, flattened),
    arviz's, as two floats."""
    az = arviz_import.module()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lo, hi = az.hdi(np.ravel(np.asarray(x, dtype=float)), hdi_prob=prob)
    return float(lo), float(hi)


def every_nth(thin: int) -> str:
    """Words for keeping every ``thin``-th draw: "every step", "every 2nd step", ..."""
    if thin == 1:
        return "every step"
    suffix = "th" if 10 <= thin % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(thin % 10, "th")
    return f"every {thin}{suffix} step"

SUMMARY_COLUMNS = ("name", "kind", "mean", "sd", "hdi_3%", "hdi_97%", "r_hat", "ess_bulk", "ess_tail", "flag")
#: The columns that hold numbers.
NUMBER_COLUMNS = SUMMARY_COLUMNS[2:-1]
MAX_DRAWS = 600  # draws that get a simulation for log-likelihood and predictive
#: A fit's PSIS-LOO (:func:`loo_summary`), beside its summary.
LOO_FILE = "loo.json"


@dataclass
class PosteriorSample:
    """Kept draws after burn-in: sampled values (chain=walker, draw, name), the raw
    friction parameters derived from sums and shares (if split), and phi."""

    names: list
    values: np.ndarray  # (walkers, draws, ndim) in SI units (shares and rho as is)
    theta: np.ndarray  # (walkers, draws, ndim) as sampled
    derived: dict  # name -> (walkers, draws)
    phi: np.ndarray  # (walkers, draws)
    lp: np.ndarray  # (walkers, draws)
    burn: int
    thin: int

    def as_dict(self) -> dict:
        out = {n: self.values[:, :, i] for i, n in enumerate(self.names)}
        out.update(self.derived)
        out["phi"] = self.phi
        return out


def _derived(model: PosteriorModel, values: np.ndarray) -> dict:
    if not model.derived_names:
        return {}
    return model.derived({n: values[..., i] for i, n in enumerate(model.names)})


def posterior_sample(model: PosteriorModel, run) -> PosteriorSample:
    """Kept draws of a finished :class:`..sampling.sampler.SamplerRun` (in theta, whatever
    coordinates its walkers moved in)."""
    sampler, tau = run.sampler, run.tau
    n, skip = sampler.iteration, run.warmup
    if np.all(np.isfinite(tau)) and skip + 2 * np.max(tau) < n - 10:
        burn = skip + int(2 * np.max(tau))
        thin = max(1, int(0.5 * np.min(tau)))
    else:
        burn, thin = max(skip, n // 2), 1
    chain = run.chain(discard=burn, thin=thin)  # (draws, walkers, ndim)
    blobs = sampler.get_blobs(discard=burn, thin=thin)
    lp = run.log_prob(discard=burn, thin=thin)
    theta = np.transpose(chain, (1, 0, 2))
    values = model.to_values(theta)
    return PosteriorSample(
        names=list(model.names), values=values, theta=theta, derived=_derived(model, values),
        phi=np.asarray(blobs, dtype=float).T, lp=lp.T, burn=burn, thin=thin,
    )


def _subset(sample: PosteriorSample, max_draws: int):
    walkers, draws = sample.phi.shape
    step = max(1, math.ceil(walkers * draws / max_draws))
    return np.arange(draws - 1, -1, -step)[::-1]


def to_inference_data(model: PosteriorModel, sample: PosteriorSample, *, rng: np.random.Generator,
                      max_draws: int = MAX_DRAWS, keep_sims: int = 200):
    """InferenceData of the kept draws; also the full-rate low-passed simulations of up to
    ``keep_sims`` draws (for credible bands), shape (n, K)."""
    az = arviz_import.module()

    idx = _subset(sample, max_draws)
    theta = sample.theta[:, idx]
    walkers, draws, _ = theta.shape
    n_grid = len(model.grid)
    n_obs = model.harmonic.harmonics if model.harmonic is not None else n_grid
    loglik = np.empty((walkers, draws, n_obs))
    pred = np.empty((walkers, draws, n_grid))
    sims = []
    sim_every = max(1, math.ceil(walkers * draws / keep_sims))
    k = 0
    for w in range(walkers):
        for d in range(draws):
            _, ll, sim = model.evaluate(theta[w, d])
            if ll is None:  # cannot happen for accepted draws, but never write garbage
                loglik[w, d] = np.nan
                pred[w, d] = np.nan
                continue
            loglik[w, d] = ll
            pred[w, d] = sim[model.grid] + _predictive_error(model, theta[w, d], rng)
            if k % sim_every == 0:
                sims.append(sim)
            k += 1
    posterior = {n: v[:, idx] for n, v in sample.as_dict().items()}
    coords = {"time": model.record.time[model.grid]}
    dims = {"accel": ["time"]}
    if model.harmonic is not None:
        coords["harmonic"] = np.arange(1, model.harmonic.harmonics + 1)
        dims[_loglik_name(model)] = ["harmonic"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idata = az.from_dict(
            posterior=posterior,
            log_likelihood={_loglik_name(model): loglik},
            posterior_predictive={"accel": pred},
            observed_data={"accel": model.observed},
            sample_stats={"lp": sample.lp[:, idx]},
            coords=coords,
            dims=dims,
        )
    return idata, np.array(sims)


def _loglik_name(model: PosteriorModel) -> str:
    """What the likelihood's pointwise terms are of: samples of the acceleration, or
    harmonics of the acceleration or (motion in) of the force."""
    if model.harmonic is None:
        return "accel"
    return "force_harmonics" if model.motion is not None else "accel_harmonics"


def _predictive_error(model: PosteriorModel, theta, rng: np.random.Generator) -> np.ndarray:
    """A draw of what the likelihood adds to the simulation on its grid: the AR(1)
    residual, or for the harmonic likelihood a periodic error whose harmonic k is
    complex normal with the variance V_k (noise and discrepancy) at theta."""
    if model.harmonic is None:
        sigma, rho = model.noise(theta)
        return ar1_noise(rng, len(model.grid), sigma, rho)
    V = model.accel_error_variance(theta)
    z = (rng.standard_normal(len(V)) + 1j * rng.standard_normal(len(V))) * np.sqrt(V / 2.0)
    return at_times(z, model.harmonic.omega, model.record.time[model.grid])


def ar1_noise(rng, n, sigma, rho):
    """A stationary AR(1) series of length n: innovations N(0, sigma^2), coefficient rho."""
    e = rng.standard_normal(n) * sigma
    if rho == 0.0:
        return e
    out = np.empty(n)
    out[0] = e[0] / math.sqrt(1 - rho * rho)
    for i in range(1, n):
        out[i] = rho * out[i - 1] + e[i]
    return out


def contraction(model: PosteriorModel, sample: PosteriorSample) -> dict:
    """Posterior contraction per sampled quantity: 1 - var(posterior) / var(prior), both
    in the sampled (log or linear) scale. Near 1: the data identify it; near 0 (or
    below, for a non-uniform prior's truncated tail): the posterior is the prior."""
    out = {}
    for i, name in enumerate(model.names):
        prior = model.all_priors[name]
        lo, hi = prior.bounds
        if hasattr(prior, "median") and prior.log_scale and not hasattr(prior, "low"):
            var_prior = prior.sigma**2
        else:
            var_prior = (hi - lo) ** 2 / 12.0
        out[name] = 1.0 - float(np.var(sample.theta[:, :, i])) / var_prior
    return out


def summary_rows(sample: PosteriorSample, kinds: dict | None = None) -> list[dict]:
    """One row per parameter (and phi) with the summary columns, from the kept draws.
    ``kinds``: each name's ``kind`` ("sampled", "derived", ...; empty where not given).
    A derived quantity that is not defined in every draw (NaN: ``b_app``) is summarised
    over the draws where it is, and its kind says in how many."""
    az = arviz_import.module()

    rows = []
    data = sample.as_dict()
    kinds = kinds or {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, x in data.items():
            kind = kinds.get(name, "")
            defined = np.isfinite(x)
            if not np.all(defined):
                kind += f" (defined in {np.mean(defined):.0%} of the draws)"
                if np.sum(defined) < 2:
                    rows.append({"name": name, "kind": kind, **{c: math.nan for c in NUMBER_COLUMNS}})
                    continue
                # R-hat and ESS need whole chains: not computed over a subset of draws
                rows.append({"name": name, "kind": kind, **_moments(x[defined]), "r_hat": math.nan,
                             "ess_bulk": math.nan, "ess_tail": math.nan})
                continue
            lo, hi = hdi(x)
            rows.append({
                "name": name,
                "kind": kind,
                "mean": float(np.mean(x)),
                "sd": float(np.std(x, ddof=1)),
                "hdi_3%": lo,
                "hdi_97%": hi,
                "r_hat": float(az.rhat(x)),
                "ess_bulk": float(az.ess(x, method="bulk")),
                "ess_tail": float(az.ess(x, method="tail")),
            })
    return rows


def _moments(x: np.ndarray) -> dict:
    """mean, sd and the 94 % HDI of draws ``x`` (any shape, all finite)."""
    lo, hi = hdi(x)
    return {"mean": float(np.mean(x)), "sd": float(np.std(x, ddof=1)), "hdi_3%": lo, "hdi_97%": hi}


def write_summary(path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(SUMMARY_COLUMNS)
        for r in rows:
            w.writerow([r["name"], r.get("kind", "")] + [f"{r[c]:.10g}" for c in NUMBER_COLUMNS] + [r.get("flag", "")])


def loo_data(idata):
    """``idata``'s log-likelihood with the posterior variables that are finite in every
    draw: what PSIS-LOO reads. A derived quantity defined on some draws only (``b_app``,
    NaN elsewhere) enters arviz's relative efficiency, which ignores it, and made arviz
    log "Array contains NaN-value" for every fit; without it the LOO is the same."""
    az = arviz_import.module()

    post = idata.posterior
    finite = [v for v in post.data_vars if np.all(np.isfinite(np.asarray(post[v])))]
    return az.InferenceData(posterior=post[finite], log_likelihood=idata.log_likelihood)


def loo_summary(idata) -> dict:
    """PSIS-LOO of a fit's InferenceData (arviz): elpd_loo, its standard error, p_loo,
    the largest Pareto k and the number of points. Small enough to keep beside a fit's
    summary where ``posterior.nc`` is not kept (committed results), so a study's model
    comparison can be rebuilt without it."""
    import warnings

    az = arviz_import.module()

    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a large Pareto k is reported in the result instead
        loo = az.loo(loo_data(idata), pointwise=True)
    k = np.asarray(loo.pareto_k)
    return {"elpd_loo": float(loo.elpd_loo), "elpd_se": float(loo.se), "p_loo": float(loo.p_loo),
            "pareto_k_max": float(np.max(k)), "n_points": int(k.size)}


def write_loo(folder, idata) -> dict:
    """:func:`loo_summary` of ``idata``, written to ``folder``/:data:`LOO_FILE`; returns it."""
    import json
    from pathlib import Path

    loo = loo_summary(idata)
    (Path(folder) / LOO_FILE).write_text(json.dumps(loo, indent=2) + "\n")
    return loo
