"""A realistic record generator for the paper's protocol.

Terminal 1 is driven by a position-servoed actuator through a sinusoidal displacement
with a smooth ramp-in from rest; the device (any network, any friction law, optional
backlash) is simulated at a fine internal rate; then the acquisition chain: the sensors'
bandwidth, a linear-phase anti-alias filter, sampling at the record's rate, and sensor
noise. MODEL.md sections 5 and 7 say why each stage matters: a record sampled
instantaneously from the simulation is one that no model fits.

Every setting is an **assumption** (the paper gives none of them) and an option of
:class:`GeneratorSettings`; the defaults are documented there and in the README.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from ..device import FREQUENCIES_HZ, SETTINGS, InerterParameters, paper_parameters
from ..friction import STRIBECK_RATIO, STRIBECK_VELOCITY
from ..networks import device_network
from ..network import Network, compile_network
from ..simulate import exact_applies, run_piecewise_linear, run_stiff
from .record import Record

__all__ = ["GeneratorSettings", "generate_record", "paper_grid", "paper_record", "STIFF_RTOL", "CHUNK_SECONDS"]

#: Relative tolerance of the general stiff solver when the truth is richer than the exact
#: kernel handles (Stribeck, smooth law, backlash): 1e-6 changes phi by about 2e-5 against
#: 1e-8 and saves a third of the time (5-8 s of computing per second of record, measured).
STIFF_RTOL = 1e-6


@dataclass(frozen=True)
class GeneratorSettings:
    """How a record is made. Every field is an assumption the paper does not state.

    Attributes
    ----------
    amplitude : drive displacement amplitude, m (default 10 mm).
    fs : record sampling rate, Hz (default 1 kHz).
    duration : record length including the ramp, s (default 10 s).
    ramp : smooth (raised-cosine) ramp-in time from rest, s (default 2 s).
    oversample : internal simulation rate / fs (default 20: 20 kHz).
    k_p, k_d : servo position (N/m) and velocity (N s/m) gains (MODEL.md section 7).
    force_noise : load-cell noise, N rms at the record rate (default 2 N).
    accel_noise : accelerometer noise, m/s^2 rms at the record rate (default 0.01, ~1e-3 g).
    disp_noise : displacement sensor noise, m rms (default 1 micrometre).
    noise_corner : None (default) for white sensor noise; else the -3 dB frequency, Hz,
        of a second-order Butterworth low-pass that colours all three sensors' noise
        (scaled to keep the rms above): drift-like, correlated noise, as from a charge
        amplifier or a noisy reference, that the likelihood's AR(1) residual only
        approximates.
    force_bandwidth, accel_bandwidth : sensor -3 dB bandwidths, Hz (second-order
        Butterworth; defaults 2 kHz and 5 kHz); None for ideal sensors.
    force_delay, accel_delay : each sensor's pure time delay, s (default 0: none),
        rounded to the internal rate's sample (``1 / (fs oversample)``): a conditioning
        amplifier's or a converter's latency that the record's time stamps do not show.
    force_gain, accel_gain : each sensor's true sensitivity over the nominal one the
        record is converted with: a calibration error (default 1: none). The records
        alone cannot reveal it (``records.sensitivity``).
    antialias : "fir" (linear-phase FIR with its delay removed, as a delta-sigma
        converter's decimation filter; default) or "none" (instantaneous sampling, the
        naive record MODEL.md section 7 warns against).
    tail : time simulated past the end and cut, s (keeps filter end effects out).
    network : truth network, "reduced" (default) or "full" (adds the sin(theta) nut friction).
    friction : truth friction law, "coulomb" (default), "stribeck" or "smooth".
    stribeck_ratio, stribeck_velocity : the Stribeck law's break-away over Coulomb force
        and its Stribeck velocity, m/s (defaults ``friction.STRIBECK_RATIO`` and
        ``friction.STRIBECK_VELOCITY``: 1.3 and 0.01 m/s).
    backlash : half-width of a dead zone in the nut link, m (default 0: none).
    exact : simulate Stribeck friction (in its piecewise-linear form,
        ``friction.STRIBECK_SEGMENTS`` pieces) and backlash (a plain dead zone) on the
        exact kernel (default True); False: on the general stiff solver, regularised
        (``_stiff``: tanh sign, backlash ramp), as before. The smooth law always runs there.
    """

    amplitude: float = 0.01
    fs: float = 1000.0
    duration: float = 10.0
    ramp: float = 2.0
    oversample: int = 20
    k_p: float = 5e7
    k_d: float = 5e5
    force_noise: float = 2.0
    accel_noise: float = 0.01
    disp_noise: float = 1e-6
    noise_corner: float | None = None
    force_bandwidth: float | None = 2000.0
    accel_bandwidth: float | None = 5000.0
    force_delay: float = 0.0
    accel_delay: float = 0.0
    force_gain: float = 1.0
    accel_gain: float = 1.0
    antialias: str = "fir"
    tail: float = 0.5
    network: str = "reduced"
    friction: str = "coulomb"
    stribeck_ratio: float = STRIBECK_RATIO
    stribeck_velocity: float = STRIBECK_VELOCITY
    backlash: float = 0.0
    exact: bool = True

    def __post_init__(self) -> None:
        for name in ("amplitude", "fs", "duration", "k_p", "k_d", "force_gain", "accel_gain", "stribeck_velocity"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"generator setting {name} must be positive, got {value!r}")
        for name in ("ramp", "force_noise", "accel_noise", "disp_noise", "tail", "backlash", "force_delay",
                     "accel_delay"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"generator setting {name} must be non-negative, got {value!r}")
        if not (isinstance(self.stribeck_ratio, (int, float)) and self.stribeck_ratio >= 1.0):
            raise ValueError(f"generator setting stribeck_ratio must be at least 1, got {self.stribeck_ratio!r}")
        if not (isinstance(self.oversample, int) and self.oversample >= 1):
            raise ValueError(f"oversample must be a positive integer, got {self.oversample!r}")
        if self.antialias not in ("fir", "none"):
            raise ValueError(f"antialias must be 'fir' or 'none', got {self.antialias!r}")
        if self.antialias == "fir" and self.oversample < 4:
            raise ValueError("antialias='fir' needs oversample >= 4")
        if self.ramp >= self.duration:
            raise ValueError(f"ramp ({self.ramp} s) must be shorter than duration ({self.duration} s)")
        if self.noise_corner is not None and not (
                isinstance(self.noise_corner, (int, float)) and 0 < self.noise_corner < self.fs / 2):
            raise ValueError(f"noise_corner must lie between 0 and fs/2 = {self.fs / 2:g} Hz, got {self.noise_corner!r}")
        if self.network not in ("reduced", "full"):
            raise ValueError(f"truth network must be 'reduced' or 'full', got {self.network!r}")
        for bw in (self.force_bandwidth, self.accel_bandwidth):
            if bw is not None and not (bw > 0 and bw < self.fs * self.oversample / 2):
                raise ValueError(
                    f"sensor bandwidth {bw} Hz must lie below the internal Nyquist rate "
                    f"{self.fs * self.oversample / 2:g} Hz"
                )

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _reference_motion(t, freq, amplitude, ramp):
    """x_ref, v_ref of a sinusoid under a raised-cosine envelope (smooth from rest)."""
    w = 2 * np.pi * freq
    if ramp > 0:
        s = np.clip(t / ramp, 0.0, 1.0)
        env = 0.5 - 0.5 * np.cos(np.pi * s)
        denv = np.where(s < 1.0, 0.5 * np.pi * np.sin(np.pi * s) / ramp, 0.0)
    else:
        env, denv = np.ones_like(t), np.zeros_like(t)
    x = amplitude * env * np.sin(w * t)
    v = amplitude * (denv * np.sin(w * t) + env * w * np.cos(w * t))
    return x, v


def _truth_network(params: InerterParameters, s: GeneratorSettings) -> Network:
    return device_network(s.network, params, s.friction, stribeck_ratio=s.stribeck_ratio,
                          stribeck_velocity=s.stribeck_velocity, backlash=s.backlash)


#: Records are simulated and filtered in pieces of this many seconds of internal time,
#: so that memory is bounded by a piece rather than growing with the record (20 kHz
#: states for 10 minutes would be about 1.5 GB). A record no longer than one piece is
#: made in one pass; a longer one gives the same numbers bit for bit as one pass (the
#: exact kernel continues from its state at each joint; the filters carry theirs; the
#: anti-alias windows overlap; checked in the tests). The general stiff solver (Stribeck,
#: smooth law, backlash) still runs in one piece. Not a physical assumption.
CHUNK_SECONDS = 30.0


def _servo_system(params, s: GeneratorSettings):
    """The device's compiled network with the servo closed around node 0."""
    compiled = compile_network(_truth_network(params, s))
    inv_m0 = 1.0 / compiled.masses[0]
    exact = compiled.all_coulomb or (s.exact and exact_applies(compiled))
    A, B1 = compiled.state_space(viscous=exact, position=True)
    n = A.shape[0]
    pos = n - 1
    # servo force k_p (x_ref - x_0) + k_d (v_ref - v_0) on node 0
    A[0, pos] -= s.k_p * inv_m0
    A[0, 0] -= s.k_d * inv_m0
    B = np.zeros((n, 2))
    B[0] = [s.k_p * inv_m0, s.k_d * inv_m0]
    return compiled, A, B, pos, exact


def _simulate_servo(params, freq, s: GeneratorSettings, chunk_s: float):
    """Fine-rate simulation of device + servo, piece by piece: yields (velocity of node 0,
    displacement, servo force) for consecutive runs of fine samples; each piece starts
    from the state the last one ended in."""
    fine = s.fs * s.oversample
    n_fine = int(round((s.duration + s.tail) * fine)) + 1
    compiled, A, B, pos, exact = _servo_system(params, s)
    piece = max(2, int(round(chunk_s * fine))) if exact else n_fine
    x0, a = None, 0
    while a < n_fine:
        lo, hi = max(a - 1, 0), min(a + piece, n_fine)  # a piece re-takes the last sample
        t = np.arange(lo, hi) / fine
        x_ref, v_ref = _reference_motion(t, freq, s.amplitude, s.ramp)
        inputs = np.column_stack([x_ref, v_ref])
        if exact:
            _, states = run_piecewise_linear(compiled, A, B, inputs, 1.0 / fine, x0=x0, store=True)
        else:  # the general stiff solver runs in one piece
            _, states = run_stiff(compiled, A, B, t, inputs, rtol=STIFF_RTOL)
        if lo < a:
            states, x_ref, v_ref = states[1:], x_ref[1:], v_ref[1:]
        x0 = states[-1].copy()
        vel, disp = states[:, 0], states[:, pos]
        yield vel, disp, s.k_p * (x_ref - disp) + s.k_d * (v_ref - vel)
        a = hi


class _MeanAcceleration:
    """Streaming ``simulate.mean_acceleration`` (np.gradient's central differences, one-
    sided at the ends): the sensor sees the continuous acceleration, which jumps at every
    Coulomb switch, so its fine-rate samples are means over +-1/fine around each instant,
    not point values, and a jump is not aliased onto one sample."""

    def __init__(self, h):
        self.h, self.tail = h, None

    def push(self, v, final):
        f = v if self.tail is None else np.concatenate([self.tail, v])
        out = np.empty(len(f))
        if self.tail is None:
            out[0] = (f[1] - f[0]) / self.h
        out[1:-1] = (f[2:] - f[:-2]) / (2.0 * self.h)
        out[-1] = (f[-1] - f[-2]) / self.h
        first = 0 if self.tail is None else 1  # the tail's value was given last time
        self.tail = f[-2:]
        return out[first:] if final else out[first:-1]


class _Sensor:
    """A sensor's second-order Butterworth response and its pure delay (whole samples of
    the internal rate, the signal at rest before t = 0), their state carried across pieces."""

    def __init__(self, bandwidth, fine, delay: float = 0.0):
        self.sos = None if bandwidth is None else signal.butter(2, bandwidth, fs=fine, output="sos")
        self.zi = None if self.sos is None else np.zeros((self.sos.shape[0], 2))
        self.held = np.zeros(int(round(delay * fine)))

    def push(self, x):
        y = x
        if self.sos is not None:
            y, self.zi = signal.sosfilt(self.sos, x, zi=self.zi)
        if self.held.size:
            both = np.concatenate([self.held, y])
            y, self.held = both[: len(y)], both[len(y):]
        return y


class _Acquisition:
    """Anti-alias and sample at the record rate, piece by piece, with the same numbers as
    on the whole signal: "none" takes every ``oversample``-th sample; "fir" is scipy's
    ``decimate(ftype="fir", zero_phase=True)`` (a linear-phase FIR with its delay
    removed, as a delta-sigma converter's decimation filter), computed on windows that
    overlap by more than the filter's half length."""

    def __init__(self, s: GeneratorSettings):
        self.q, self.fir = s.oversample, s.antialias == "fir"
        self.pad = (10 + 2) * self.q  # > decimate's half length 10 q, a multiple of q
        self.buf, self.start, self.done = np.empty(0), 0, 0  # fine index of buf[0]; outputs given

    def push(self, x, final):
        self.buf = np.concatenate([self.buf, x])
        end = self.start + len(self.buf)  # fine samples received
        n_out = -(-end // self.q) if final else max(0, (end - self.pad) // self.q)
        if n_out <= self.done:
            return np.empty(0)
        if not self.fir:
            y = self.buf[self.done * self.q - self.start : n_out * self.q - self.start : self.q]
        else:
            lo = max(0, self.done * self.q - self.pad)
            hi = end if final else n_out * self.q + self.pad
            window = self.buf[lo - self.start : hi - self.start]
            y = signal.decimate(window, self.q, ftype="fir", zero_phase=True)
            y = y[(self.done * self.q - lo) // self.q :][: n_out - self.done]
        self.done = n_out
        keep = max(0, self.done * self.q - self.pad) - self.start  # drop what no output needs
        self.buf, self.start = self.buf[keep:], self.start + keep
        return y


def _record_signals(params, freq, s: GeneratorSettings, chunk_s: float = CHUNK_SECONDS):
    """Force, acceleration and displacement at the record rate, before sensor noise."""
    fine = s.fs * s.oversample
    n_fine = int(round((s.duration + s.tail) * fine)) + 1
    accel_mean = _MeanAcceleration(1.0 / fine)
    sensors = [_Sensor(s.force_bandwidth, fine, s.force_delay), _Sensor(s.accel_bandwidth, fine, s.accel_delay),
               _Sensor(None, fine)]
    acquire = [_Acquisition(s) for _ in range(3)]
    out = [[], [], []]
    received = 0
    for vel, disp, force in _simulate_servo(params, freq, s, chunk_s):
        received += len(vel)
        final = received == n_fine
        for k, x in enumerate((force, accel_mean.push(vel, final), disp)):
            out[k].append(acquire[k].push(sensors[k].push(x), final))
    n = int(round(s.duration * s.fs)) + 1
    return [np.concatenate(o)[:n] for o in out]


def _noise(gen: np.random.Generator, n: int, s: GeneratorSettings) -> np.ndarray:
    """Unit-rms sensor noise: white, or white through the ``noise_corner`` low-pass,
    rescaled by the filter's noise gain (the root sum of squares of its impulse
    response) so the rms stays 1."""
    w = gen.standard_normal(n)
    if s.noise_corner is None:
        return w
    b, a = signal.butter(2, s.noise_corner, fs=s.fs)
    impulse = signal.lfilter(b, a, np.r_[1.0, np.zeros(max(4096, int(50 * s.fs / s.noise_corner)))])
    return signal.lfilter(b, a, w) / math.sqrt(np.sum(impulse**2))


def generate_record(
    params: InerterParameters,
    freq: float,
    *,
    settings: GeneratorSettings | None = None,
    rng: np.random.Generator | int | None = None,
    setting_name: str | None = None,
) -> Record:
    """Generate one record of the paper's protocol.

    Parameters
    ----------
    params : the device's true parameters.
    freq : drive frequency, Hz (> 0).
    settings : how the record is made (defaults: :class:`GeneratorSettings`).
    rng : a numpy Generator or a seed for the sensor noise (same seed, same record).
        Required when any noise is on.
    setting_name : flywheel setting name to store in the metadata.
    """
    s = settings or GeneratorSettings()
    if not (isinstance(freq, (int, float)) and math.isfinite(freq) and freq > 0):
        raise ValueError(f"drive frequency must be positive, got {freq!r}")
    if freq >= s.fs / 10:
        raise ValueError(f"drive frequency {freq} Hz is too high for fs = {s.fs} Hz")
    noisy = s.force_noise > 0 or s.accel_noise > 0 or s.disp_noise > 0
    if rng is None and noisy:
        raise ValueError("generate_record needs rng (a seed or numpy Generator) when noise is on")
    gen = np.random.default_rng(rng) if not isinstance(rng, np.random.Generator) else rng
    force, accel, disp = _record_signals(params, freq, s)
    n = len(force)
    force = s.force_gain * force + s.force_noise * _noise(gen, n, s)
    accel = s.accel_gain * accel + s.accel_noise * _noise(gen, n, s)
    disp = disp + s.disp_noise * _noise(gen, n, s)
    meta = {
        "source": "generated",
        "setting": setting_name,
        "m_s": params.m_s,
        "m_B": params.m_B,
        "drive_frequency_hz": float(freq),
        "sampling_rate_hz": float(s.fs),
        "true_parameters": params.as_dict(),
        "generator": s.as_dict(),
    }
    time = np.arange(n) / s.fs
    return Record(time=time, force=force, accel=accel, disp=disp, metadata=meta)


def paper_grid(
    *,
    settings: GeneratorSettings | None = None,
    seed: int = 0,
    frequencies=FREQUENCIES_HZ,
    names=tuple(SETTINGS),
):
    """The paper's 27 records (nine settings, 0.5 / 1 / 1.5 Hz) at the paper's parameters.

    Each record gets its own noise stream, spawned from ``seed`` in a fixed order, so any
    one record can be regenerated alone (:func:`paper_record`). Yields (setting name,
    frequency, Record).
    """
    for name in names:
        for freq in frequencies:
            yield name, freq, paper_record(name, freq, settings=settings, seed=seed, frequencies=frequencies,
                                           names=names)


def paper_record(name: str, freq: float, *, settings: GeneratorSettings | None = None, seed: int = 0,
                 frequencies=FREQUENCIES_HZ, names=tuple(SETTINGS)):
    """The record of setting ``name`` at ``freq`` exactly as :func:`paper_grid` (same
    grid, same seed) makes it, without making the others."""
    names, frequencies = list(names), list(frequencies)
    if name not in names or freq not in frequencies:
        raise ValueError(f"no setting {name!r} at {freq:g} Hz in the grid")
    seeds = np.random.SeedSequence(seed).spawn(len(names) * len(frequencies))
    i = names.index(name) * len(frequencies) + frequencies.index(freq)
    return generate_record(paper_parameters(name), freq, settings=settings, rng=np.random.default_rng(seeds[i]),
                           setting_name=name)
