"""The numeric kernel: exact, event-driven simulation of a piecewise-linear network.

Private. A pure function of flat float arrays (cheap to pickle to workers); the only
place where speed tricks live. See ``simulate.py`` for the public entry point.

Method
------
Between events the network is linear with inputs that are linear in time over each
sample interval (first-order hold) and Coulomb forces that are constant. Augmenting the
state with the inputs, their slopes and the Coulomb forces::

    z = [x (n), u (n_in), du (n_in), w (nc)],    z' = Abar_S z

makes every interval an exact matrix exponential. The *mode* S says which contacts stick
(a stuck node's velocity row is zeroed; its friction force is whatever holds it, within
+-f0). For each mode the kernel tabulates ``F_j = exp(Abar_S h / 2^j) - I`` for
j = 0..J by a Taylor series at the finest level and squaring (keeping E - I, which loses
no digits for small steps). A sample interval is then one matrix-vector product unless a
guard is crossed:

- a sliding contact's velocity changes sign (or dips through zero and back, caught by a
  cubic Hermite test on values and derivatives at both ends);
- a stuck contact's holding force leaves [-f0, f0].

The crossing is then located by bisection on the dyadic grid h / 2^J (one product per
halving), the contact switches (stick, reverse, or break away) and the interval goes on
in the new mode. Times are integers in units of h / 2^J, so the remainder of an interval
is a product over the binary digits of what is left. The linear part is exact to
rounding; events are located to h / 2^J (about 1 ns for 1 kHz records).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["run_kernel", "STATUS_OK", "STATUS_TOO_MANY_EVENTS"]

STATUS_OK = 0
STATUS_TOO_MANY_EVENTS = 1

MIN_LEVELS = 20  # event resolution h / 2^20
MAX_LEVELS = 60


@njit(cache=True)
def _levels(Abar, h):
    norm = 0.0
    for i in range(Abar.shape[0]):
        s = 0.0
        for j in range(Abar.shape[1]):
            s += abs(Abar[i, j])
        norm = max(norm, s)
    scaled = norm * h
    J = MIN_LEVELS
    while J < MAX_LEVELS and scaled / 2.0**J > 1.0 / 16.0:
        J += 1
    return J


@njit(cache=True)
def _tables(Abar, h, J):
    """F[j] = exp(Abar h / 2^j) - I for j = 0..J (Taylor at J, then squaring)."""
    m = Abar.shape[0]
    F = np.zeros((J + 1, m, m))
    X = Abar * (h / 2.0**J)
    term = X.copy()
    acc = X.copy()
    for q in range(2, 30):
        term = term @ X / q
        acc += term
        if np.max(np.abs(term)) < 1e-300 or np.max(np.abs(term)) < 1e-18 * np.max(np.abs(acc)):
            break
    F[J] = acc
    for j in range(J - 1, -1, -1):
        G = F[j + 1]
        F[j] = 2.0 * G + G @ G
    return F


@njit(cache=True)
def _step(F, mode, level, z, out, n, n_in, T):
    """out = z + F z over a time T, F = F[mode, level] (its n state rows). Only the n state
    rows need the product: the inputs move linearly (u += du T) and their slopes and the
    Coulomb forces stay. The tables are indexed in place rather than through a view per
    call. Each row's sum runs in the order of j; five rows at a time (independent chains,
    each z[j] loaded once for five rows; the paper's networks have n = 5).

    The small helpers are left to LLVM to inline: numba's own ``inline="always"`` made
    the simulation of a 10 s record 5-7 % slower (measured side by side)."""
    m = z.shape[0]
    i = 0
    while i + 5 <= n:
        s0 = z[i]
        s1 = z[i + 1]
        s2 = z[i + 2]
        s3 = z[i + 3]
        s4 = z[i + 4]
        for j in range(m):
            zj = z[j]
            s0 += F[mode, level, i, j] * zj
            s1 += F[mode, level, i + 1, j] * zj
            s2 += F[mode, level, i + 2, j] * zj
            s3 += F[mode, level, i + 3, j] * zj
            s4 += F[mode, level, i + 4, j] * zj
        out[i] = s0
        out[i + 1] = s1
        out[i + 2] = s2
        out[i + 3] = s3
        out[i + 4] = s4
        i += 5
    while i < n:
        s0 = z[i]
        for j in range(m):
            s0 += F[mode, level, i, j] * z[j]
        out[i] = s0
        i += 1
    for i in range(n, m):
        out[i] = z[i]
    for q in range(n_in):
        out[n + q] += T * z[n + n_in + q]


@njit(cache=True)
def _dot3(M, a, b, z):
    """M[a, b] . z without making the view M[a, b]."""
    s = 0.0
    for j in range(z.shape[0]):
        s += M[a, b, j] * z[j]
    return s


@njit(cache=True)
def _dot2(M, a, z):
    """M[a] . z without making the view M[a]."""
    s = 0.0
    for j in range(z.shape[0]):
        s += M[a, j] * z[j]
    return s


@njit(cache=True)
def _cubic_range(y0, d0, y1, d1):
    """Min and max over s in [0, 1] of the cubic Hermite interpolant (d scaled by T)."""
    lo = min(y0, y1)
    hi = max(y0, y1)
    a = 2.0 * y0 - 2.0 * y1 + d0 + d1
    b = -3.0 * y0 + 3.0 * y1 - 2.0 * d0 - d1
    c = d0
    # extremes at the roots of 3 a s^2 + 2 b s + c inside (0, 1)
    A = 3.0 * a
    B = 2.0 * b
    if abs(A) < 1e-300:
        if abs(B) > 1e-300:
            s = -c / B
            if 0.0 < s < 1.0:
                p = ((a * s + b) * s + c) * s + y0
                lo = min(lo, p)
                hi = max(hi, p)
        return lo, hi
    disc = B * B - 4.0 * A * c
    if disc >= 0.0:
        sq = np.sqrt(disc)
        for s in ((-B - sq) / (2.0 * A), (-B + sq) / (2.0 * A)):
            if 0.0 < s < 1.0:
                p = ((a * s + b) * s + c) * s + y0
                lo = min(lo, p)
                hi = max(hi, p)
    return lo, hi


@njit(cache=True)
def _guards(z, mode, nc, node, R, VD, RD, val, der):
    """Guard values and time derivatives at z: velocity (sliding) or holding force (stuck)."""
    for i in range(nc):
        if (mode >> i) & 1:
            val[i] = _dot2(R, i, z)
            der[i] = _dot3(RD, mode, i, z)
        else:
            val[i] = z[node[i]]
            der[i] = _dot3(VD, mode, i, z)


#: The cubic Hermite interpolant on [0, 1] lies within HERMITE_SLACK (|d0| + |d1|) of the
#: range of its end values (its value basis functions are non-negative and sum to one;
#: each slope basis function is at most 4/27 in size).
HERMITE_SLACK = 4.0 / 27.0


@njit(cache=True)
def _crossed(va, da, vb, db, T, mode, nc, sgn, f0):
    """True when some guard is (or may have been) violated between the two ends.

    A guard whose end values clear its bound by more than the Hermite slack cannot have
    been crossed: the exact cubic test (roots and a square root) runs only where that
    cheap bound fails, which is near the contacts' switches."""
    for i in range(nc):
        slack = HERMITE_SLACK * T * (abs(da[i]) + abs(db[i]))
        if (mode >> i) & 1:
            if abs(vb[i]) > f0[i]:
                return True
            if max(abs(va[i]), abs(vb[i])) + slack <= f0[i]:
                continue
            lo, hi = _cubic_range(va[i], T * da[i], vb[i], T * db[i])
            if hi > f0[i] or lo < -f0[i]:
                return True
        else:
            s = sgn[i]
            if s * vb[i] < 0.0:
                return True
            if min(s * va[i], s * vb[i]) - slack > 0.0:
                continue
            lo, hi = _cubic_range(s * va[i], T * s * da[i], s * vb[i], T * s * db[i])
            if lo < 0.0:
                return True
    return False


@njit(cache=True)
def _advance(z, zn, va, da, vb, db, nc):
    """Move to the end of a step: z = zn and the end's guards become the start's (copies,
    not swaps: rebinding arrays costs atomic reference counting in numba)."""
    for j in range(z.shape[0]):
        z[j] = zn[j]
    for i in range(nc):
        va[i] = vb[i]
        da[i] = db[i]


@njit(cache=True)
def _bisect(F, mode, level, size, z, zc, zm, zn, n, n_in, tick, nc, node, R, VD, RD, va, da, vb, db, sgn, f0):
    """Bisect [0, size] ticks from state z for the first guard crossing, on the dyadic
    grid; returns the ticks advanced before the last halving step, with the state at
    the crossing's end (one tick later) in zn."""
    advanced = np.int64(0)
    for j in range(z.shape[0]):
        zc[j] = z[j]
    # the guards at zc (va, da): computed once here, then carried along (they are those
    # at zm whenever zc moves to zm)
    _guards(zc, mode, nc, node, R, VD, RD, va, da)
    while size > 1:
        size >>= 1
        level += 1
        _step(F, mode, level, zc, zm, n, n_in, tick * size)
        _guards(zm, mode, nc, node, R, VD, RD, vb, db)
        if _crossed(va, da, vb, db, tick * size, mode, nc, sgn, f0):
            for j in range(z.shape[0]):
                zn[j] = zm[j]
        else:
            _advance(zc, zm, va, da, vb, db, nc)
            advanced += size
    return advanced


@njit(cache=True)
def _switch(z, mode, nc, node, R, f0, sgn, wcol):
    """Apply the contact switches due at z; return the new mode (z, sgn changed in place)."""
    for i in range(nc):
        bit = 1 << i
        if mode & bit:
            r = _dot2(R, i, z)
            if abs(r) > f0[i]:  # break away in the direction of the holding force
                mode &= ~bit
                sgn[i] = 1.0 if r > 0 else -1.0
                z[wcol + i] = sgn[i] * f0[i]
        elif sgn[i] * z[node[i]] < 0.0:  # velocity reached zero: stick or reverse
            z[node[i]] = 0.0
            r = _dot2(R, i, z)
            if abs(r) <= f0[i]:
                mode |= bit
            else:
                sgn[i] = 1.0 if r > 0 else -1.0
                z[wcol + i] = sgn[i] * f0[i]
    return mode


@njit(cache=True)
def _setup(Abar, n, n_in, node, mass, h, out_node):
    """Per mode: the tables' n state rows (see _step), the guards' derivative rows VD and
    RD, the output row OUT; and the stuck contacts' holding-force rows R.
    Returns (J, F, VD, RD, OUT, R)."""
    m = Abar.shape[0]
    nc = node.shape[0]
    wcol = n + 2 * n_in
    n_modes = 1 << nc
    J = _levels(Abar, h)
    F = np.zeros((n_modes, J + 1, n, m))
    VD = np.zeros((n_modes, max(nc, 1), m))
    RD = np.zeros((n_modes, max(nc, 1), m))
    OUT = np.zeros((n_modes, m))
    R = np.zeros((max(nc, 1), m))
    for i in range(nc):
        R[i] = mass[i] * Abar[node[i]]
        for q in range(nc):
            R[i, wcol + q] = 0.0
    for mode in range(n_modes):
        As = Abar.copy()
        for i in range(nc):
            if (mode >> i) & 1:
                As[node[i], :] = 0.0
        T = _tables(As, h, J)
        for lev in range(J + 1):
            F[mode, lev] = T[lev][:n]
        for i in range(nc):
            VD[mode, i] = As[node[i]]
            RD[mode, i] = R[i] @ As
        OUT[mode] = As[out_node]
    return J, F, VD, RD, OUT, R


@njit(cache=True)
def _start(z_init, inputs, n, n_in, m, node, R, f0):
    """The augmented state at the first sample, the sliding contacts' signs and the mode:
    contacts at rest stick if they can. Returns (z, sgn, mode)."""
    nc = node.shape[0]
    wcol = n + 2 * n_in
    z = np.zeros(m)
    z[:n] = z_init
    for q in range(n_in):
        z[n + q] = inputs[0, q]
    sgn = np.ones(max(nc, 1))
    mode = 0
    for i in range(nc):
        v = z[node[i]]
        if v == 0.0:
            mode |= 1 << i
        else:
            sgn[i] = 1.0 if v > 0 else -1.0
            z[wcol + i] = sgn[i] * f0[i]
    mode = _switch(z, mode, nc, node, R, f0, sgn, wcol)
    return z, sgn, mode


@njit(cache=True)
def _events(F, mode, J, h, z, zn, zc, zm, n, n_in, node, R, VD, RD, va, da, vb, db, sgn, f0, stats, max_events):
    """One sample interval from z (guards va, da at z) the general way: dyadic steps, each
    checked by the exact Hermite test, a bisection where a guard is crossed, the contact
    switched, and on in the new mode. z, va, da, sgn end at the interval's end.
    Returns (mode, ok); not ok after more than max_events switches."""
    nc = node.shape[0]
    wcol = n + 2 * n_in
    FULL = np.int64(1) << J
    pos = np.int64(0)
    events = 0
    while pos < FULL:
        if pos == 0:
            tz = J
        else:
            tz = 0
            while (pos >> tz) & 1 == 0:
                tz += 1
        size = np.int64(1) << tz
        level = J - tz
        _step(F, mode, level, z, zn, n, n_in, h * size / FULL)
        _guards(zn, mode, nc, node, R, VD, RD, vb, db)
        if not _crossed(va, da, vb, db, h * size / FULL, mode, nc, sgn, f0):
            _advance(z, zn, va, da, vb, db, nc)
            pos += size
            continue
        # Bisect for the first crossing inside [pos, pos + size] (out of line: the
        # rare path, kept out of the hot loop's code).
        stats[1] += 1
        pos += _bisect(F, mode, level, size, z, zc, zm, zn, n, n_in, h / FULL, nc, node, R, VD, RD,
                       va, da, vb, db, sgn, f0)
        pos += 1
        z[:] = zn
        new_mode = _switch(z, mode, nc, node, R, f0, sgn, wcol)
        if new_mode != mode:
            stats[0] += 1
            mode = new_mode
        # a switch, or none due: a false alarm of the Hermite test, or a switch that left
        # the mode unchanged (a reversal); count all to bound the work
        events += 1
        if events > max_events:
            return mode, False
        _guards(z, mode, nc, node, R, VD, RD, va, da)
    return mode, True


@njit(cache=True)
def run_kernel(Abar, n, n_in, node, f0, mass, inputs, h, z_init, out_node, store, max_events):
    """Simulate; see module docstring. The general kernel, for any sizes; ``kernel_for``
    gives one specialised to a network's sizes, with the same numbers.

    Parameters
    ----------
    Abar : (m, m) augmented matrix with no contact stuck; m = n + 2 n_in + nc.
    n, n_in : state and input sizes.
    node, f0, mass : (nc,) contact node index, Coulomb bound (N, > 0), node mass (kg).
    inputs : (K, n_in) input samples, linearly interpolated between samples.
    h : sample interval, s.
    z_init : (n,) initial state.
    out_node : node whose acceleration is returned.
    store : whether to return the state at every sample.
    max_events : switches allowed within one sample interval before giving up.

    Returns
    -------
    accel : (K,) acceleration of out_node just after each sample instant, m/s^2.
    vel : (K,) velocity of out_node at each sample instant, m/s (continuous in the
        parameters, unlike accel, which jumps at every Coulomb switch).
    states : (K, n) states at the samples (shape (0, n) unless store).
    status : STATUS_OK, or STATUS_TOO_MANY_EVENTS (accel, vel then NaN from that sample on).
    stats : (2,) int, the number of mode switches and of bisections (switch searches).
    """
    m = Abar.shape[0]
    nc = node.shape[0]
    K = inputs.shape[0]
    J, F, VD, RD, OUT, R = _setup(Abar, n, n_in, node, mass, h, out_node)

    accel = np.full(K, np.nan)
    vel = np.full(K, np.nan)
    stats = np.zeros(2, dtype=np.int64)  # mode switches, bisections
    states = np.zeros((K if store else 0, n))
    z, sgn, mode = _start(z_init, inputs, n, n_in, m, node, R, f0)
    accel[0] = _dot2(OUT, mode, z)
    vel[0] = z[out_node]
    if store:
        states[0] = z[:n]

    # The current mode's level-0 table, copied into a small contiguous array at each mode
    # change (a copy rather than the 4-d index in the fast path: about 5 % faster).
    FS = np.empty((n, m))
    cur = -1
    # A sliding contact acon at out_node has VD[mode, acon] = OUT[mode] (both are
    # As[out_node]), and at an interval's end da holds the guards at z, whichever path got
    # there: the output is then da[acon], the very same sum (no second product).
    acon = -1

    zn = np.empty(m)
    zc = np.empty(m)
    zm = np.empty(m)
    va = np.empty(max(nc, 1))
    da = np.empty(max(nc, 1))
    vb = np.empty(max(nc, 1))
    db = np.empty(max(nc, 1))
    for k in range(K - 1):
        if mode != cur:
            cur = mode
            acon = -1
            for i in range(nc):
                if node[i] == out_node and not (mode >> i) & 1:
                    acon = i
            for i in range(n):
                for j in range(m):
                    FS[i, j] = F[mode, 0, i, j]
        for q in range(n_in):
            z[n + q] = inputs[k, q]
            z[n + n_in + q] = (inputs[k + 1, q] - inputs[k, q]) / h
        if k == 0:
            _guards(z, mode, nc, node, R, VD, RD, va, da)
        else:
            # the guards at the interval's start are those at the last one's end, but for
            # a stuck contact's holding-force rate, which sees the new input slope
            for i in range(nc):
                if (mode >> i) & 1:
                    da[i] = _dot3(RD, mode, i, z)
        # Fast path, written out in the loop: the whole interval in one step, its guards,
        # and the cheap Hermite bound; _events takes over only where the bound fails (near
        # the contacts' switches).
        i = 0
        while i + 5 <= n:
            s0 = z[i]
            s1 = z[i + 1]
            s2 = z[i + 2]
            s3 = z[i + 3]
            s4 = z[i + 4]
            for j in range(m):
                zj = z[j]
                s0 += FS[i, j] * zj
                s1 += FS[i + 1, j] * zj
                s2 += FS[i + 2, j] * zj
                s3 += FS[i + 3, j] * zj
                s4 += FS[i + 4, j] * zj
            zn[i] = s0
            zn[i + 1] = s1
            zn[i + 2] = s2
            zn[i + 3] = s3
            zn[i + 4] = s4
            i += 5
        while i < n:
            s0 = z[i]
            for j in range(m):
                s0 += FS[i, j] * z[j]
            zn[i] = s0
            i += 1
        for i in range(n, m):
            zn[i] = z[i]
        for q in range(n_in):
            zn[n + q] += h * z[n + n_in + q]
        clear = True
        for i in range(nc):
            d = 0.0
            if (mode >> i) & 1:
                v = 0.0
                for j in range(m):
                    v += R[i, j] * zn[j]
                    d += RD[mode, i, j] * zn[j]
            else:
                v = zn[node[i]]
                for j in range(m):
                    d += VD[mode, i, j] * zn[j]
            vb[i] = v
            db[i] = d
            slack = HERMITE_SLACK * h * (abs(da[i]) + abs(d))
            if (mode >> i) & 1:
                if max(abs(va[i]), abs(v)) + slack > f0[i]:
                    clear = False
            elif min(sgn[i] * va[i], sgn[i] * v) - slack <= 0.0:
                clear = False
        if clear:
            for j in range(m):
                z[j] = zn[j]
            for i in range(nc):
                va[i] = vb[i]
                da[i] = db[i]
        else:
            mode, ok = _events(F, mode, J, h, z, zn, zc, zm, n, n_in, node, R, VD, RD, va, da, vb, db, sgn, f0,
                               stats, max_events)
            if not ok:
                return accel, vel, states, STATUS_TOO_MANY_EVENTS, stats
        if acon >= 0 and mode == cur:
            accel[k + 1] = da[acon]
        else:
            accel[k + 1] = _dot2(OUT, mode, z)
        vel[k + 1] = z[out_node]
        if store:
            states[k + 1] = z[:n]
    return accel, vel, states, STATUS_OK, stats


# -- kernels specialised to a network's sizes ------------------------------------------
#
# run_kernel keeps the state in arrays whose sizes it learns at run time, so the compiler
# must assume any store may change any array: every sample reloads the state, the tables
# and the guards from memory (about 20 ns a sample of pure bookkeeping, measured with the
# products taken out). The specialised kernel is the same loop written out for fixed
# sizes, contact nodes and output node, with the state, the current mode's table rows and
# the guards in local variables; every sum is formed in run_kernel's order, so the
# numbers are the same bit for bit. The rare path (an interval where the cheap bound
# fails) stores the locals into the arrays and runs ``events``, _events written out in
# the same way (``_events_source``). Rare as it is, it was most of the time: on A3 at
# 1 Hz (10 s, paper's parameters) 226 of 10,000 intervals took it, and their 62
# bisections and the intervals' remainders came to about 2,100 dyadic steps, each a
# step, the guards and the Hermite test passing arrays between compiled functions: the
# kernel took 428 us, and 155 us with the rare path cut out (every interval taken as
# clear). Written out, it took 256 us (medians of 40, same numbers bit for bit).

_SPECIALISED: dict = {}


def _dot_source(coef, names, cols) -> str:
    """Source of the sum s = 0.0; s += coef(j) * names[j] for j in cols, in that order (as
    _dot2 and _dot3 sum)."""
    expr = "0.0"
    for j in cols:
        expr = f"({expr} + {coef(j)} * {names[j]})"
    return expr


def _load_source(m: int, indent: str) -> list:
    """Lines that load the state array z into the locals z0, z1, ..."""
    return [f"{indent}z{j} = z[{j}]" for j in range(m)]


def _store_source(m: int, indent: str) -> list:
    """Lines that store the locals z0, z1, ... into the state array z."""
    return [f"{indent}z[{j}] = z{j}" for j in range(m)]


def _step_source(n: int, n_in: int, m: int, coef, src: str, dst: str, T: str, indent: str) -> list:
    """Lines of _step written out: dst = src + F src over a time T (F's entry (i, j) is
    ``coef(i, j)``; each row's sum in the order of j), for locals named src0, src1, ..."""
    lines = []
    for i in range(n):
        expr = f"{src}{i}"
        for j in range(m):
            expr = f"({expr} + {coef(i, j)} * {src}{j})"
        lines.append(f"{indent}{dst}{i} = {expr}")
    lines += [f"{indent}{dst}{j} = {src}{j}" for j in range(n, m)]
    lines += [f"{indent}{dst}{n + q} = {src}{n + q} + {T} * {src}{n + n_in + q}" for q in range(n_in)]
    return lines


def _events_source(n: int, n_in: int, node: tuple, r_cols: list, vd_cols: list, rd_cols: list) -> str:
    """The source of ``crossed`` and ``events``: _crossed and _events (with _bisect, _step,
    _guards and _advance) written out for one network, every sum in the order of the
    general functions (the guards' structural zeros left out, as in the fast path). The
    general functions pass arrays between them at every step of the rare path; here the
    states and guards live in local variables (the kernel on A3 at 1 Hz: 256 against 428
    us, see the comment above and ``benchmarks/bench_kernel.py``)."""
    nc = len(node)
    m = n + 2 * n_in + nc
    lines = []
    add = lines.append

    args = ", ".join(f"va{i}, da{i}, vb{i}, db{i}, sg{i}, f0_{i}" for i in range(nc))

    def dot(coef, vec, cols):
        return _dot_source(coef, [f"{vec}{j}" for j in range(m)], cols)

    def step(src, dst, T, ind):  # _step: dst = src + F[mode, level] src over a time T
        lines.extend(_step_source(n, n_in, m, lambda i, j: f"F[mode, level, {i}, {j}]", src, dst, T, ind))

    def guards(src, val, der, ind):  # _guards: each contact's guard and its rate at src
        for i in range(nc):
            add(f"{ind}if (mode >> {i}) & 1:")
            add(f"{ind}    {val}{i} = {dot(lambda j, i=i: f'R[{i}, {j}]', src, r_cols[i])}")
            add(f"{ind}    {der}{i} = {dot(lambda j, i=i: f'RD[mode, {i}, {j}]', src, rd_cols[i])}")
            add(f"{ind}else:")
            add(f"{ind}    {val}{i} = {src}{node[i]}")
            add(f"{ind}    {der}{i} = {dot(lambda j, i=i: f'VD[mode, {i}, {j}]', src, vd_cols[i])}")

    def copy(src, dst, ind):
        for j in range(m):
            add(f"{ind}{dst}{j} = {src}{j}")

    def probe(src, dst, ind):  # a step from src, the guards at its end, and the test
        step(src, dst, "T", ind)
        guards(dst, "vb", "db", ind)
        return f"crossed(mode, T, {args})"

    def advance(src, dst, ind):  # _advance: the step's end becomes the start
        copy(src, dst, ind)
        for i in range(nc):
            add(f"{ind}va{i} = vb{i}")
            add(f"{ind}da{i} = db{i}")

    def load(ind):
        lines.extend(_load_source(m, ind))
        for i in range(nc):
            add(f"{ind}sg{i} = sgn[{i}]")

    def store(ind):
        lines.extend(_store_source(m, ind))

    add("@_jit")
    add(f"def crossed(mode, T{', ' + args if nc else ''}):")
    add("    # _crossed on scalars")
    for i in range(nc):
        add(f"    slack = HERMITE_SLACK * T * (abs(da{i}) + abs(db{i}))")
        add(f"    if (mode >> {i}) & 1:")
        add(f"        if abs(vb{i}) > f0_{i}:")
        add("            return True")
        add(f"        if not max(abs(va{i}), abs(vb{i})) + slack <= f0_{i}:")
        add(f"            lo, hi = _cubic_range(va{i}, T * da{i}, vb{i}, T * db{i})")
        add(f"            if hi > f0_{i} or lo < -f0_{i}:")
        add("                return True")
        add("    else:")
        add(f"        if sg{i} * vb{i} < 0.0:")
        add("            return True")
        add(f"        if not min(sg{i} * va{i}, sg{i} * vb{i}) - slack > 0.0:")
        add(f"            lo, hi = _cubic_range(sg{i} * va{i}, T * sg{i} * da{i}, sg{i} * vb{i}, T * sg{i} * db{i})")
        add("            if lo < 0.0:")
        add("                return True")
    add("    return False")
    add("")
    add("")
    add("@_jit")
    add("def events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events):")
    add("    # _events on local variables: z, va, da, sgn in and out")
    add(f"    wcol = {n + 2 * n_in}")
    load("    ")
    for i in range(nc):
        add(f"    va{i} = va[{i}]")
        add(f"    da{i} = da[{i}]")
        add(f"    vb{i} = 0.0")
        add(f"    db{i} = 0.0")
        add(f"    f0_{i} = f0[{i}]")
    add("    FULL = np.int64(1) << J")
    add("    pos = np.int64(0)")
    add("    count = 0")
    add("    while pos < FULL:")
    add("        if pos == 0:")
    add("            tz = J")
    add("        else:")
    add("            tz = 0")
    add("            while (pos >> tz) & 1 == 0:")
    add("                tz += 1")
    add("        size = np.int64(1) << tz")
    add("        level = J - tz")
    add("        T = h * size / FULL")
    add(f"        if not {probe('z', 'y', '        ')}:")
    advance("y", "z", "            ")
    add("            pos += size")
    add("            continue")
    add("        stats[1] += 1")
    add("        # _bisect: [0, size] ticks from z for the first crossing; its end state in y")
    add("        tick = h / FULL")
    add("        advanced = np.int64(0)")
    copy("z", "c", "        ")
    guards("c", "va", "da", "        ")
    add("        while size > 1:")
    add("            size >>= 1")
    add("            level += 1")
    add("            T = tick * size")
    add(f"            if {probe('c', 'w', '            ')}:")
    copy("w", "y", "                ")
    add("            else:")
    advance("w", "c", "                ")
    add("                advanced += size")
    add("        pos += advanced")
    add("        pos += 1")
    copy("y", "z", "        ")
    store("        ")
    add(f"        new_mode = _switch(z, mode, {nc}, node, R, f0, sgn, wcol)")
    load("        ")
    add("        if new_mode != mode:")
    add("            stats[0] += 1")
    add("            mode = new_mode")
    add("        count += 1")
    add("        if count > max_events:")
    add("            return mode, False")
    guards("z", "va", "da", "        ")
    store("    ")
    for i in range(nc):
        add(f"    va[{i}] = va{i}")
        add(f"    da[{i}] = da{i}")
    add("    return mode, True")
    return "\n".join(lines) + "\n"


def _specialised_source(n: int, n_in: int, node: tuple, out_node: int, nonzero: bytes | None = None) -> str:
    """The source of run_kernel specialised to these sizes and nodes (see above).

    ``nonzero``: the augmented matrix's nonzero pattern (``(Abar != 0).tobytes()``), or
    None for a dense one. The guards' rows and the output row are rows of Abar (of R @
    Abar for a stuck contact's holding-force rate), so their terms where the pattern says
    zero are left out: a term 0 * z adds nothing to the sum (but the sign of a zero
    result), and with both contacts sliding this leaves about half of the guards'
    products. The tables' rows (exponentials) are taken as dense."""
    nc = len(node)
    m = n + 2 * n_in + nc
    wcol = n + 2 * n_in
    P = np.ones((m, m), dtype=bool) if nonzero is None else np.frombuffer(nonzero, dtype=bool).reshape(m, m)
    r_cols, vd_cols, rd_cols = [], [], []
    for i in range(nc):
        r = P[node[i]].copy()
        r[wcol:] = False
        r_cols.append([j for j in range(m) if r[j]])
        vd_cols.append([j for j in range(m) if P[node[i], j]])
        rd = (r[:, None] & P).any(axis=0)
        rd_cols.append([j for j in range(m) if rd[j]])
    out_cols = [j for j in range(m) if P[out_node, j]]
    zs = [f"z{j}" for j in range(m)]
    lines = []
    add = lines.append

    dot = _dot_source

    def load_z(indent):
        lines.extend(_load_source(m, indent))

    def store_z(indent):
        lines.extend(_store_source(m, indent))

    add("@_jit")
    add("def kernel(Abar, n_, n_in_, node, f0, mass, inputs, h, z_init, out_node_, store, max_events):")
    add(f"    n = {n}")
    add(f"    n_in = {n_in}")
    add(f"    m = {m}")
    add("    K = inputs.shape[0]")
    add("    J, F, VD, RD, OUT, R = _setup(Abar, n, n_in, node, mass, h, out_node_)")
    add("    accel = np.full(K, np.nan)")
    add("    vel = np.full(K, np.nan)")
    add("    stats = np.zeros(2, dtype=np.int64)")
    add("    states = np.zeros((K if store else 0, n))")
    add("    z, sgn, mode = _start(z_init, inputs, n, n_in, m, node, R, f0)")
    add("    accel[0] = _dot2(OUT, mode, z)")
    add(f"    vel[0] = z[{out_node}]")
    add("    if store:")
    add("        states[0] = z[:n]")
    w = max(nc, 1)
    for a in ("va", "da"):
        add(f"    {a} = np.empty({w})")
    load_z("    ")
    for i in range(nc):
        add(f"    f0_{i} = f0[{i}]")
        add(f"    sg{i} = sgn[{i}]")
        add(f"    va{i} = 0.0")
        add(f"    da{i} = 0.0")
        for j in r_cols[i]:
            add(f"    r{i}_{j} = R[{i}, {j}]")
        for j in vd_cols[i]:
            add(f"    vd{i}_{j} = 0.0")
        for j in rd_cols[i]:
            add(f"    rd{i}_{j} = 0.0")
    for i in range(n):
        for j in range(m):
            add(f"    f{i}_{j} = 0.0")
    add("    cur = -1")
    add("    acon = -1")
    add("    for k in range(K - 1):")
    add("        if mode != cur:")
    add("            cur = mode")
    add("            acon = -1")
    for i in range(nc):
        if node[i] == out_node:
            add(f"            if not (mode >> {i}) & 1:")
            add(f"                acon = {i}")
    for i in range(n):
        for j in range(m):
            add(f"            f{i}_{j} = F[mode, 0, {i}, {j}]")
    for i in range(nc):
        for j in vd_cols[i]:
            add(f"            vd{i}_{j} = VD[mode, {i}, {j}]")
        for j in rd_cols[i]:
            add(f"            rd{i}_{j} = RD[mode, {i}, {j}]")
    for q in range(n_in):
        add(f"        z{n + q} = inputs[k, {q}]")
        add(f"        z{n + n_in + q} = (inputs[k + 1, {q}] - inputs[k, {q}]) / h")
    add("        if k == 0:")
    store_z("            ")
    add("            _guards(z, mode, {nc}, node, R, VD, RD, va, da)".format(nc=nc))
    for i in range(nc):
        add(f"            va{i} = va[{i}]")
        add(f"            da{i} = da[{i}]")
    if nc:
        add("        else:")
        for i in range(nc):
            add(f"            if (mode >> {i}) & 1:")
            add(f"                da{i} = {dot(lambda j, i=i: f'rd{i}_{j}', zs, rd_cols[i])}")
    else:
        add("        pass")
    # the whole interval in one step
    zn = [f"y{j}" for j in range(m)]
    lines.extend(_step_source(n, n_in, m, lambda i, j: f"f{i}_{j}", "z", "y", "h", "        "))
    add("        clear = True")
    for i in range(nc):
        add(f"        if (mode >> {i}) & 1:")
        add(f"            vb{i} = {dot(lambda j, i=i: f'r{i}_{j}', zn, r_cols[i])}")
        add(f"            db{i} = {dot(lambda j, i=i: f'rd{i}_{j}', zn, rd_cols[i])}")
        add(f"            slack = HERMITE_SLACK * h * (abs(da{i}) + abs(db{i}))")
        add(f"            if max(abs(va{i}), abs(vb{i})) + slack > f0_{i}:")
        add("                clear = False")
        add("        else:")
        add(f"            vb{i} = {zn[node[i]]}")
        add(f"            db{i} = {dot(lambda j, i=i: f'vd{i}_{j}', zn, vd_cols[i])}")
        add(f"            slack = HERMITE_SLACK * h * (abs(da{i}) + abs(db{i}))")
        add(f"            if min(sg{i} * va{i}, sg{i} * vb{i}) - slack <= 0.0:")
        add("                clear = False")
    add("        if clear:")
    for j in range(m):
        add(f"            {zs[j]} = {zn[j]}")
    for i in range(nc):
        add(f"            va{i} = vb{i}")
        add(f"            da{i} = db{i}")
    add("        else:")
    store_z("            ")
    for i in range(nc):
        add(f"            va[{i}] = va{i}")
        add(f"            da[{i}] = da{i}")
    add("            mode, ok = events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events)")
    add("            if not ok:")
    add("                return accel, vel, states, STATUS_TOO_MANY_EVENTS, stats")
    load_z("            ")
    for i in range(nc):
        add(f"            va{i} = va[{i}]")
        add(f"            da{i} = da[{i}]")
        add(f"            sg{i} = sgn[{i}]")
    at_out = [i for i in range(nc) if node[i] == out_node]
    cond = "if"
    for i in at_out:
        add(f"        {cond} acon == {i} and mode == cur:")
        add(f"            accel[k + 1] = da{i}")
        cond = "elif"
    if at_out:
        add("        else:")
        add(f"            accel[k + 1] = {dot(lambda j: f'OUT[mode, {j}]', zs, out_cols)}")
    else:
        add(f"        accel[k + 1] = {dot(lambda j: f'OUT[mode, {j}]', zs, out_cols)}")
    add(f"        vel[k + 1] = {zs[out_node]}")
    add("        if store:")
    for i in range(n):
        add(f"            states[k + 1, {i}] = {zs[i]}")
    add("    return accel, vel, states, STATUS_OK, stats")
    return _events_source(n, n_in, node, r_cols, vd_cols, rd_cols) + "\n\n" + "\n".join(lines) + "\n"


#: Where the specialised kernels' generated modules are written, so that numba's cache
#: keeps their machine code between processes: ``$BAYES_INERTER_KERNEL_DIR``, else
#: ``~/.cache/bayes-inerter/kernels``, else a folder in the temporary directory. Files
#: are named by a hash of their source and of this module's, so a changed kernel never
#: meets an old cache. Where no folder can be written they are compiled in memory.
KERNEL_DIR_ENV = "BAYES_INERTER_KERNEL_DIR"


def _kernel_dirs():
    import os
    import tempfile
    from pathlib import Path

    if os.environ.get(KERNEL_DIR_ENV):
        yield Path(os.environ[KERNEL_DIR_ENV])
    yield Path.home() / ".cache" / "bayes-inerter" / "kernels"
    yield Path(tempfile.gettempdir()) / f"bayes-inerter-kernels-{os.getuid() if hasattr(os, 'getuid') else 0}"


_HEADER = (
    "import numpy as np\n"
    "from numba import njit\n"
    "from bayes_inerter._kernel import (HERMITE_SLACK, STATUS_OK, STATUS_TOO_MANY_EVENTS, _cubic_range, _dot2,\n"
    "                                   _guards, _setup, _start, _switch)\n\n"
)


def _load_specialised(source: str):
    import hashlib
    import importlib.util
    import os
    import sys
    from pathlib import Path

    own = Path(__file__).read_bytes()
    digest = hashlib.sha256(own + source.encode()).hexdigest()[:20]
    name = f"bayes_inerter_kernel_{digest}"
    text = _HEADER + "_jit = njit(cache=True)\n\n\n" + source
    for folder in _kernel_dirs():
        path = folder / f"{name}.py"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            if not path.exists() or path.read_text() != text:
                tmp = folder / f".{name}.{os.getpid()}.tmp"
                tmp.write_text(text)
                os.replace(tmp, path)
        except OSError:
            continue
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # numba's cache finds the function's module by name
        spec.loader.exec_module(module)
        return module.kernel
    namespace: dict = {}
    exec(compile(_HEADER + "_jit = njit\n\n\n" + source, name, "exec"), namespace)
    return namespace["kernel"]


def kernel_for(n: int, n_in: int, node, out_node: int, nonzero: bytes | None = None):
    """run_kernel specialised to a network: state size ``n``, ``n_in`` inputs, contacts at
    ``node`` (a sequence of node indices), the output node, and optionally the augmented
    matrix's nonzero pattern ``(Abar != 0).tobytes()`` (see ``_specialised_source``; the
    kernel is then for matrices with zeros at least there). Takes run_kernel's arguments
    and gives its results, bit for bit but for the sign of a zero; compiled once per
    process (numba's cache keeps it between processes where a folder can be written, see
    ``KERNEL_DIR_ENV``)."""
    key = (int(n), int(n_in), tuple(int(x) for x in node), int(out_node), nonzero)
    fn = _SPECIALISED.get(key)
    if fn is None:
        fn = _SPECIALISED[key] = _load_specialised(_specialised_source(*key))
    return fn
