"""Moves beside emcee's own, one a module: a jump along the nut's ridge (:mod:`.ridge`),
independence proposals from a fitted multivariate t (:mod:`.independence`) and
Metropolis-within-Gibbs block proposals from a normal in normal scores (:mod:`.block`).
Each leaves any posterior invariant; docs/inference.md says what each was measured to do,
and which moves were tried and not kept."""

from .block import BlockMove
from .independence import IndependenceMove
from .ridge import NutRidgeMove, ridge_indices

__all__ = ["IndependenceMove", "BlockMove", "NutRidgeMove", "ridge_indices"]
