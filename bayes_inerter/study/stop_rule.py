"""Which convergence rule a study's chains were stopped by, so that a folder continued
over several sessions never mixes two.

``Convergence.tau_rtol`` changed default (CHANGELOG.md); a study's rows name the value
their chains used, and rows written before they did were stopped with
:data:`TAU_RTOL_BEFORE`.
"""

from __future__ import annotations

from dataclasses import replace

from ..inference.sampling.convergence import Convergence

__all__ = ["TAU_RTOL_BEFORE", "resolved", "recorded", "convergence", "check_folder"]

#: ``Convergence.tau_rtol`` of every chain whose row does not name one.
TAU_RTOL_BEFORE = 0.05


def resolved(tau_rtol: float | None) -> float:
    """The tolerance a run asking ``tau_rtol`` uses (None: the package's default)."""
    return Convergence().tau_rtol if tau_rtol is None else float(tau_rtol)


def recorded(row: dict) -> float:
    """The tolerance the chain of ``row`` (a study's JSON row) was stopped with."""
    return float(row.get("tau_rtol", TAU_RTOL_BEFORE))


def convergence(max_steps: int, tau_rtol: float | None, replicas: bool = False) -> Convergence:
    """The package's rule with the cap ``max_steps``, the tolerance asked, and a tempered
    chain's tau read on its replicas where ``replicas`` (``Convergence.replicas``; False
    by default here, unlike the package's rule: the studies' committed tempered folders
    were stopped on the posterior's ensemble alone, and a folder continues under its
    own rule)."""
    return replace(Convergence(), max_steps=max_steps, tau_rtol=resolved(tau_rtol), replicas=replicas)


def check_folder(rows, tau_rtol: float | None, folder) -> None:
    """ValueError if a row of ``rows`` was stopped with another tolerance than
    ``tau_rtol`` asks (the message names the option that continues them)."""
    want = resolved(tau_rtol)
    other = sorted({recorded(r) for r in rows} - {want})
    if other:
        raise ValueError(f"{folder} holds chains stopped with tau_rtol {', '.join(f'{v:g}' for v in other)}, "
                         f"not {want:g}: continue it with --tau-rtol {other[0]:g}, or choose another folder")
