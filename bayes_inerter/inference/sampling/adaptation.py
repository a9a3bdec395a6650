"""Adaptive moves: a multivariate t fitted to the chain so far, refitted at fixed steps.

At every multiple of ``every`` steps, a multivariate t is fitted to the chain so far
after its :func:`.convergence.transient`, in its normal scores (``knots``; or in sampler
coordinates), and :class:`.moves.IndependenceMove` proposes from it, with
:class:`.moves.BlockMove` from a normal in the same scores in ``blocks`` of their share,
in ``weight`` of the following steps, the ensemble moves in the rest. The proposals
change only at those steps and are fitted to a growing chain (diminishing adaptation,
Roberts and Rosenthal 2007); between two of them they are fixed and every move leaves
the posterior invariant. A continued chain refits from the same stored steps, so it is
the chain an uninterrupted run gives.

:class:`Adaptation` holds the settings; :class:`Schedule` gives the moves of each
stretch of a run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .convergence import transient
from .marginals import KNOTS
from .moves import BlockMove, IndependenceMove
from .moves.block import PARTNERS
from .transport import TriangularScores

__all__ = ["Adaptation", "Schedule", "STRETCH", "FIT_MAX_STEPS", "NAMED"]

#: The adaptive samplers that studies and benchmarks compare side by side, by name:
#: keyword arguments of :class:`Adaptation` (``adaptive``: one t in the sampler's
#: coordinates; ``scores``: the t in normal scores; ``blocks``: that and block moves of
#: random coordinates, the default; ``correlated``: block moves of a coordinate and its
#: most correlated partners).
NAMED = {"adaptive": {"knots": None, "blocks": 0.0},
         "scores": {"knots": 200, "blocks": 0.0},
         "blocks": {"knots": 200, "blocks": 0.5, "block_partners": "random"},
         "correlated": {"knots": 200, "blocks": 0.5, "block_partners": "correlated"}}

#: The fitted moves learn from at most this many of the chain's steps after its
#: transient: a longer chain is thinned evenly to them (every ceil(n / FIT_MAX_STEPS)-th
#: step), so a refit costs the same however long the chain has grown. Chains up to this
#: length are fitted from every step, as before. Measured: refitting from every step of
#: a paper-like record's 20,000-step chain took 11 % of its run.
FIT_MAX_STEPS = 2000


#: Steps in one stretch of a run without adaptation (the moves never change there; a
#: stretch only bounds how far the checkpoint is grown ahead).
STRETCH = 250


@dataclass(frozen=True)
class Adaptation:
    """The fitted moves' share of the steps, and when they are refitted (see module
    docstring). By default the independence move's t is fitted in the chain's normal
    scores (:mod:`.marginals`), and half of the fitted moves' share goes to block moves
    (:class:`.moves.BlockMove`) from a normal in the same scores; ``knots=None,
    blocks=0`` is one t in the sampler's coordinates, the earlier default. Measured side by side with it (same starts and seeds): on the joint model
    of 9 records (``studies/joint_mixing.py``, 3,000 steps) the largest autocorrelation
    time over the last four fifths fell from 115.0 to 30.0 steps; on single records to
    convergence (``benchmarks/bench_adaptation.py``), A3 at 1 Hz took 4,500 steps
    against 8,000, B2 at 1 Hz 2,000 against 1,500. Earlier, on A3 at 1 Hz (3,000 steps
    from the optimum's ensemble, 24 walkers, one seed): the largest autocorrelation time
    over steps 1,000-3,000 was 96.3 steps with the ensemble moves alone, 44.8 with the
    fitted t alone (``wide=0``) and 38.4 with the t and its wide part.

    Attributes
    ----------
    weight : share of the steps that propose from the fitted t once there is one
        (default 0.5); the ensemble moves keep their proportions in the rest.
    every : the proposal is refitted at every multiple of this many steps (default 250),
        from the chain's steps after its transient, if at least ``every // 2`` of them.
    dof, scale : the t's degrees of freedom and the factor on its covariance's square
        root (:class:`.moves.IndependenceMove`; defaults 10 and 1.1).
    wide, wide_scale : share of proposals drawn from the same t ``wide_scale`` times
        wider (defaults 0.2 and 3; see :class:`.moves.IndependenceMove`).
    knots : the t's fitted in the chain's normal scores (:mod:`.marginals`) with this
        many knots per coordinate (default 200), or (None) in the sampler's coordinates.
    blocks : share of ``weight`` given to a :class:`.moves.BlockMove` fitted in the
        same normal scores (needs ``knots``; default 0.5; 0: none).
    block_partners : how a block move picks its coordinates (:data:`.moves.block.PARTNERS`):
        "random" (default), or "correlated", a coordinate and its most correlated partners
        under the fitted normal (:class:`.moves.BlockMove`; measured side by side in
        docs/inference.md, "Adaptation": fewer steps on two records, not on two others).
    transport : the independence move's t fitted after a triangular quadratic map of the
        normal scores (:class:`.transport.TriangularScores`; needs ``knots``), the block
        move kept in the normal scores alone (default False: not measured to mix faster
        yet, results/chain-geometry).
    """

    weight: float = 0.5
    every: int = 250
    dof: float = 10.0
    scale: float = 1.1
    wide: float = 0.2
    wide_scale: float = 3.0
    knots: int | None = KNOTS
    blocks: float = 0.5
    transport: bool = False
    block_partners: str = "random"

    def __post_init__(self) -> None:
        if not 0.0 <= self.blocks < 1.0:
            raise ValueError(f"adaptation's block share must lie in [0, 1), got {self.blocks}")
        if self.blocks > 0.0 and self.knots is None:
            raise ValueError("adaptation block moves are fitted in normal scores: give knots too")
        if self.block_partners not in PARTNERS:
            raise ValueError(f"adaptation's block partners must be one of {', '.join(PARTNERS)}, "
                             f"got {self.block_partners!r}")
        if self.transport and self.knots is None:
            raise ValueError("adaptation's transport map starts from normal scores: give knots too")
        if self.knots is not None and not (isinstance(self.knots, int) and self.knots >= 4):
            raise ValueError(f"adaptation knots must be a whole number of at least 4 or None, got {self.knots!r}")
        if not 0.0 < self.weight < 1.0:
            raise ValueError(f"adaptation weight must lie in (0, 1), got {self.weight}")
        if not (isinstance(self.every, int) and self.every >= 2):
            raise ValueError(f"adaptation period must be a whole number of at least 2 steps, got {self.every!r}")
        if not (self.dof > 0 and self.scale > 0 and self.wide_scale > 0):
            raise ValueError(f"adaptation dof and scales must be positive, got {self.dof}, {self.scale} "
                             f"and {self.wide_scale}")
        if not 0.0 <= self.wide < 1.0:
            raise ValueError(f"adaptation's wide share must lie in [0, 1), got {self.wide}")

    def fit(self, chain: np.ndarray, log_prob: np.ndarray) -> tuple[IndependenceMove | None, BlockMove | None]:
        """The moves fitted to ``chain`` (steps, walkers, ndim; sampler coordinates) after
        its :func:`transient` (from ``log_prob``, steps x walkers): the independence move,
        and with ``blocks`` the block move in the same normal-scores map (fitted once, to
        the same draws). Each None where fewer than ``every // 2`` steps follow the
        transient or the draws define none."""
        skip = transient(log_prob)
        if len(chain) - skip < self.every // 2:
            return None, None
        thin = -(-(len(chain) - skip) // FIT_MAX_STEPS)  # 1 up to FIT_MAX_STEPS steps
        draws = chain[skip::thin].reshape(-1, chain.shape[-1])
        t = {"dof": self.dof, "scale": self.scale, "wide": self.wide, "wide_scale": self.wide_scale}
        proposal = self._transported(draws, t) if self.transport else None
        z = None
        if proposal is None:
            proposal, z = IndependenceMove.fit_scored(draws, knots=self.knots, **t)
        if self.blocks == 0.0:
            return proposal, None
        scores = proposal.scores if proposal is not None else None
        scores = scores.scores if isinstance(scores, TriangularScores) else scores
        return proposal, BlockMove.fit(draws, knots=self.knots, scores=scores, z=z,  # z: None after the map
                                       partners=self.block_partners)

    def _transported(self, draws: np.ndarray, t: dict) -> IndependenceMove | None:
        """The independence move's t fitted after the triangular map of ``draws``, or None
        where the draws define none (the normal scores' t is then fitted instead)."""
        try:
            tmap = TriangularScores.fit(draws, self.knots)
        except (ValueError, np.linalg.LinAlgError):
            return None
        return IndependenceMove.fit_in(draws, tmap, **t)

    def moves(self, base: list, proposal: IndependenceMove | None, block: BlockMove | None = None) -> list:
        """``base`` moves, with ``proposal`` (and ``block``, in ``blocks`` of their share)
        in ``weight`` of the steps where there is one."""
        if proposal is None:
            return list(base)
        fitted = [(proposal, self.weight)] if block is None else [
            (proposal, self.weight * (1.0 - self.blocks)), (block, self.weight * self.blocks)]
        return [(m, w * (1.0 - self.weight)) for m, w in base] + fitted

    def describe(self) -> str:
        law = "t"
        if self.knots is not None:
            law += f" in normal scores ({self.knots} knots)"
        if self.transport:
            law += " after a triangular quadratic map"
        if self.blocks > 0.0:
            law += f"; {self.blocks:g} of its share to block moves from a normal in the same scores"
            if self.block_partners == "correlated":
                law += ", each block a coordinate and its most correlated partners"
        return (f"IndependenceMove {self.weight:.3g} ({law}, dof {self.dof:g}, scale {self.scale:g}, "
                f"{self.wide:g} of it {self.wide_scale:g} x wider, refitted every {self.every} steps; "
                f"the others scaled by {1 - self.weight:.3g} once fitted)")


class Schedule:
    """The moves of each stretch of one run: ``base`` (the ensemble moves) alone, or with
    ``adaptation``'s fitted moves from the last multiple of ``adaptation.every`` at or
    before the stretch's first step (fitted once per multiple, from the chain's first
    that many steps)."""

    def __init__(self, base: list, adaptation: Adaptation | None):
        self.base = list(base)
        self.adaptation = adaptation
        self._fitted: dict[int, tuple[IndependenceMove | None, BlockMove | None]] = {}
        self._hot: dict[tuple[int, int], tuple[IndependenceMove | None, BlockMove | None]] = {}
        self._hot_rows: tuple = (None, None)  # the step the hot ensembles' walkers were read to, and them

    @property
    def period(self) -> int:
        return self.adaptation.every if self.adaptation is not None else STRETCH

    def end_of_stretch(self, step: int) -> int:
        """The first step after ``step`` at which the moves may change."""
        return (step // self.period + 1) * self.period

    def moves_at(self, step: int, backend) -> list:
        """The moves from ``step`` to :meth:`end_of_stretch` (``backend``: the chain so
        far, in sampler coordinates)."""
        if self.adaptation is None:
            return self.base
        at = (step // self.period) * self.period
        if at > 0 and at not in self._fitted:
            self._fitted[at] = self.adaptation.fit(backend.get_chain()[:at], backend.get_log_prob()[:at])
        return self.adaptation.moves(self.base, *self._fitted.get(at, (None, None)))

    def hot_moves_at(self, step: int, backend, k: int) -> list:
        """A tempered run's ``k``-th hot ensemble's moves from ``step`` to
        :meth:`end_of_stretch`: fitted as :meth:`moves_at` fits the posterior's, to that
        ensemble's own walkers so far (the per-step ``hot_chain`` the back end keeps,
        :mod:`.tempering`), where a proposal fitted to the posterior would be too narrow.
        The hot ensembles' log probabilities are not kept per step, so no transient is
        left out: their walkers start drawn at their own spread."""
        if self.adaptation is None:
            return self.base
        at = (step // self.period) * self.period
        if at > 0 and (at, k) not in self._hot:
            if self._hot_rows[0] != at:  # read once per refit for all the hot ensembles
                self._hot_rows = (at, backend.get_rows("hot_chain")[:at])
            hot = np.asarray(self._hot_rows[1][:, k], dtype=float)
            self._hot[at, k] = self.adaptation.fit(hot, np.zeros(hot.shape[:2]))
        return self.adaptation.moves(self.base, *self._hot.get((at, k), (None, None)))

    def used(self) -> tuple:
        """The moves the run used and their weights ("DEMove 0.48", ...): the fitted t's
        only where one was fitted (at least one refit had enough steps after the
        transient)."""
        names = tuple(f"{type(m).__name__} {w:.3g}" for m, w in self.base)
        proposed = any(fitted[0] is not None for fitted in self._fitted.values())
        return names + ((self.adaptation.describe(),) if self.adaptation is not None and proposed else ())
