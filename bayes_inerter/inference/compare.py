"""One record under several models: b under each, their LOO, and b stacked over them.

A user's device is never the model's, and which effects it has is not known before the
fit. :func:`compare_models` fits the record under each model the likelihood knows
(``fit_record``, each in its own folder ``out/<model>``, so an interrupted comparison
continues each fit from its checkpoint), compares them by PSIS-LOO (arviz; a Pareto k
above :data:`PARETO_K_LIMIT` flags a fit whose LOO is unreliable), and stacks them:
arviz's stacking weights (Yao, Vehtari, Simpson and Gelman 2018) maximise the
leave-one-out predictive density of the weighted mixture, and b's stacked posterior is
that mixture of the models' draws of b.

The LOO's points are what the likelihood's pointwise log-likelihood holds (for the
motion-in likelihood: the drive's harmonics of the force), so the models must be fitted
under one likelihood to be compared; a model the likelihood refuses is reported with the
reason (``model.refusal``) and left out of the stacking.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import arviz_import
from .fit import check_output_folder, fit_record
from .posterior.model import MODELS, LikelihoodSettings, refusal
from .summaries.results import HDI_PROB, hdi, loo_data

__all__ = ["ModelFit", "Comparison", "compare_models", "stack_draws", "COMPARED", "PARETO_K_LIMIT", "COMPARE_FILE"]

#: The models compared by default, in order: the paper's and its limits, then the richer ones.
COMPARED = ("two-port", "rigid", "linear", "two-port-stribeck", "two-port-backlash", "two-port-rich")
#: A fit whose largest Pareto k exceeds this has an unreliable PSIS-LOO (Vehtari et al. 2017).
PARETO_K_LIMIT = 0.7
#: The comparison's table, in ``out``.
COMPARE_FILE = "compare.csv"
#: The levels of b's reported intervals.
LEVEL = HDI_PROB


@dataclass(frozen=True)
class ModelFit:
    """One model's fit in a comparison (b in kg, elpd in nats); ``skipped`` the reason a
    model was not fitted (its other fields are then NaN)."""

    model: str
    b_median: float = math.nan
    b_lo: float = math.nan
    b_hi: float = math.nan
    elpd_loo: float = math.nan
    elpd_se: float = math.nan
    p_loo: float = math.nan
    pareto_k_max: float = math.nan
    weight: float = math.nan
    converged: bool = False
    steps: int = 0
    skipped: str = ""

    @property
    def loo_reliable(self) -> bool:
        return self.pareto_k_max <= PARETO_K_LIMIT


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare_models` found: each model's fit and b stacked over them."""

    fits: tuple
    b_median: float
    b_lo: float
    b_hi: float
    out: Path

    @property
    def fitted(self) -> list:
        return [f for f in self.fits if not f.skipped]


def stack_draws(draws: dict, weights: dict, rng: np.random.Generator, n: int | None = None) -> np.ndarray:
    """``n`` draws (default: as many as the models hold together) of the mixture of the
    models' draws with the given weights: each draw's model by its weight, then one of
    that model's draws uniformly."""
    names = [m for m in draws if weights.get(m, 0.0) > 0.0]
    if not names:
        raise ValueError("no model has a positive weight")
    w = np.array([weights[m] for m in names], dtype=float)
    w = w / w.sum()
    n = int(n if n is not None else sum(np.size(draws[m]) for m in draws))
    pick = rng.choice(len(names), size=n, p=w)
    out = np.empty(n)
    for i, m in enumerate(names):
        sel = pick == i
        flat = np.ravel(draws[m])
        out[sel] = flat[rng.integers(0, flat.size, size=int(sel.sum()))]
    return out


def _weights(idatas: dict) -> dict:
    """arviz's stacking weights of the fitted models (one model: weight 1)."""
    if len(idatas) == 1:
        return {m: 1.0 for m in idatas}
    az = arviz_import.module()

    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # large Pareto k: flagged per fit instead
        table = az.compare({m: loo_data(d) for m, d in idatas.items()}, ic="loo", method="stacking")
    return {m: float(table.loc[m, "weight"]) for m in idatas}


def compare_models(record, out, *, models=COMPARED, likelihood: LikelihoodSettings | None = None, seed: int = 0,
                   on_model=None, progress_for=None, **fit_options) -> Comparison:
    """Fit ``record`` under each of ``models`` (``fit_record`` with ``fit_options``, each
    into ``out/<model>``), compare them by PSIS-LOO and stack them; writes
    ``out/compare.csv`` (one row a model, the stacked b last) and ``out/compare.json``.

    ``on_model(model, reason)``: called before each model's fit (reason "") and for each
    model left out (the reason why). ``progress_for(model)``: returns the ``progress`` and
    ``report`` callbacks of that model's fit (``run_sampler``'s). Raises ValueError if no
    model can be fitted under ``likelihood``."""
    likelihood = likelihood or LikelihoodSettings()
    out = Path(out)
    check_output_folder(out)
    unknown = [m for m in models if m not in MODELS]
    if unknown:
        raise ValueError(f"unknown model {unknown[0]!r}; choose among {', '.join(MODELS)}")
    reasons = {m: refusal(m, likelihood) for m in models}
    if all(reasons.values()):
        raise ValueError(f"no model of {', '.join(models)} can be fitted under the {likelihood.residual} likelihood")
    fits, idatas, draws = {}, {}, {}
    for m in models:
        if reasons[m]:
            fits[m] = ModelFit(m, skipped=reasons[m])
            if on_model:
                on_model(m, reasons[m])
            continue
        if on_model:
            on_model(m, "")
        if progress_for:
            fit_options["progress"], fit_options["report"] = progress_for(m)
        res = fit_record(record, out / m, model=m, likelihood=likelihood, seed=seed, **fit_options)
        b = np.asarray(res.idata.posterior["b"], dtype=float)
        lo, hi = hdi(b, LEVEL)
        loo = res.loo
        idatas[m], draws[m] = res.idata, b
        fits[m] = ModelFit(m, float(np.median(b)), lo, hi, loo["elpd_loo"], loo["elpd_se"], loo["p_loo"],
                           loo["pareto_k_max"], converged=bool(res.converged), steps=int(res.iterations))
    weights = _weights(idatas)
    fits = {m: (f if f.skipped else ModelFit(**{**asdict(f), "weight": weights[m]})) for m, f in fits.items()}
    stacked = stack_draws(draws, weights, np.random.default_rng(seed))
    out.mkdir(parents=True, exist_ok=True)
    lo, hi = hdi(stacked, LEVEL)
    result = Comparison(tuple(fits[m] for m in models), float(np.median(stacked)), lo, hi, out)
    _write(result, likelihood, seed)
    return result


def _write(c: Comparison, likelihood: LikelihoodSettings, seed: int) -> None:
    fields = ["model", "b_median", "b_lo", "b_hi", "elpd_loo", "elpd_se", "p_loo", "pareto_k_max", "loo_reliable",
              "weight", "converged", "steps", "skipped"]
    with (c.out / COMPARE_FILE).open("w", newline="") as f:
        w = csv.DictWriter(f, fields)
        w.writeheader()
        for fit in c.fits:
            w.writerow({**asdict(fit), "loo_reliable": fit.loo_reliable if not fit.skipped else ""})
        w.writerow({"model": "stacked", "b_median": c.b_median, "b_lo": c.b_lo, "b_hi": c.b_hi,
                    "weight": sum(f.weight for f in c.fitted)})
    info = {"likelihood": likelihood.residual, "seed": seed, "level": LEVEL, "pareto_k_limit": PARETO_K_LIMIT,
            "stacked": {"b_median": c.b_median, "b_lo": c.b_lo, "b_hi": c.b_hi},
            "models": [{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in asdict(f).items()}
                       for f in c.fits]}
    (c.out / "compare.json").write_text(json.dumps(info, indent=1) + "\n")
