"""Sampling a posterior: the start, the walkers' coordinates and moves, the chain.

The start search (:mod:`.optimize`), the density in the sampler's coordinates
(:mod:`.target`, :mod:`.coordinates`), the moves (:mod:`.moves`; the fitted ones learn
from :mod:`.marginals` and :mod:`.transport`, refitted by :mod:`.adaptation`), the
convergence rule (:mod:`.convergence`, :mod:`.diagnostics`), the crash-safe checkpoint
(:mod:`.checkpoint`, :mod:`.twin_backend`, :mod:`.identity`) and the loop that runs
emcee's generator through them (:mod:`.sampler`). It uses :mod:`..posterior` and nothing
of :mod:`..summaries`.
"""
