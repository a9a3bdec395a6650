"""How a record's simulated and measured accelerations are compared: the settings of the
likelihood (``model.PosteriorModel``)."""

from __future__ import annotations

from dataclasses import dataclass

from ..records.conditioning import LOWPASS_HZ
from ..simulate import SAMPLINGS

__all__ = ["LikelihoodSettings"]


@dataclass(frozen=True)
class LikelihoodSettings:
    """How simulated and measured accelerations are compared (all documented defaults).

    Attributes
    ----------
    residual : "ar1" (default) or "iid".
    cutoff : matched low-pass cut-off, Hz (default 30).
    stride : keep every stride-th sample; None: fs / (2 cutoff), about one sample per
        correlation length of the low-passed signal (16 at 1 kHz and 30 Hz).
    edge : seconds left out at each end (zero-phase filter transients), default 0.25 s.
    upsample : **assumption** on the force between samples. The record's force is
        interpolated linearly between samples (the paper's choice) when 1 (default);
        with q > 1 it is reconstructed at q times the rate by band-limited polyphase
        FIR interpolation (``scipy.signal.resample_poly``), simulated there, and the
        simulated acceleration is brought back by the same filter, at q times the cost.
        Measured on generated records (A1 1 Hz, A0 0.5 Hz, B2 1.5 Hz) with the "mean"
        sampling below: the residual at the true parameters is the same for q = 1, 2
        and 4 (2.34e-3, 2.31e-3, 2.35e-3 m/s^2 rms), and a local optimum lies 2-5 nats
        from the truth for each q (the noise's share). It mattered only with
        "instant" sampling.
    sampling : how the simulated acceleration is sampled (``simulate``'s option):
        "mean" (default), its mean around each sample instant, continuous in the
        parameters; "instant", its value at the instant, which jumps by the Coulomb
        force over the plate mass whenever a friction switch crosses a sample instant
        and makes the likelihood rough (tens of nats for a 0.05 % change of the
        Coulomb force, measured on a generated A1 record at 1 Hz; with "mean" the same
        scan is a smooth parabola peaked at the truth).
    """

    residual: str = "ar1"
    cutoff: float = LOWPASS_HZ
    stride: int | None = None
    edge: float = 0.25
    upsample: int = 1
    sampling: str = "mean"

    def __post_init__(self) -> None:
        if self.residual not in ("ar1", "iid"):
            raise ValueError(f"residual model must be 'ar1' or 'iid', got {self.residual!r}")
        if not self.cutoff > 0:
            raise ValueError(f"cut-off must be positive, got {self.cutoff}")
        if self.stride is not None and not (isinstance(self.stride, int) and self.stride >= 1):
            raise ValueError(f"stride must be a positive integer, got {self.stride!r}")
        if not self.edge >= 0:
            raise ValueError(f"edge must be non-negative, got {self.edge}")
        if not (isinstance(self.upsample, int) and 1 <= self.upsample <= 16):
            raise ValueError(f"upsample must be a whole number from 1 to 16, got {self.upsample!r}")
        if self.sampling not in SAMPLINGS:
            raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, got {self.sampling!r}")
