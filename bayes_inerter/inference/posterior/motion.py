"""Motion in, force out: the harmonic likelihood of the force given the measured motion.

A displacement-controlled test prescribes the motion of terminal 1; the device answers
with a force. Over the record's whole steady drive periods (``harmonic.harmonic_data``)
the measured acceleration's harmonics A_k give the plate's periodic motion,
V_k = A_k / (i k omega), and the two-port model (MODEL.md section 2) then gives the force
at terminal 1 harmonic by harmonic, the plate's side by impedance algebra (the
drivetrain's rotation, which sticks and slips, is simulated: below):

    z_B = c_B + k_B / (i w),  z_n = c_n + k_n / (i w),  y = i w b + c_f2
    Z_f = z_n y / (z_n + y),  g = z_n / (z_n + y)           (nut in series with the rotation)
    V_s = (z_B V - g F_2) / (z_B + i w m_s + Z_f)            (the screw's translation)
    F   = (i w m_B + c_f1) V + f1_0 S + z_B (V - V_s)

S_k are the harmonics of sgn(v_B(t)), the plate's Coulomb force's square wave, and F_2
the rotation's Coulomb force. The plate's friction switches when the plate's velocity
changes sign, read from the measured motion reconstructed up to ``sign_band``
(**assumption**, default 100 Hz: the switches' timing sets the friction's phase, and a
band of 30 Hz moved the apparent mass at 1 Hz by 0.5 % on the generator's noise-free
records, 100 Hz by 0.03 %).

The rotation is not prescribed: it lags the plate through the nut (by about
f2_0 / c_n in velocity, and it sticks at each reversal until the nut's force exceeds
f2_0). Where f2_0 > 0 the drivetrain behind the plate (the screw's translation and
rotation, Coulomb friction on the rotation, set-valued) is therefore **simulated**, driven
by the measured plate velocity on ``DRIVE_GRID`` points a period with the exact kernel
(``simulate.exact_runner``), from the linear periodic state for ``DRIVE_SETTLE`` periods,
then with Newton steps on the periodic state (the period map's monodromy: the linear
flow between the rotation's reversals and each reversal's saltation) until one finds a
period's end within ``DRIVE_TOL / 2`` of it, the next period then taken; where the
rotation sticks, a period at a time until two successive periods' bearing force agree
(``DRIVE_TOL``, at most ``DRIVE_MAX_PERIODS`` in all). The bearing's force z_B (V - V_s)
is taken from the last period. The
Newton steps matter where the flywheel rings on the nut and the bearing, lightly damped:
simulated period by period such a drivetrain approaches its periodic state by a factor of
about 0.8 a period. This replaced
the algebra's F_2 = f2_0 S (the rotation reversing with the plate), which on a
noise-free generator record of a rotation with f2_0 = 2,000 N behind a soft nut
missed the measured force by 144 N rms a harmonic at the truth, the simulation by
0.13 N (``tests/test_inference_motion.py``).

Inside a short window around each of the plate's reversals the motion does not fix the
plate's friction (a stuck plate, a noisy zero crossing): there S_k is formed with one
switch at the window's middle, and the friction's deviation from it is marginalised
(:mod:`.reversals`, its term added to the harmonics' log-likelihood in equal shares).
Over the whole period the friction may also deviate from the model's law by an odd
function of the measured velocity (:mod:`.friction_law`, ``LikelihoodSettings.law``),
its amplitudes marginalised in the same closed form.
That function is taken beyond the model's own law: the plate's Coulomb and viscous
harmonics are projected out of it (``LikelihoodSettings.law_orthogonal``), so that it
cannot make the force f1_0 and c_f1 make. The deviations' prior sd scales with the
Coulomb forces of the reference point (the start search's optimum,
``LikelihoodSettings.deviation_scale``), not with each walker's: with the walker's own,
the Gaussian normaliser of the deviations, -1/2 log det(I + s^2 U' D^-1 U), rewards a
small friction. On the model's own records (simulation-based calibration, 6 chains)
the two together left f_0's and c_f's truth outside every 50 % interval, f_0 mostly
above the draws and c_f below; on a
rigid device with Coulomb friction alone the maximum-likelihood f1_0 lay 5 % low with
the law's deviations free to mimic the square wave, within its noise without
(``tests/test_inference_motion.py``).

The force channel's delay d behind the acceleration channel's is sampled
(``LikelihoodSettings(delay_sd=...)``, a normal prior of sd 0.5 ms by default; 0 takes
the channels as simultaneous): the predicted force and its transfer are turned by
exp(-i w_k d) (a latency the time stamps do not show turns friction, in phase with the
velocity, into the inertial phase by w d). Two sensors of unequal bandwidth make one:
on the generator's noise-free record of A2 at 1 Hz (load cell 2 kHz, accelerometer
5 kHz, a 68 us difference of group delay) b's optimum was -0.30 % with the channels
taken as simultaneous, -0.11 % with ideal sensors, and -0.002 % with the delay sampled.

The plate's mode and its chatter leave the likelihood (only the drivetrain behind the
plate is simulated, driven by the measured motion); what the data cannot pin (the
bearing) stays with its prior. The residual F_k - F^_k(theta) is complex normal with

    V_k = (s2_F,k + |Y_k / g|^2 s2_A,k - 2 Re(Y_k c_k / g)) / P  +  tau^2 k^(-2 alpha)

Y_k = dF^_k / dA_k the model's linear transfer from the measured acceleration to the
predicted force (its noise enters the prediction: errors in both signals), g the
acceleration channel's gain relative to the force's, c_k = E[(A - A_k) conj(F - F_k)],
and tau (N) the model's discrepancy, sampled (alpha 0, a white discrepancy, unless
``LikelihoodSettings(decay=True)`` samples it too).

    log L = sum_k [ -log(pi W_k) - |F_k - F^_k|^2 / V_k ]

The normaliser W_k is where an errors-in-variables likelihood goes wrong. With W_k = V_k
(the Gaussian's own) the noise of the measured motion, |Y_k / g|^2 s2_A,k / P, makes
-log W_k fall as b rises, at every harmonic where that noise is most of V_k: a pull
towards a small b that no data term balances (the expected score at the truth is
-d log V_k / d theta, not 0). The quadratic term alone is unbiased (the sample
maximum-likelihood estimator of Pintelon and Schoukens divides by V_k and has no
normaliser), but tau needs a normaliser to have a scale. So W_k takes the noise at a
**reference** point theta_ref, W_k = noise_k(theta_ref) + tau^2 k^(-2 alpha): no pull
on the physical parameters, and tau's scale right near theta_ref (``PosteriorModel.
with_reference``; the sampler takes the start search's optimum, **assumption**,
``LikelihoodSettings(normaliser="full")`` restores W_k = V_k). Measured on one rigid
device whose motion's noise is most of the variance (``tests/test_inference_motion.py``,
40 records): the maximum-likelihood mass -4.57 +- 0.47 % with W_k = V_k, +0.14 +- 0.49 %
with the reference. The joint model takes each record's at its part of the joint
start (``JointModel.with_reference``).

The measured motion's noise also drives the simulated drivetrain, whose rotation sticks
and slips and whose bearing may ring, and comes out of it beyond the linear term. At the
reference point 16 seeded draws of that noise are pushed through the model
(:func:`input_noise_shapes`) and each draw's force error is a further marginalised
deviation, so that the errors' covariance across the harmonics is kept
(``LikelihoodSettings.input_noise_form``; :func:`input_noise_variance`, one variance per
harmonic, is the earlier form).

The fit accuracy reported with
each evaluation is the force's at the harmonics, 1 - |F - F^| / |F| over k = 1..K
(Parseval's: the periodic part's phi, not the paper's phi of the acceleration).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
import threadpoolctl
from numba import njit

from ...friction import Coulomb, Stribeck
from ...network import CompiledNetwork
from ...networks import FIELDS
from ...records.record import Record
from ...simulate import SimulationError, exact_runner, piecewise_runner
from .effects import NO_EFFECT
from .harmonic import HarmonicData, at_times, harmonic_data
from .likelihood import REVERSAL_SCALES
from . import friction_law
from .reversals import SD, deviations_mean, switched_sign, reversal_correction, reversal_windows, window_basis

__all__ = ["MotionData", "motion_data", "predicted_force", "deviation_sd", "bearing_force", "motion_variance", "motion_loglik",
           "input_noise_variance", "input_noise_shapes", "with_input_noise", "with_input_shapes", "INPUT_NOISE_SEED",
           "fundamental_misfit", "plate_hump", "form_shape", "form_columns", "FORM_STEP", "SIGN_BAND", "SIGN_GRID", "DRIVE_GRID", "DRIVE_SETTLE", "DRIVE_TOL",
           "DRIVE_MAX_PERIODS", "ORDER", "FUNDAMENTAL_MAX"]

#: **Assumption** of the reporting: b is called identified only where the fit reproduces
#: the fundamental's force in phase with the acceleration (the inertial force, which b
#: makes) to within this share. Where it does not, the posterior's b is set by the
#: harmonics above, whose inertial content a richer device need not share with the
#: model (its nut's backlash keeps the plate's reversal jerks from the flywheel).
FUNDAMENTAL_MAX = 0.1

#: **Assumption**: the band of the measured motion whose sign times the Coulomb forces, Hz.
SIGN_BAND = 100.0
#: Points per period on which the sign's square wave is formed before its harmonics are taken.
SIGN_GRID = 8192
#: Points per period on which the drivetrain behind the plate is simulated (the bearing's
#: force changed by under 0.1 N between 1024 and 16384 on the records checked).
DRIVE_GRID = 2048
#: Periods the drivetrain is simulated, from the linear periodic state, before its first
#: Newton step (``bearing_force``).
DRIVE_SETTLE = 1
#: **Assumption**: the drivetrain is simulated until its bearing force is periodic to
#: ``DRIVE_TOL`` (N) at every harmonic, at most ``DRIVE_MAX_PERIODS`` periods in all:
#: until a Newton step on the periodic state (``bearing_force``) finds a period's end
#: within ``DRIVE_TOL / 2`` of it (the next period is then taken), or, where the rotation
#: sticks within a period (the step's monodromy assumes it slides) or the steps stop
#: converging, until two successive periods' bearing force differs by at most
#: ``DRIVE_TOL``. Without the Newton steps a lightly damped drivetrain converges slowly:
#: on a heavy rotation with a large drag behind a soft nut
#: (``tests/test_inference_motion.py``: b 18.5 t, c_f2 12.9 kN s/m, k_n 5.5e4 N/m, f2_0
#: 3.0 kN, 1 Hz) one settling period left the bearing's force 3.8 N from its periodic
#: value at a harmonic; on the posterior draws of a paper-like A3 record at 1 Hz, where
#: the flywheel rings on the nut and the bearing at a damping ratio of 0.1 to 1 %, eight
#: plain periods left it up to 90 N from a 300-period run (7.8 N at the 90th
#: percentile), the Newton steps 0.02 N at most (``docs/inference.md``).
DRIVE_TOL = 0.005
DRIVE_MAX_PERIODS = 8
#: The richer models' drivetrain (a Stribeck law on the rotation, a dead zone in the
#: nut): at most this many periods simulated, the finite differences' included
#: (``_periodic_by_differences``), and each difference's step as a share of its state's
#: largest value over the period (with ``_FD_FLOOR`` below it).
DRIVE_MAX_PERIODS_EFFECTS = 40
DRIVE_FD_STEP = 1e-6
_FD_FLOOR = np.array([1e-6, 1e-6, 1e-12, 1e-12])  # m/s, m/s, m, m
#: The seed of :func:`input_noise_variance`'s draws of the measured motion's noise
#: (**assumption**: any fixed seed; the same record and reference give the same variance).
INPUT_NOISE_SEED = 0


@dataclass(frozen=True)
class MotionData:
    """What the motion-in likelihood needs of a record: the harmonic data (force and
    acceleration, their scatter), the plate's velocity harmonics and the sign's."""

    harmonic: HarmonicData
    velocity: np.ndarray  # (K,) complex, m/s: A_k / (i k omega)
    sign: np.ndarray  # (K,) complex: harmonics of sgn(v_B(t))
    omega: np.ndarray  # (K,) rad/s
    drive: np.ndarray  # (DRIVE_GRID,) m/s: the plate's velocity over one period from t = 0
    basis: np.ndarray  # (2K, m): the marginalised deviations, the reversals', the law's, the input noise's
    scale: np.ndarray  # (m, 3): each deviation's prior sd is scale[j] . (f1_0, f2_0, 1), N
    windows: tuple = ()  # the reversals' windows, shares of the period (``reversals.reversal_windows``)
    #: (m,) bool: the columns of ``basis`` that are the friction law's deviations (their
    #: prior sd scaled by a sampled ``law`` where the likelihood samples one); None: none
    law_columns: np.ndarray | None = None
    #: the plate motion's reconstruction: its harmonics (rad/s, the first K are ``omega``'s)
    #: and the variance of each one's period mean, (m/s^2)^2 (:func:`input_noise_variance`)
    fine_omega: np.ndarray | None = None
    fine_var: np.ndarray | None = None

    @functools.cached_property
    def drive_sign(self) -> np.ndarray:
        """sgn of ``drive`` with one switch in each reversal window (``sign``'s square
        wave on the drivetrain's grid): where the plate's Stribeck hump switches."""
        return switched_sign(self.drive, self.windows)

    @functools.cached_property
    def period_input(self) -> np.ndarray:
        """The drivetrain simulation's input over one period: ``drive`` and the next
        period's first sample, as a column."""
        return np.append(self.drive, self.drive[0]).reshape(-1, 1)

    @property
    def harmonics(self) -> int:
        return self.harmonic.harmonics


def _plate_motion(record: Record, freq: float, band: float, pool: int, settle: int):
    """The measured plate velocity and acceleration reconstructed up to ``band`` (each a
    function of the points per period) and the velocity's noise sd (m/s) there."""
    fine = harmonic_data(record, freq, cutoff=min(band, 0.45 * record.fs), pool=pool, settle=settle)
    V = fine.accel / (1j * fine.omega)
    sigma_v = math.sqrt(float(np.sum(fine.var_accel / fine.omega ** 2)) / (2.0 * fine.periods))

    def on_grid(X):
        return lambda n: at_times(X, fine.omega, np.arange(n) / (n * freq))

    return on_grid(V), on_grid(fine.accel), sigma_v, (fine.omega, fine.var_accel / fine.periods)


def motion_data(record: Record, freq: float, *, cutoff: float, pool: int = 2, settle: int = 1,
                sign_band: float = SIGN_BAND, law: bool = True, law_orthogonal: bool = True,
                law_beyond_viscous: bool = True, reversal_scale: str = "total",
                reversals: bool = True) -> MotionData:
    """:class:`MotionData` of ``record`` driven at ``freq`` Hz (see module docstring);
    ``reversals``: marginalise the friction's deviations at the plate's reversals
    (False leaves them out of the basis; the windows still place the sign's switches);
    ``law_orthogonal``: the law's deviations with the plate's own Coulomb and viscous
    harmonics taken out (``friction_law.beyond``), the viscous ones only where
    ``law_beyond_viscous``; ``reversal_scale``: the reversals'
    deviations scaled by the plate's Coulomb force ("plate") or by the plate's and the
    rotation's ("total"; ``LikelihoodSettings.reversal_scale``)."""
    if reversal_scale not in REVERSAL_SCALES:
        raise ValueError(f"reversal_scale must be one of {', '.join(REVERSAL_SCALES)}, got {reversal_scale!r}")
    # on one BLAS thread whatever the process's: the basis's digits (which a checkpoint's
    # identity hashes) would otherwise depend on how many threads its SVDs ran on, and a
    # fit made in a study's worker (its share of the cores) be refused by `report` after
    with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
        return _motion_data(record, freq, cutoff, pool, settle, sign_band, law, law_orthogonal, law_beyond_viscous,
                            reversal_scale, reversals)


def _motion_data(record, freq, cutoff, pool, settle, sign_band, law, law_orthogonal, law_beyond_viscous,
                 reversal_scale, reversals) -> MotionData:
    data = harmonic_data(record, freq, cutoff=cutoff, pool=pool, settle=settle)
    velocity, accel, sigma_v, (fine_omega, fine_var) = _plate_motion(record, freq, max(sign_band, cutoff), pool, settle)
    v = velocity(SIGN_GRID)
    windows = tuple(reversal_windows(v, accel(SIGN_GRID), sigma_v, 1.0 / freq))
    switched = switched_sign(v, windows)
    sign = (np.fft.rfft(switched) / SIGN_GRID * 2.0)[1: data.harmonics + 1]
    K = data.harmonics
    V = data.accel / (1j * data.omega)  # the plate's velocity at the harmonics
    # each part: its deviations' basis, their prior sd's shares, whether they are the law's
    parts = []
    if reversals:
        parts.append((window_basis(windows, K), (SD, SD if reversal_scale == "total" else 0.0, 0.0), False))
    if law:
        U = friction_law.law_basis(v, switched, K)
        if law_orthogonal:
            U = friction_law.beyond(U, sign, V) if law_beyond_viscous else friction_law.beyond(U, sign)
        parts.append((U, (friction_law.SD, friction_law.SD, 0.0), True))
    basis = np.hstack([U for U, _, _ in parts]) if parts else np.zeros((2 * K, 0))
    scale = np.array([c for U, c, _ in parts for _ in range(U.shape[1])], dtype=float).reshape(-1, 3)
    law_columns = np.concatenate([np.full(U.shape[1], is_law) for U, _, is_law in parts] or [np.zeros(0, bool)])
    return MotionData(data, V, sign, data.omega, velocity(DRIVE_GRID),
                      basis, scale, windows, law_columns, fine_omega, fine_var)


#: The physical parameters in the order the compiled kernels unpack them: ``networks.FIELDS``'s.
ORDER = ("b", "m_s", "m_B", "c_n", "k_n", "c_B", "k_B", "f1_0", "c_f1", "f2_0", "c_f2")
if ORDER != FIELDS:  # the model hands the kernels its field vector as it is
    raise ImportError("motion.ORDER must be networks.FIELDS")


@njit(cache=True)
def _screw(iw, V, F2, x):
    """The module docstring's algebra at one harmonic (iw = i w): the screw's translation
    V_s for the plate's velocity V and the rotation's Coulomb force F2, with the link
    impedances z_B, z_n, the rotation's admittance y and the denominator it uses."""
    b, m_s, c_n, k_n, c_B, k_B, c_f2 = x[0], x[1], x[3], x[4], x[5], x[6], x[10]
    z_B = c_B + k_B / iw
    z_n = c_n + k_n / iw
    y = iw * b + c_f2
    den = z_B + iw * m_s + z_n * y / (z_n + y)
    return (z_B * V - z_n / (z_n + y) * F2) / den, z_B, z_n, y, den


@njit(cache=True)
def _predicted(x, gain, omega, velocity, sign, bearing, simulated, delay, hump):
    """(F^_k, Y_k) of the module docstring for the parameters ``x`` in :data:`ORDER`;
    with ``simulated``, the bearing's force is ``bearing`` (the drivetrain's simulation);
    ``hump`` the plate's friction beyond its Coulomb square wave (a Stribeck law's, N;
    zeros for the paper's law); both as the force channel records them ``delay`` s after
    the acceleration channel."""
    m_B, f1_0, c_f1, f2_0 = x[2], x[7], x[8], x[9]
    K = omega.shape[0]
    F = np.empty(K, dtype=np.complex128)
    Y = np.empty(K, dtype=np.complex128)
    for k in range(K):
        iw = 1j * omega[k]
        V = velocity[k] / gain
        V_s, z_B, _, _, den = _screw(iw, V, f2_0 * sign[k], x)
        plate = (iw * m_B + c_f1) * V + f1_0 * sign[k] + hump[k]
        late = np.exp(-iw * delay) if delay != 0.0 else 1.0 + 0.0j
        F[k] = (plate + (bearing[k] if simulated else z_B * (V - V_s))) * late
        Y[k] = (iw * m_B + c_f1 + z_B * (1.0 - z_B / den)) / iw / gain * late
    return F, Y


@njit(cache=True)
def _variance(Y, tau, alpha, var_force, var_accel, cov, periods):
    """V_k of the module docstring, from the transfer Y_k."""
    K = Y.shape[0]
    V = np.empty(K)
    for k in range(K):
        noise = (var_force[k] + (Y[k].real ** 2 + Y[k].imag ** 2) * var_accel[k]
                 - 2.0 * (Y[k] * cov[k]).real) / periods
        V[k] = max(noise, 0.0) + tau * tau * (k + 1.0) ** (-2.0 * alpha)
    return V


@njit(cache=True)
def _deviation_sd(scale, x):
    """Each marginalised deviation's prior sd, N: ``scale[j] . (f1_0, f2_0, 1)``."""
    return scale[:, 0] * x[7] + scale[:, 1] * x[9] + scale[:, 2]


def deviation_sd(data: MotionData, p, law: float | None = None) -> np.ndarray:
    """(m,) N: the prior sd of each deviation the likelihood marginalises (the columns of
    ``data.basis``) at the physical parameters ``p`` (by name, or a vector in
    :data:`ORDER`), the law's scaled by a sampled ``law`` where given."""
    return _deviation_sd(data.scale, _vector(p)) * _factors(data, law)


def _factors(data: MotionData, law: float | None) -> np.ndarray:
    """Each marginalised deviation's multiplier of its prior sd: ``law`` /
    ``friction_law.SD`` on the law's columns where ``law`` (a sampled share of the
    Coulomb forces) is given, 1 elsewhere."""
    factor = np.ones(data.basis.shape[1])
    if law is not None and data.law_columns is not None:
        factor[data.law_columns] = float(law) / friction_law.SD
    return factor


@njit(cache=True)
def _terms(x, tau, alpha, gain, omega, velocity, sign, bearing, simulated, hump, basis, scale, force, var_force,
           var_accel, cov, periods, reference, delay, sd_at, factor):
    """Each harmonic's log-likelihood term (the reversals' marginal in equal shares), and
    the squared residuals' and the force's sums; the deviations' prior sd is taken at
    the parameters ``sd_at`` (``x`` itself, or a reference point's), times ``factor``."""
    F, Y = _predicted(x, gain, omega, velocity, sign, bearing, simulated, delay, hump)
    V_all = _variance(Y, tau, alpha, var_force, var_accel, cov, periods)
    K = omega.shape[0]
    ok = True
    for k in range(K):
        if not V_all[k] > 0:
            ok = False
    s = _deviation_sd(scale, sd_at) * factor
    share = reversal_correction(basis, V_all, force - F, s) / K if ok else 0.0
    terms = np.empty(K)
    sq_sum = 0.0
    f_sum = 0.0
    for k in range(K):
        V = V_all[k]
        r = force[k] - F[k]
        sq = r.real ** 2 + r.imag ** 2
        W = V if reference[k] < 0.0 else reference[k] + tau * tau * (k + 1.0) ** (-2.0 * alpha)
        terms[k] = -np.log(np.pi * W) - sq / V + share if V > 0 and W > 0 else -np.inf
        sq_sum += sq
        f_sum += force[k].real ** 2 + force[k].imag ** 2
    return terms, sq_sum, f_sum


def _vector(p) -> np.ndarray:
    return p if isinstance(p, np.ndarray) else np.array([float(p[n]) for n in ORDER])


def _effects(effects) -> tuple[float, float, float]:
    """(r_s, v_s, gap) of the richer models' ``effects`` (a dict; what it lacks, and
    None, as ``effects.NO_EFFECT``: the paper's Coulomb law, no backlash)."""
    e = {**NO_EFFECT, **(effects or {})}
    return float(e["r_s"]), float(e["v_s"]), float(e["gap"])


def plate_hump(data: MotionData, p, gain: float = 1.0, effects=None) -> np.ndarray:
    """(K,) complex, N: the harmonics of the plate's friction beyond its Coulomb square
    wave f1_0 sgn(v) under the richer models' Stribeck law (``effects``' r_s, v_s; zeros
    for r_s = 1): f1_0 (g(|v|) - 1) sgn(v), g the law over its Coulomb level in the
    simulator's piecewise-linear form (``friction.Stribeck.piecewise``), v the measured
    plate velocity on the drivetrain's grid and the sign switched as ``sign``'s is
    (``MotionData.drive_sign``). The plate's motion is measured, so its friction is a
    known function of it and needs no simulation."""
    r_s, v_s, _ = _effects(effects)
    x = _vector(p)
    K = data.harmonics
    if r_s <= 1.0 or x[7] <= 0.0:
        return np.zeros(K, dtype=np.complex128)
    law = Stribeck(1.0, r_s, v_s).piecewise()
    level = np.interp(np.abs(data.drive / gain), law.speeds, law.forces) - 1.0  # beyond the last knot: 0
    wave = x[7] * level * data.drive_sign
    return np.fft.rfft(wave)[1: K + 1] / wave.shape[0] * 2.0


def _drivetrain_runner(x, A, B, h, r_s, v_s, gap):
    """The drivetrain's simulation (``exact_runner``'s callable): the Coulomb kernel for
    the paper's law, else the exact kernel's piecewise-linear form with the rotation's
    Stribeck law (break-away r_s f2_0, over v_s) and the nut's dead zone of half-width
    ``gap`` (the drivetrain's states are a chain's: screw, rotation, the nut's
    deflection, then the bearing's)."""
    b, m_s, c_n, k_n, f2_0, c_f2 = x[0], x[1], x[3], x[4], x[9], x[10]
    if r_s <= 1.0 and gap <= 0.0:
        return exact_runner(A, B, _ROTATION, np.array([f2_0]), np.array([b]), h)
    law = Stribeck(f2_0, r_s * f2_0, v_s, c_f2) if r_s > 1.0 else Coulomb(f2_0, c_f2)
    chain = CompiledNetwork(np.array([m_s, b]), np.array([c_n]), np.array([k_n]), np.array([gap]),
                            ((), (law,) if f2_0 > 0.0 else ()), name="drivetrain")
    return piecewise_runner(chain, A, B, h)


def bearing_force(data: MotionData, p, gain: float = 1.0, effects=None):
    """The bearing's force z_B (V - V_s) at the harmonics 1..K from the simulated
    drivetrain (see module docstring), or None where the rotation has no Coulomb force
    and the nut no backlash (f2_0 = 0, gap = 0: the algebra is then exact). ``p`` as for
    :func:`predicted_force`; ``effects``: the richer models' (``plate_hump``), whose
    rotation's Stribeck law and nut's dead zone the simulation takes, its periodic state
    then found with a Jacobian by finite differences (``_periodic_by_differences``).
    ``simulate.SimulationError`` where the rotation's contact chatters."""
    x = _vector(p)
    b, c_B, k_B, f2_0 = x[0], x[5], x[6], x[9]
    r_s, v_s, gap = _effects(effects)
    if f2_0 <= 0.0 and gap <= 0.0:
        return None
    v = data.drive / gain
    N = v.shape[0]
    freq = data.omega[0] / (2.0 * math.pi)
    x0 = _periodic_state(x, float(gain), data.omega, data.velocity, data.sign)
    A, B = _drivetrain(x)
    u = data.period_input / gain
    T = 1.0 / freq
    run = _drivetrain_runner(x, A, B, T / N, r_s, v_s, gap)
    if r_s > 1.0 or gap > 0.0:
        def coulomb(states):  # the Coulomb monodromy at the break-away force, the nut closed: a first guess
            ok, M = _monodromy(A, max(r_s, 1.0) * f2_0, b, states, T)
            return M if ok and np.all(np.isfinite(M)) else None

        return _bearing_harmonics(_periodic_by_differences(run, u, x0, x, v, data.harmonics, coulomb), v, c_B, k_B,
                                  data.harmonics)
    start = x0
    for _ in range(DRIVE_SETTLE - 1):
        start = run(u, x0=start, store=True)[1][-1]
    _, states = run(u, x0=start, store=True)  # the period the first Newton step learns from
    periods, last, newton, before_step, got = DRIVE_SETTLE, math.inf, True, None, None
    while True:
        if newton and periods < DRIVE_MAX_PERIODS:
            ok, target, miss = _newton(A, f2_0, b, c_B, k_B, states, T, start)
            if ok and miss <= DRIVE_TOL / 2:  # the next period is the periodic one, within DRIVE_TOL / 2
                _, states = run(u, x0=states[-1], store=True)
                return _bearing_harmonics(states[:-1], v, c_B, k_B, data.harmonics)
            if ok and miss < last and periods + 2 <= DRIVE_MAX_PERIODS:
                before_step, start, last, got = states, target, miss, None
                _, states = run(u, x0=start, store=True)
                periods += 1
                continue
            newton = False
            if before_step is not None and ok and miss >= last:
                states = before_step  # the last step did not bring the periodic state nearer: go on from before it
        # the last period's harmonics: the last plain period's, else computed here
        before = got if got is not None else _bearing_harmonics(states[:-1], v, c_B, k_B, data.harmonics)
        start = states[-1]
        _, states = run(u, x0=start, store=True)
        periods += 1
        got = _bearing_harmonics(states[:-1], v, c_B, k_B, data.harmonics)
        if float(np.max(np.abs(got - before))) <= DRIVE_TOL or periods >= DRIVE_MAX_PERIODS:
            return got


def _links_miss(r, x) -> float:
    """A period's end less its start, ``r``, as the forces it leaves unbalanced in the
    bearing and the nut (their springs and dampers), N."""
    c_n, k_n, c_B, k_B = x[3], x[4], x[5], x[6]
    return abs(c_B * r[0]) + abs(k_B * r[3]) + abs(c_n * (r[0] - r[1])) + abs(k_n * r[2])


def _periodic_by_differences(run, u, start, x, v, K, guess=None):
    """One period of the richer models' drivetrain (states, rows from t = 0 to T) from its
    periodic state. A Stribeck fall and a dead zone have no closed-form monodromy, so the
    Newton steps on the period map P start from ``guess(states)``'s Jacobian (the
    Coulomb monodromy, where it can be formed), else take it by finite differences
    (``DRIVE_FD_STEP``, four further periods), and update it by Broyden's rank-one rule
    after each step (in coordinates scaled by each state's largest value over the first
    period); every step is taken (a first step may overshoot where the nut's gap opens
    and closes, and the next ones come back). Where the period's end misses its start by
    at most ``DRIVE_TOL`` in the links' forces (``_links_miss``), one more period is
    simulated from the end and, where the two periods' bearing force agrees within
    ``DRIVE_TOL`` at every harmonic, that period is returned. ``simulate.SimulationError``
    where none is found within ``DRIVE_MAX_PERIODS_EFFECTS`` periods: where the flywheel
    rattles in the nut's gap behind an almost undamped nut, no periodic state exists, and
    the likelihood, which compares period means, takes such parameters as impossible
    (an **assumption**: the device's steady response is periodic, as its records'
    periods show by their scatter)."""
    c_B, k_B = x[5], x[6]
    _, states = run(u, x0=start, store=True)
    periods = 1
    scale = np.maximum(np.max(np.abs(states), axis=0), _FD_FLOOR)
    J = None  # the Jacobian of P in the scaled coordinates
    while periods + 2 <= DRIVE_MAX_PERIODS_EFFECTS:
        G = states[-1] - start
        if _links_miss(G, x) <= DRIVE_TOL:
            _, after = run(u, x0=states[-1], store=True)
            periods += 1
            now = _bearing_harmonics(states[:-1], v, c_B, k_B, K)
            if float(np.max(np.abs(_bearing_harmonics(after[:-1], v, c_B, k_B, K) - now))) <= DRIVE_TOL:
                return after[:-1]
            start, states = states[-1], after
            continue
        if J is None and guess is not None:
            M = guess(states)
            if M is not None:
                J = M * scale[None, :] / scale[:, None]
            guess = None
        if J is None:
            J = np.empty((4, 4))
            for i in range(4):
                moved = start.copy()
                moved[i] += DRIVE_FD_STEP * scale[i]
                J[:, i] = (run(u, x0=moved, store=True)[1][-1] - states[-1]) / scale / DRIVE_FD_STEP
            periods += 4
        try:
            dz = np.linalg.solve(np.eye(4) - J, G / scale)
        except np.linalg.LinAlgError:
            dz = G / scale  # a plain period
        target = start + dz * scale
        _, tried = run(u, x0=target, store=True)
        periods += 1
        if not np.all(np.isfinite(tried)):
            break
        dP = (tried[-1] - states[-1]) / scale
        if dz @ dz > 0.0:
            J += np.outer(dP - J @ dz, dz) / (dz @ dz)
        start, states = target, tried
    raise SimulationError(f"the drivetrain found no periodic state in {DRIVE_MAX_PERIODS_EFFECTS} periods (the "
                          f"flywheel rattles in the nut's gap?)")


def _drivetrain(x):
    """(A, B) of the drivetrain behind the plate with the rotation sliding, its Coulomb
    force apart: states v_s, v_th, x_s - x_th, x_B - x_s; input the plate's velocity v_B.
    ``x`` the physical parameters in ``ORDER``."""
    b, m_s, c_n, k_n, c_B, k_B, c_f2 = x[0], x[1], x[3], x[4], x[5], x[6], x[10]
    A = np.array([[-(c_B + c_n) / m_s, c_n / m_s, -k_n / m_s, k_B / m_s],
                  [c_n / b, -(c_n + c_f2) / b, k_n / b, 0.0],
                  [1.0, -1.0, 0.0, 0.0],
                  [-1.0, 0.0, 0.0, 0.0]])
    return A, np.array([[c_B / m_s], [0.0], [0.0], [1.0]])


def _newton(A, f2_0, b, c_B, k_B, states, T, start):
    """(ok, target, miss): the drivetrain's periodic state as the monodromy of the period
    ``states`` (simulated from ``start``) predicts it, and by how much the period's end
    misses it in the bearing's force (c_B and k_B times the screw's velocity and the
    bearing's deflection, N); not ok where the monodromy cannot be formed (the rotation
    sticks) or the prediction is not finite."""
    try:
        return _newton_target(A, f2_0, b, c_B, k_B, states, T, start)
    except np.linalg.LinAlgError:
        return False, start, math.inf


@njit(cache=True)
def _newton_target(A, f2_0, b, c_B, k_B, states, T, start):
    """:func:`_newton`, compiled."""
    ok, M = _monodromy(A, f2_0, b, states, T)
    if not ok:
        return False, start, math.inf
    target = start + np.linalg.solve(np.eye(4) - M, states[-1] - start)
    if not np.all(np.isfinite(target)):
        return False, start, math.inf
    miss = target - states[-1]
    return True, target, abs(c_B * miss[0]) + abs(k_B * miss[3])


@njit(cache=True)
def _monodromy(A, f2_0, b, states, T):
    """(ok, M): the drivetrain's monodromy matrix dx(T)/dx(0) over one period of stored
    ``states`` (rows from t = 0 to T, the rotation sliding throughout): the linear flow
    exp(A t) between the rotation's velocity reversals and, at each, the saltation of its
    Coulomb force (the force jumps by 2 f2_0 when the reversal's time moves with the
    start). Not ok where the rotation sticks at a sample or a reversal grazes."""
    N = states.shape[0] - 1
    h = T / N
    for j in range(N):
        if states[j, 1] == 0.0:
            return False, np.eye(4)
    lam, V = np.linalg.eig(A.astype(np.complex128))
    Vi = np.linalg.inv(V)
    M = np.eye(4, dtype=np.complex128)
    t_prev = 0.0
    for j in range(N):
        v0, v1 = states[j, 1], states[j + 1, 1]
        if v0 * v1 >= 0.0:
            continue
        frac = v0 / (v0 - v1)
        ts = (j + frac) * h
        sign = 1.0 if v0 > 0.0 else -1.0
        accel = -f2_0 * sign / b
        for c in range(4):
            accel += A[1, c] * (states[j, c] + frac * (states[j + 1, c] - states[j, c]))
        if abs(accel) * h < 1e-9 * (abs(v0) + abs(v1)):
            return False, np.eye(4)
        flow = (V * np.exp(lam * (ts - t_prev))) @ Vi
        M = flow @ M
        jump = 2.0 * f2_0 * sign / b / accel
        for c in range(4):
            M[1, c] += jump * M[1, c]
        t_prev = ts
    M = ((V * np.exp(lam * (T - t_prev))) @ Vi) @ M
    return True, M.real


def _bearing_harmonics(period: np.ndarray, v: np.ndarray, c_B: float, k_B: float, K: int) -> np.ndarray:
    """The bearing's force z_B (V - V_s) at the harmonics 1..K from one period of the
    drivetrain's states (rows from t = 0) and the plate's velocity ``v`` on the same grid."""
    T_B = c_B * (v - period[:, 0]) + k_B * period[:, 3]
    return np.fft.rfft(T_B)[1: K + 1] / v.shape[0] * 2.0  # real: rfft's harmonics are fft's, in half the time


_ROTATION = np.array([1], dtype=np.int64)  # the drivetrain's contact: the rotation (state 1)


@njit(cache=True)
def _periodic_state(x, gain, omega, velocity, sign):
    """The drivetrain's state at t = 0 in the linear periodic solution with the rotation's
    friction a square wave with the plate's (the simulation's start)."""
    out = np.zeros(4)
    for k in range(omega.shape[0]):
        iw = 1j * omega[k]
        V = velocity[k] / gain
        F2 = x[9] * sign[k]
        V_s, _, z_n, y, _ = _screw(iw, V, F2, x)
        V_th = (z_n * V_s - F2) / (z_n + y)
        out[0] += V_s.real
        out[1] += V_th.real
        out[2] += ((V_s - V_th) / iw).real
        out[3] += ((V - V_s) / iw).real
    return out


#: The last :func:`_inputs` call's data, arguments and result (a copy of its vector):
#: the start search asks each candidate's residual and then its likelihood at the same
#: parameters, and the drivetrain is simulated once for both.
_LAST_INPUTS: list = [None]


def _inputs(data: MotionData, p, gain, effects):
    """The compiled kernels' parameter vector, bearing-force arguments and plate hump;
    the last call's result again where ``data`` and the arguments are the same."""
    x = np.array(_vector(p), dtype=float)
    key = (x.tobytes(), float(gain), _effects(effects))
    last = _LAST_INPUTS[0]
    if last is not None and last[0] is data and last[1] == key:
        return last[2]
    bearing = bearing_force(data, x, gain, effects)
    got = (x, (np.zeros(data.harmonics, dtype=np.complex128) if bearing is None else bearing), bearing is not None,
           plate_hump(data, x, gain, effects))
    _LAST_INPUTS[0] = (data, key, got)
    return got


def predicted_force(data: MotionData, p, gain: float = 1.0, delay: float = 0.0, effects=None):
    """(F^_k, Y_k): the model's force at the harmonics for the physical parameters ``p``
    (by name, or a vector in :data:`ORDER`), and its transfer from the measured
    acceleration, dF^_k / dA_k (the network linearised, the Coulomb forces out), as the
    force channel records them ``delay`` s behind the acceleration channel; ``effects``
    the richer models' (r_s, v_s, gap by name; None: the paper's model)."""
    x, bearing, simulated, hump = _inputs(data, p, gain, effects)
    return _predicted(x, float(gain), data.omega, data.velocity, data.sign, bearing, simulated, float(delay), hump)


def motion_variance(data: MotionData, p, tau: float, alpha: float, gain: float = 1.0, delay: float = 0.0):
    """(V_k, Y_k): each harmonic's residual variance (noise of both channels and the
    discrepancy, N^2) and the model's transfer from the measured acceleration to the force
    (``p`` as for :func:`predicted_force`)."""
    h = data.harmonic
    zeros = np.zeros(data.harmonics, dtype=np.complex128)
    _, Y = _predicted(_vector(p), float(gain), data.omega, data.velocity, data.sign, zeros, False, float(delay), zeros)
    return _variance(Y, float(tau), float(alpha), h.var_force, h.var_accel, h.cov, float(h.periods)), Y


def _input_noise_draws(data: MotionData, x: np.ndarray, gain: float, delay: float, draws: int, seed: int,
                       effects=None):
    """(d, Y e) of each of ``draws`` draws e of the measured motion's noise (see
    :func:`input_noise_variance`): the predicted force's change beyond the linear term,
    and the linear term, each (K,) complex."""
    if data.fine_var is None:
        raise ValueError("this motion data keeps no noise of its plate motion; make it again with motion_data")
    F0, Y = predicted_force(data, x, gain, delay, effects)
    K = data.harmonics
    n_fine = data.fine_omega.shape[0]
    t = np.arange(DRIVE_GRID) / (DRIVE_GRID * data.omega[0] / (2.0 * math.pi))
    on_grid = np.exp(1j * np.outer(t, data.fine_omega))  # harmonics to the drive's grid (``at_times``), once
    rng = np.random.default_rng(seed)
    for _ in range(draws):
        e = np.sqrt(data.fine_var / 2.0) * (rng.standard_normal(n_fine) + 1j * rng.standard_normal(n_fine))
        dv = e / (1j * data.fine_omega)  # the velocity's noise at each harmonic
        moved = dataclasses.replace(data, velocity=data.velocity + dv[:K], drive=data.drive + np.real(on_grid @ dv))
        linear = Y * e[:K]
        yield predicted_force(moved, x, gain, delay, effects)[0] - F0 - linear, linear


def input_noise_variance(data: MotionData, p, gain: float = 1.0, delay: float = 0.0, *, draws: int = 16,
                         seed: int = INPUT_NOISE_SEED, effects=None) -> np.ndarray:
    """(K,) N^2: the predicted force's variance from the measured motion's noise beyond
    the linear errors-in-variables term |Y_k|^2 s2_A,k / P (``LikelihoodSettings.input_noise``
    with ``input_noise_form="variance"``).

    The measured motion drives the model twice over: linearly through the plate's
    inertia, damping and bearing (the transfer Y_k while everything slides), and through
    the drivetrain's simulation, whose rotation sticks and slips behind the nut. The
    second passes the motion's noise on as it is not linear. ``draws`` draws e of that
    noise (complex normal at each harmonic of the plate motion's reconstruction, with
    its period mean's variance, ``fine_var``; seeded by ``seed``) are added to the
    plate's velocity harmonics and to the drivetrain's input, and the predicted force
    computed again; with d = F^(v + e) - F^(v) - Y e the part the linear term leaves
    out, the result is max(0, mean(|d|^2 + 2 Re(conj(Y e) d))), averaged over the
    harmonics within two of each (``pool``'s default). The plate's sign wave is left as
    measured (its switch times' noise is the reversal windows' to carry). ``effects``:
    the richer models' (:func:`predicted_force`)."""
    K = data.harmonics
    total = np.zeros(K)
    for d, linear in _input_noise_draws(data, _vector(p), gain, delay, draws, seed, effects):
        total += np.abs(d) ** 2 + 2.0 * np.real(np.conj(linear) * d)
    extra = np.maximum(total / draws, 0.0)
    return np.array([extra[max(0, k - 2): k + 3].mean() for k in range(K)])


def input_noise_shapes(data: MotionData, p, gain: float = 1.0, delay: float = 0.0, *, draws: int = 16,
                       seed: int = INPUT_NOISE_SEED, effects=None) -> np.ndarray:
    """(2K, draws) N: the draws d_j of :func:`input_noise_variance` (the predicted force's
    change beyond the linear term, real parts then imaginary parts), each over sqrt(draws),
    so that U U' is their sample covariance across the harmonics
    (``input_noise_form="shapes"``). A stuck rotation that slips a little earlier or later
    moves every harmonic at once; these shapes keep that coherence, which one variance
    per harmonic loses (docs/inference.md). None, (2K, 0), where the rotation has no
    Coulomb force (f2_0 = 0), the nut no backlash and the plate no Stribeck hump: the
    model is then linear in the motion, the linear term holds all of its noise.
    ``effects``: the richer models' (:func:`predicted_force`)."""
    x = _vector(p)
    r_s, _, gap = _effects(effects)
    if x[9] <= 0.0 and gap <= 0.0 and (r_s <= 1.0 or x[7] <= 0.0):  # linear in the motion: the shapes are zero
        return np.zeros((2 * data.harmonics, 0))
    cols = [np.concatenate([d.real, d.imag])
            for d, _ in _input_noise_draws(data, x, gain, delay, draws, seed, effects)]
    return np.array(cols).T / math.sqrt(draws) if cols else np.zeros((2 * data.harmonics, 0))


def with_input_noise(data: MotionData, extra: np.ndarray) -> MotionData:
    """``data`` with ``extra`` (K,) N^2 added to every harmonic's residual variance
    (:func:`input_noise_variance`): the force channel's variance of one period grows by
    P times it, so V_k grows by it."""
    h = data.harmonic
    return dataclasses.replace(data, harmonic=dataclasses.replace(h, var_force=h.var_force + h.periods * extra))


#: The relative step in b of :func:`form_shape`'s central difference.
FORM_STEP = 1e-3


def form_shape(data: MotionData, p, gain: float = 1.0, delay: float = 0.0, effects=None) -> np.ndarray:
    """(2K, 1): the predicted force's derivative in log b at the physical parameters
    ``p`` (as for :func:`predicted_force`; a central difference of :data:`FORM_STEP`),
    real parts then imaginary parts: the direction along which a relative error of b
    moves the force (``LikelihoodSettings.form_sd``)."""
    x = np.array(_vector(p), dtype=float)
    up, down = x.copy(), x.copy()
    up[0] *= math.exp(FORM_STEP)
    down[0] *= math.exp(-FORM_STEP)
    d = (predicted_force(data, up, gain, delay, effects)[0]
         - predicted_force(data, down, gain, delay, effects)[0]) / (2.0 * FORM_STEP)
    return np.concatenate([d.real, d.imag])[:, None]


def form_columns(shape: np.ndarray, form_sd: float, form_friction: float, p) -> np.ndarray:
    """The model-form errors' deviation columns (prior sd 1 each) from :func:`form_shape`'s
    ``shape`` at the physical parameters ``p``: ``form_sd`` times it (a relative error of
    b), and the same direction scaled to ``form_friction`` times the Coulomb forces
    f1_0 + f2_0 at the fundamental (an error that grows with the friction); those asked."""
    x = _vector(p)
    K = shape.shape[0] // 2
    cols = []
    if form_sd > 0:
        cols.append(form_sd * shape)
    fundamental = math.hypot(float(shape[0, 0]), float(shape[K, 0]))
    if form_friction > 0 and fundamental > 0:
        cols.append(form_friction * (x[7] + x[9]) / fundamental * shape)
    return np.hstack(cols) if cols else np.zeros((shape.shape[0], 0))


def with_input_shapes(data: MotionData, shapes: np.ndarray) -> MotionData:
    """``data`` with the columns of ``shapes`` (:func:`input_noise_shapes`) among its
    marginalised deviations, each with a prior sd of 1 (their scale is in the columns)."""
    m = shapes.shape[1]
    scale = np.vstack([data.scale, np.column_stack([np.zeros(m), np.zeros(m), np.ones(m)])])
    law = None if data.law_columns is None else np.concatenate([data.law_columns, np.zeros(m, dtype=bool)])
    return dataclasses.replace(data, basis=np.hstack([data.basis, shapes]), scale=scale, law_columns=law)


def motion_loglik(data: MotionData, p, tau: float, alpha: float, gain: float = 1.0, *,
                  pointwise: bool = False, reference: np.ndarray | None = None, delay: float = 0.0,
                  deviation_at=None, law: float | None = None, effects=None):
    """(log L, phi of the force at the harmonics) of the module docstring; with
    ``pointwise``, each harmonic's term (an array) instead of log L. ``p`` as for
    :func:`predicted_force`. ``reference``: each harmonic's noise variance (N^2) that
    the normaliser uses in place of the parameters' own (see module docstring); None:
    their own. ``delay``: the force channel's behind the acceleration's, s.
    ``deviation_at``: the parameters (as ``p``) whose Coulomb forces scale the
    marginalised deviations' prior sd; None: ``p``'s own. ``law``: the friction law's
    deviations' prior sd as a share of the Coulomb forces, where the likelihood samples
    it (``LikelihoodSettings.law_sampled``); None: ``friction_law.SD``. ``effects``:
    the richer models' (:func:`predicted_force`)."""
    h = data.harmonic
    x, bearing, simulated, hump = _inputs(data, p, gain, effects)
    at = x if deviation_at is None else _vector(deviation_at)
    terms, sq, norm = _terms(x, float(tau), float(alpha), float(gain), data.omega, data.velocity, data.sign, bearing,
                             simulated, hump, data.basis, data.scale, h.force, h.var_force, h.var_accel, h.cov, float(h.periods),
                             np.full(data.harmonics, -1.0) if reference is None else np.asarray(reference, float),
                             float(delay), at, _factors(data, law))
    phi = 1.0 - math.sqrt(sq / norm)
    return (terms if pointwise else float(terms.sum())), phi


def fundamental_misfit(data: MotionData, p, gain: float = 1.0, tau: float | None = None,
                       alpha: float = 0.0, delay: float = 0.0, deviation_at=None, law: float | None = None,
                       effects=None) -> float:
    """The fit's residual at the drive's fundamental in phase with the model's inertial
    force there, as a share of that force: |Re(r_1 / (Y_1 A_1 / g))| (see
    :data:`FUNDAMENTAL_MAX`). With ``tau`` (the discrepancy, N) the marginalised
    deviations' posterior mean (the reversals', the law's and the input noise's shapes,
    ``reversals.deviations_mean``) is taken from the residual first: what they explain
    the posterior has accounted for; None: the residual of the mean prediction alone.
    ``deviation_at``, ``law`` and ``effects`` as for :func:`motion_loglik`."""
    F, Y = predicted_force(data, p, gain, delay, effects)
    r = data.harmonic.force - F
    if tau is not None and data.basis.shape[1]:
        h = data.harmonic
        V = _variance(Y, float(tau), float(alpha), h.var_force, h.var_accel, h.cov, float(h.periods))
        at = _vector(p) if deviation_at is None else _vector(deviation_at)
        r = r - deviations_mean(data.basis, V, r, _deviation_sd(data.scale, at) * _factors(data, law))
    inertial = Y[0] * data.harmonic.accel[0]  # Y already holds the gain
    return float(abs((r[0] / inertial).real))
