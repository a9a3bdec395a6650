"""The plate's reversals: where motion in cannot say what the plate's friction does.

At each reversal of a displacement-driven test the plate's Coulomb friction passes from
+f1_0 to -f1_0. Where the plate slides through, it switches in an instant; where it
sticks (a large friction against a stiff servo), the friction follows the actuator
through the dwell, whatever the motion; and where the measured velocity is noisy its
zero crossing, which times the switch, moves by sigma_v / |a| or crosses several times.
In all three cases the motion alone does not fix the friction inside a short window
around the reversal, so the likelihood marginalises it there:

- the windows: each cluster of the reconstructed plate velocity's zero crossings (those
  within ``CLUSTER`` of a period of each other) with the stretch around it where the
  velocity stays below ``DWELL`` of its peak (a stuck plate's dwell), widened on each side by ``WIDEN`` times
  the crossing's timing uncertainty sigma_v / |a| (sigma_v: the reconstructed
  velocity's noise from the periods' scatter, |a|: the plate's peak acceleration, the
  drive's at a reversal) and by at least ``MIN_HALF_WIDTH`` of the period;
- the friction's mean inside a window: one switch, midway between its first and last
  zero crossing (the sign wave's
  harmonics, :func:`switched_sign`; a straight ramp across the window was tried first
  and moved the apparent mass of a noise-free A3 record at 1.5 Hz by 0.13 % once the
  windows took in the slow stretch around a reversal);
- its deviation from that mean: a_j P_j(x) with P_j the Legendre polynomials of degree
  j < d on the window (d at least ``DEGREES``, more for a wide window) and
  a_j ~ N(0, (``SD`` f_0)^2) (**assumption**: the
  deviation is of the friction's own size; f_0 = f1_0 + f2_0, the Coulomb force of
  plate and rotation together (``LikelihoodSettings.reversal_scale``; "plate" takes
  f1_0 alone), the reference point's by default,
  ``LikelihoodSettings.deviation_scale``), whose harmonics form the columns of the
  basis U (2K real rows: the real parts, then the imaginary parts).

With the residual's other variance D (each harmonic's V_k / 2 for its real and its
imaginary part) the marginal adds to the independent harmonics' log-likelihood

    -1/2 log det(I + s^2 U' D^-1 U) + 1/2 s^2 w' (I + s^2 U' D^-1 U)^-1 w,   w = U' D^-1 r,

s = SD f_0 (Woodbury's identity: the density of r under D + s^2 U U'). This is the
"variance that lives at velocity reversals" of the likelihood's design: what the model
cannot know is left free where it is, not smeared over every harmonic.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["reversal_windows", "switched_sign", "window_degrees", "window_basis", "reversal_correction",
           "deviations_mean", "CLUSTER",
           "WIDEN", "MIN_HALF_WIDTH", "DWELL", "DEGREES", "MAX_DEGREES", "SD"]

#: Zero crossings closer than this share of a period are one reversal.
CLUSTER = 0.1
#: **Assumption**: a window reaches this many timing standard deviations past its crossings.
WIDEN = 3.0
#: **Assumption**: the least half-width of a window, as a share of the period.
MIN_HALF_WIDTH = 0.002
#: **Assumption**: a window takes in the stretch around its crossings where the velocity
#: stays below this share of its peak (a stuck plate's dwell).
DWELL = 0.02
#: Legendre polynomials per window for the friction's deviation from its mean, at least;
#: a window also gets one for each degree of freedom of the harmonics 1..K over its
#: width (2 K times its share of the period), at most ``MAX_DEGREES``. On noise-free
#: generator records of Table I's parameters (the paper's 27 settings and frequencies,
#: the optimum nearest the truth) 8 put b within 0.1 % on 26 of 27 (A2 at 1 Hz -0.2 to
#: -0.3 %), 4 on 23 (A0 at 0.5 Hz -0.74 %: four polynomials could not follow a plate
#: that sticks through its reversal).
DEGREES = 8
MAX_DEGREES = 24
#: **Assumption**: the prior sd of each deviation's amplitude, in units of the Coulomb
#: force (f1_0 + f2_0, or f1_0 alone: ``LikelihoodSettings.reversal_scale``).
SD = 1.0


def _sign(v: np.ndarray) -> np.ndarray:
    """sgn(v) with 0 read as +1 (a crossing is where it changes)."""
    s = np.sign(v)
    s[s == 0] = 1.0
    return s


def reversal_windows(v: np.ndarray, a: np.ndarray, sigma_v: float, period: float) -> list[tuple[float, float]]:
    """The windows (start, end) as shares of the period, in time order (a window may reach
    below 0 or past 1: it wraps) around the reversals of the velocity ``v`` (m/s) sampled on a
    uniform grid over one period of ``period`` s; ``a`` the acceleration on that grid
    (m/s^2), ``sigma_v`` the velocity's noise sd (m/s)."""
    n = v.shape[0]
    s = _sign(v)
    cross = np.flatnonzero(s != np.roll(s, 1))  # a crossing between sample i-1 and i
    if cross.size == 0:
        return []
    gap = CLUSTER * n
    # rotate so that no cluster straddles the period's end: start after the largest gap
    d = np.diff(np.append(cross, cross[0] + n))
    first = int(np.argmax(d)) + 1
    order = np.concatenate([cross[first:], cross[:first] + n])
    clusters, current = [], [order[0]]
    for c in order[1:]:
        if c - current[-1] < gap:
            current.append(c)
        else:
            clusters.append(current)
            current = [c]
    clusters.append(current)
    # the velocity's slope through a reversal: the drive's peak acceleration (a stuck
    # plate's own acceleration is near zero in its dwell, which would not say how fast
    # the drive takes the velocity through zero)
    slope = float(np.max(np.abs(a))) * period  # m/s per period share
    half = max(MIN_HALF_WIDTH, WIDEN * sigma_v / slope if slope > 0 else CLUSTER)
    # a plate that sticks rests near zero velocity through its dwell: the window takes in
    # the slow stretch on either side of the crossings
    slow = np.abs(v) < DWELL * float(np.max(np.abs(v)))
    out = []
    for cl in clusters:
        lo, hi = cl[0], cl[-1]
        while slow[(lo - 1) % n] and hi - lo < gap:
            lo -= 1
        while slow[(hi + 1) % n] and hi - lo < gap:
            hi += 1
        start = (lo - 0.5) / n - half
        shift = math.floor(start + half)  # the crossings' start in [0, 1)
        out.append((start - shift, (hi - 0.5) / n + half - shift))
    return sorted(out)


def switched_sign(v: np.ndarray, windows) -> np.ndarray:
    """sgn(v) on its grid with one switch in each window, midway between its first and
    last zero crossing (the friction's mean there: a noisy crossing's chatter and a
    dwell's slow passage are left to the marginalised deviation)."""
    n = v.shape[0]
    s = _sign(v)
    out = s.copy()
    for lo, hi in windows:
        a, b = int(math.floor(lo * n)), int(math.ceil(hi * n))
        idx = np.arange(a, b + 1)
        inside = s[idx % n]
        flips = np.flatnonzero(inside[1:] != inside[:-1]) + 1  # a crossing before idx[j]
        mid = 0.5 * (idx[flips[0]] + idx[flips[-1]]) if flips.size else 0.5 * (a + b)
        out[idx % n] = np.where(idx < mid, inside[0], inside[-1])
    return out


def window_degrees(lo: float, hi: float, K: int) -> int:
    """The Legendre polynomials a window [lo, hi] gets (see :data:`DEGREES`)."""
    return int(min(MAX_DEGREES, max(DEGREES, math.ceil(2 * K * (hi - lo)))))


def window_basis(windows, K: int, points: int = 64) -> np.ndarray:
    """U (2K, sum of the windows' degrees): the harmonics 1..K (real parts, then imaginary
    parts) of the Legendre polynomials on each window, X_k = 2 int P_j(x(t)) exp(-i k w t) dt / T."""
    k = np.arange(1, K + 1)
    cols = []
    for lo, hi in windows:
        d = window_degrees(lo, hi, K)
        u = lo + (np.arange(points) + 0.5) / points * (hi - lo)  # midpoints, in period shares
        x = 2.0 * (u - lo) / (hi - lo) - 1.0
        e = np.exp(-2j * math.pi * np.outer(k, u)) * (2.0 * (hi - lo) / points)
        X = e @ np.polynomial.legendre.legvander(x, d - 1)  # (K, d): every degree at once
        cols.append(np.vstack([X.real, X.imag]))
    return np.hstack(cols) if cols else np.zeros((2 * K, 0))


@njit(cache=True)
def reversal_correction(U, V, r, s):
    """What the marginal of Gaussian deviations U beta adds to the independent harmonics'
    log-likelihood (module docstring): U the basis, V each harmonic's complex variance,
    r the complex residual, s (m,) each column's prior sd (N)."""
    m = U.shape[1]
    K = V.shape[0]
    if m == 0:
        return 0.0
    M = np.zeros((m, m))
    w = np.zeros(m)
    for i in range(2 * K):
        d = 2.0 / V[i % K]  # 1 / (V / 2)
        ri = r[i].real if i < K else r[i - K].imag
        for a in range(m):
            ua = U[i, a] * d
            w[a] += ua * ri
            for c in range(a, m):
                M[a, c] += ua * U[i, c]
    G = np.empty((m, m))
    for a in range(m):
        w[a] *= s[a]
        for c in range(a, m):
            G[a, c] = s[a] * M[a, c] * s[c]
            G[c, a] = G[a, c]
        G[a, a] += 1.0
    L = np.linalg.cholesky(G)
    logdet = 0.0
    for a in range(m):
        logdet += 2.0 * math.log(L[a, a])
    z = np.linalg.solve(L, w)
    return -0.5 * logdet + 0.5 * float(np.dot(z, z))


def deviations_mean(U, V, r, s) -> np.ndarray:
    """The deviations' posterior mean given the residual, at the harmonics: U beta^ as
    K complex values, beta^ = S (I + S U' D^-1 U S)^-1 S U' D^-1 r (the same Gaussian as
    :func:`reversal_correction`; U, V, r, s as there)."""
    U = np.asarray(U, dtype=float)
    V = np.asarray(V, dtype=float)
    r = np.asarray(r, dtype=complex)
    s = np.asarray(s, dtype=float)
    K = V.shape[0]
    if U.shape[1] == 0:
        return np.zeros(K, dtype=complex)
    d = 2.0 / np.concatenate([V, V])
    rr = np.concatenate([r.real, r.imag])
    SU = U * s  # the columns scaled by their prior sd
    G = np.eye(U.shape[1]) + SU.T @ (d[:, None] * SU)
    fitted = SU @ np.linalg.solve(G, SU.T @ (d * rr))
    return fitted[:K] + 1j * fitted[K:]
