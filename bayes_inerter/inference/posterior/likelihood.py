"""How a record's simulated and measured accelerations are compared: the settings of the
likelihood (``model.PosteriorModel``) and the time-domain residual's densities, which
the single-record and the joint model share (the harmonic likelihood: ``harmonic``).
"""

from __future__ import annotations

import json
import math
import numbers
from dataclasses import dataclass

import numpy as np

from ...records.conditioning import LOWPASS_HZ
from ...records.sensitivity import SensorCalibration
from ...simulate import SAMPLINGS

__all__ = ["LikelihoodSettings", "RESIDUALS", "NORMALISERS", "DEVIATION_SCALES", "DELAY_SD", "INPUT_NOISE_DRAWS", "INPUT_NOISE_FORMS", "ar1_pointwise",
           "ar1_marginal", "settings_changes"]

#: The likelihoods: the time-domain residual as a stationary AR(1) process or white, and
#: the harmonic likelihood with errors in both signals and a sampled discrepancy.
RESIDUALS = ("ar1", "iid", "harmonic", "motion")
#: **Assumption**: the prior sd of the force channel's delay behind the acceleration
#: channel's, s, that the motion-in likelihood samples by default
#: (``LikelihoodSettings.delay_sd``).
DELAY_SD = 5e-4
#: Draws of the measured motion's noise that the motion-in likelihood pushes through the
#: model at its reference point by default (``LikelihoodSettings.input_noise`` None); the
#: draws' seed is ``motion.INPUT_NOISE_SEED``.
INPUT_NOISE_DRAWS = 16
#: Where the motion-in likelihood's marginalised deviations take the Coulomb forces that
#: scale their prior sd (``LikelihoodSettings.deviation_scale``).
DEVIATION_SCALES = ("parameters", "reference")
#: Whose Coulomb force scales the motion-in likelihood's reversal deviations
#: (``LikelihoodSettings.reversal_scale``): the plate's alone, or the plate's and the
#: rotation's together.
REVERSAL_SCALES = ("plate", "total")
#: The motion-in likelihood's normalisers (``LikelihoodSettings.normaliser``).
NORMALISERS = ("reference", "full")

#: The forms of the drivetrain's input noise in the motion-in likelihood
#: (``LikelihoodSettings.input_noise_form``).
INPUT_NOISE_FORMS = ("variance", "shapes")


@dataclass(frozen=True)
class LikelihoodSettings:
    """How simulated and measured accelerations are compared (all documented defaults).

    Attributes
    ----------
    residual : "motion" (default; :mod:`.motion`: the measured motion in, the force
        out, at the drive's harmonics), "harmonic" (:mod:`.harmonic`: force in,
        acceleration out, at the drive's harmonics), "ar1" or "iid" (the low-passed
        acceleration sample by sample, its residual an AR(1) process or white).
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
    pool : harmonic likelihoods only: the noise's variance at a harmonic is averaged over
        the harmonics within ``pool`` of it (**assumption**: a smooth noise spectrum),
        default 2.
    settle : harmonic likelihoods only: whole drive periods left out after the start
        of the steady part (the start-up's transient), default 1.
    gain_sd : harmonic likelihoods only: log-sd of the prior on ``gain``, the
        acceleration channel's gain relative to the force channel's (**assumption**:
        the sensors' calibration uncertainties of ``records.SensorCalibration``, 0.25 %
        for the load cell and 0.5 % for the accelerometer, default their ratio's 0.56 %);
        0 fixes the gain at 1 and leaves it out of the sampled parameters.
    decay : motion-in likelihood only: sample the discrepancy's spectral decay alpha
        (variance tau^2 k^(-2 alpha), alpha uniform on 0 to 2). Default False: the
        discrepancy is white (**assumption**: what the model lacks does not live at the
        drive's first harmonics, where b and the viscous friction act; a decaying one
        let the fits of paper-like records give up the fundamental, see docs/inference.md).
        The force-in ``harmonic`` likelihood always samples alpha.
    normaliser : motion-in likelihood only: the Gaussian normaliser's noise variance.
        "reference" (default): the noise at a reference point, the start search's
        optimum (**assumption**; :mod:`.motion` explains why: with the parameters' own,
        the measured motion's noise pulls b low); "full": the parameters' own.
    delay_sd : motion-in likelihood only: the prior sd (s) of ``delay``, the force
        channel's delay behind the acceleration channel's (a conditioning amplifier's or
        converter's latency the time stamps do not show), sampled with a normal prior
        about 0; the predicted force at harmonic k is turned by exp(-i w_k delay).
        Default None: ``DELAY_SD`` (0.5 ms, **assumption**: sensors' conditioning and
        filters of unequal bandwidth, whose group delays differ by tens to hundreds of
        microseconds) for the motion-in likelihood, none for the others; 0: the
        channels taken as simultaneous.
    reversals : motion-in likelihood only: marginalise the friction's deviations in
        windows around the plate's velocity reversals (:mod:`.reversals`; default True).
        False leaves them out (a diagnostic: with ``law`` False too the likelihood
        marginalises no deviation, only the noise and the discrepancy tau remain).
    law : motion-in likelihood only: marginalise an odd deviation of the plate's friction
        from Coulomb's and the viscous law, a function of the measured velocity
        (:mod:`.friction_law`; default True).
    law_orthogonal : motion-in likelihood only: take the plate's own Coulomb and viscous
        harmonics out of the law's deviations (``friction_law.beyond``), so that a
        deviation cannot make the force that f1_0 and c_f1 make (default True). Left
        in, the deviations and the friction's parameters explain the same force, and on
        the model's own records the friction came out low and the viscous damping high.
    input_noise : motion-in likelihood only: draws of the measured motion's noise pushed
        through the model at the reference point (``input_noise_form`` says how they
        enter); 0: none. Default None (**assumption**, chosen on design seeds,
        docs/inference.md): :data:`INPUT_NOISE_DRAWS` (16) wherever there is a reference
        point (:meth:`input_noise_draws`). The drivetrain's simulation passes the
        motion's noise on nonlinearly (the rotation sticks and slips, a lightly damped
        bearing rings): on records whose friction is large against the inertia the truth
        sat tens to hundreds of nats below the optimum without the draws. Needs the
        reference point (``normaliser`` or ``deviation_scale`` "reference"); None takes
        none where there is no reference point.
    input_noise_form : how the draws of ``input_noise`` enter. "shapes" (default,
        **assumption**, chosen on design seeds, docs/inference.md): the draws themselves
        among the marginalised deviations, so that their covariance across the
        harmonics is kept (``motion.input_noise_shapes``): a rotation that slips a
        little earlier or later moves every harmonic at once. "variance": their variance
        beyond the linear term added to each V_k (``motion.input_noise_variance``), the
        earlier form, which on the record examined overstated the noise at the low
        harmonics and understated it where the drivetrain rang.
    law_beyond_viscous : with ``law_orthogonal``, take the plate's viscous harmonics out
        as well as its Coulomb square wave (default True). False leaves the deviations
        free to carry a force in phase with the velocity, which a friction that falls
        with speed (Stribeck's) needs and the viscous term, never negative, cannot make.
    deviation_scale : motion-in likelihood only: whose Coulomb forces scale the
        marginalised deviations' prior sd (the reversals' and the law's).
        "reference" (default): the reference point's, the start search's optimum
        (**assumption**: an empirical-Bayes scale); "parameters": each walker's own,
        whose Gaussian normaliser then pulls the sampled friction low.
    reversal_scale : motion-in likelihood only: the Coulomb force in the prior sd of the
        friction's deviations at the plate's reversals (``reversals.SD`` times it):
        "total" (default), f1_0 + f2_0, or "plate", f1_0 alone, the earlier default.
        Under ``deviation_scale="reference"`` the forces are the reference's, and the
        split of the Coulomb force between plate and rotation is what a record tells
        least: a reference with the friction on the rotation left the reversals no
        room for the plate's (docs/inference.md, "The reversals' scale").
    law_sampled : with ``law``, sample the law's deviations' prior sd as a share of the
        Coulomb forces (the likelihood's parameter ``law``, prior
        ``priors.MOTION_DISCREPANCY_PRIORS["law"]``) in place of the fixed
        ``friction_law.SD`` (default False: fixed). Where the records carry no
        deviation (the model's own physics) the posterior can shrink it, and with it
        the room it gives the friction's parameters.
    form_sd : motion-in likelihood only: the model-form uncertainty of b, a relative sd
        (**assumption**; default 0: none). A richer device's inertance differs from the
        two-port model's effective one by a factor exp(eps), eps normal with this sd;
        the likelihood marginalises eps to first order, as a deviation along the predicted
        force's derivative in log b at the reference point (``motion.form_shape``), so
        that b's posterior, and every parameter's that moves with it, widens inside the
        chain. Needs the reference point (``normaliser`` or ``deviation_scale``
        "reference").
    form_friction : motion-in likelihood only: a further model-form error along the same
        direction, scaled by the friction, not by b (**assumption**; default 0: none):
        at the fundamental it is this share of the Coulomb forces f1_0 + f2_0 (the
        reference point's), so it widens b most where the friction is large against the
        inertia (a break-away the Coulomb law lacks reads as inertance there). Needs the
        reference point, as ``form_sd``.
    """

    residual: str = "motion"
    cutoff: float = LOWPASS_HZ
    stride: int | None = None
    edge: float = 0.25
    upsample: int = 1
    sampling: str = "mean"
    pool: int = 2
    settle: int = 1
    gain_sd: float = SensorCalibration().ratio_sd
    decay: bool = False
    normaliser: str = "reference"
    law: bool = True
    reversals: bool = True
    delay_sd: float | None = None
    law_orthogonal: bool = True
    law_beyond_viscous: bool = True
    input_noise: int | None = None
    input_noise_form: str = "shapes"
    deviation_scale: str = "reference"
    reversal_scale: str = "total"
    law_sampled: bool = False
    form_sd: float = 0.0
    form_friction: float = 0.0

    @property
    def sampled_delay_sd(self) -> float:
        """The prior sd of the sampled channel delay, s (0: none sampled)."""
        if self.residual != "motion":
            return 0.0
        return DELAY_SD if self.delay_sd is None else float(self.delay_sd)

    def input_noise_draws(self) -> int:
        """The draws of the measured motion's noise a fit takes (``input_noise``; None: 16
        under the motion-in likelihood with a reference point, else 0)."""
        if self.input_noise is not None:
            return self.input_noise
        has_reference = "reference" in (self.normaliser, self.deviation_scale)
        return INPUT_NOISE_DRAWS if self.residual == "motion" and has_reference else 0

    @property
    def hyper_names(self) -> tuple[str, ...]:
        """The sampled parameters of the likelihood itself, after the physical ones (the
        motion-in likelihood's discrepancy is white, alpha 0, unless ``decay``)."""
        if self.residual in ("harmonic", "motion"):
            decay = self.residual == "harmonic" or self.decay
            delay = self.residual == "motion" and self.sampled_delay_sd > 0
            law = self.residual == "motion" and self.law and self.law_sampled
            return (("tau",) + (("alpha",) if decay else ()) + (("gain",) if self.gain_sd > 0 else ())
                    + (("delay",) if delay else ()) + (("law",) if law else ()))
        return ("sigma", "rho") if self.residual == "ar1" else ("sigma",)

    def __post_init__(self) -> None:
        if self.residual not in RESIDUALS:
            raise ValueError(f"residual model must be one of {', '.join(RESIDUALS)}, got {self.residual!r}")
        if not (isinstance(self.pool, int) and self.pool >= 0):
            raise ValueError(f"pool must be a whole number >= 0, got {self.pool!r}")
        if not (isinstance(self.settle, int) and self.settle >= 0):
            raise ValueError(f"settle must be a whole number >= 0, got {self.settle!r}")
        if self.input_noise is not None and not (isinstance(self.input_noise, int)
                                                 and not isinstance(self.input_noise, bool) and self.input_noise >= 0):
            raise ValueError(f"input_noise must be a whole number of draws >= 0 (or None), got {self.input_noise!r}")
        if self.input_noise and "reference" not in (self.normaliser, self.deviation_scale):
            raise ValueError("input_noise needs the reference point: normaliser or deviation_scale 'reference' "
                             "(or input_noise=0)")
        if self.input_noise_form not in INPUT_NOISE_FORMS:
            raise ValueError(f"input_noise_form must be one of {', '.join(INPUT_NOISE_FORMS)}, "
                             f"got {self.input_noise_form!r}")
        if self.normaliser not in NORMALISERS:
            raise ValueError(f"normaliser must be one of {', '.join(NORMALISERS)}, got {self.normaliser!r}")
        if self.deviation_scale not in DEVIATION_SCALES:
            raise ValueError(f"deviation_scale must be one of {', '.join(DEVIATION_SCALES)}, "
                             f"got {self.deviation_scale!r}")
        if self.reversal_scale not in REVERSAL_SCALES:
            raise ValueError(f"reversal_scale must be one of {', '.join(REVERSAL_SCALES)}, "
                             f"got {self.reversal_scale!r}")
        if self.delay_sd is not None and not (0 <= self.delay_sd < 0.01):
            raise ValueError(f"delay_sd must lie in [0, 0.01) s, got {self.delay_sd}")
        if self.delay_sd and self.residual != "motion":
            raise ValueError("delay_sd needs the motion-in likelihood (residual='motion')")
        if self.law_sampled and not (self.law and self.residual == "motion"):
            raise ValueError("law_sampled needs the friction law's deviations (law=True) and the motion-in "
                             "likelihood (residual='motion')")
        for name, top, what in (("form_sd", 0.2, "a relative sd"), ("form_friction", 0.5, "a share of the Coulomb force")):
            value, option = getattr(self, name), "--" + name.replace("_", "-")
            if not (isinstance(value, numbers.Real) and not isinstance(value, bool) and 0 <= value < top):
                raise ValueError(f"{name} (fit {option}) must be {what} in [0, {top:g}), such as 0.005, got {value!r}")
            if value and self.residual != "motion":
                raise ValueError(f"{name} (fit {option}) needs the motion-in likelihood (residual='motion', "
                                 "fit --residual motion)")
        if (self.form_sd or self.form_friction) and "reference" not in (self.normaliser, self.deviation_scale):
            raise ValueError("form_sd and form_friction need the reference point: normaliser or deviation_scale "
                             "'reference' (or both 0)")
        if not (0 <= self.gain_sd < 1):
            raise ValueError(f"gain_sd must lie in [0, 1), got {self.gain_sd}")
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


def ar1_pointwise(residual: np.ndarray, sigma: float, rho: float = 0.0) -> np.ndarray:
    """Log-density of each residual of a stationary AR(1) process with innovation sd
    ``sigma`` and coefficient ``rho`` (the first unconditional, each later one given the
    one before); rho = 0 is white noise."""
    var = sigma * sigma
    if rho == 0.0:
        return -0.5 * (residual * residual / var + math.log(2 * math.pi * var))
    out = np.empty_like(residual)
    var0 = var / (1 - rho * rho)
    out[0] = -0.5 * (residual[0] ** 2 / var0 + math.log(2 * math.pi * var0))
    innov = residual[1:] - rho * residual[:-1]
    out[1:] = -0.5 * (innov * innov / var + math.log(2 * math.pi * var))
    return out


def ar1_marginal(residual: np.ndarray, rho: float) -> float:
    """log p(residual | rho) of a stationary AR(1) process with its scale sigma
    marginalised under the prior p(sigma) ~ 1/sigma:

        log p = 0.5 log(1 - rho^2) + lgamma(n/2) - log 2 - (n/2) log(pi S),
        S = (1 - rho^2) r_0^2 + sum_t (r_t - rho r_{t-1})^2
    """
    r = np.asarray(residual, dtype=float)
    n = len(r)
    one = 1.0 - rho * rho
    innov = r[1:] - rho * r[:-1]
    s = one * r[0] * r[0] + float(innov @ innov)
    if not s > 0:
        return -math.inf
    return 0.5 * math.log(one) + math.lgamma(0.5 * n) - math.log(2.0) - 0.5 * n * math.log(math.pi * s)


def settings_changes(text: str) -> dict:
    """``name=value,...`` (values as JSON: 16, false, "plate") as a dict of changes of
    :class:`LikelihoodSettings`; "" or "default": none. Raises ValueError on a pair
    without "=", a name it lacks or a value it refuses (before any fit)."""
    changes = {}
    if text and text != "default":
        for part in text.split(","):
            name, sep, value = part.partition("=")
            if not sep:
                raise ValueError(f"likelihood changes are name=value pairs, got {part!r}")
            try:
                changes[name.strip()] = json.loads(value)
            except ValueError:
                raise ValueError(f"the value of {name.strip()} is not JSON: {value!r}") from None
    try:
        LikelihoodSettings(**changes)
    except TypeError as exc:
        raise ValueError(f"not a likelihood setting: {exc}") from None
    return changes
