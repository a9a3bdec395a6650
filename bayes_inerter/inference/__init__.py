"""Bayesian inference of one record: model, priors, sampler, results, plots."""

from .fit import FitResult, fit_joint, fit_record
from .model import MODELS, LikelihoodSettings, PosteriorModel
from .priors import DEFAULT_PRIORS, LogNormal, LogUniform
from .sampler import Adaptation, CheckpointError, Convergence, run_sampler

__all__ = [
    "FitResult",
    "fit_record",
    "fit_joint",
    "MODELS",
    "LikelihoodSettings",
    "PosteriorModel",
    "DEFAULT_PRIORS",
    "LogNormal",
    "LogUniform",
    "CheckpointError",
    "Convergence",
    "Adaptation",
    "run_sampler",
]
