"""Bayesian inference of one record or many, in three layers that point one way:
:mod:`.posterior` (priors, likelihoods, the log posterior), :mod:`.sampling` (start,
coordinates, moves, convergence, checkpoint, the sampler) and :mod:`.summaries` (draws,
intervals, loops, figures). The commands' entry points sit on top: :mod:`.fit`
(``fit_record``, ``fit_joint``), :mod:`.compare` (one record under several models) and
:mod:`.identify` (the paper's least squares)."""

from .fit import FitResult, fit_joint, fit_record
from .posterior.model import MODELS, LikelihoodSettings, PosteriorModel
from .posterior.priors import DEFAULT_PRIORS, LogNormal, LogUniform
from .sampling.sampler import Adaptation, CheckpointError, Convergence, Tempering, run_sampler

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
    "Tempering",
    "run_sampler",
]
