@_jit
def crossed(mode, T, va0, da0, vb0, db0, sg0, bound0):
    # True when some guard is (or may have been) crossed between the two ends of a step:
    # the end's value, then a cheap bound on the Hermite cubic through both ends, and
    # the cubic's exact range only where that bound fails (near the switches)
    slack = HERMITE_SLACK * T * (abs(da0) + abs(db0))
    if (mode >> 0) & 1:  # stuck: its holding force stays within +-bound
        if abs(vb0) > bound0:
            return True
        if not max(abs(va0), abs(vb0)) + slack <= bound0:
            lo, hi = cubic_range(va0, T * da0, vb0, T * db0)
            if hi > bound0 or lo < -bound0:
                return True
    else:  # sliding: its velocity keeps its sign
        if sg0 * vb0 < 0.0:
            return True
        if not min(sg0 * va0, sg0 * vb0) - slack > 0.0:
            lo, hi = cubic_range(sg0 * va0, T * sg0 * da0, sg0 * vb0, T * sg0 * db0)
            if lo < 0.0:
                return True
    return False


@_jit
def events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events):
    # One sample interval from z the careful way: dyadic steps, each checked by crossed;
    # where a guard is crossed, bisection for the first tick after the crossing, the
    # contacts switched there, and on in the new mode. z, va, da, sgn in and out.
    wcol = 3
    z0 = z[0]
    z1 = z[1]
    z2 = z[2]
    z3 = z[3]
    sg0 = sgn[0]
    va0 = va[0]
    da0 = da[0]
    vb0 = 0.0
    db0 = 0.0
    bound0 = f0[0]
    FULL = np.int64(1) << J
    pos = np.int64(0)
    count = 0
    while pos < FULL:
        # the longest dyadic step from pos: the whole interval, or pos's lowest set bit
        if pos == 0:
            tz = J
        else:
            tz = 0
            while (pos >> tz) & 1 == 0:
                tz += 1
        size = np.int64(1) << tz
        level = J - tz
        T = h * size / FULL
        y0 = ((((z0 + F[mode, level, 0, 0] * z0) + F[mode, level, 0, 1] * z1) + F[mode, level, 0, 2] * z2) + F[mode, level, 0, 3] * z3)
        y1 = z1
        y2 = z2
        y3 = z3
        y1 = z1 + T * z2
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            vb0 = ((0.0 + R[0, 0] * y0) + R[0, 1] * y1)
            db0 = ((((0.0 + RD[mode, 0, 0] * y0) + RD[mode, 0, 1] * y1) + RD[mode, 0, 2] * y2) + RD[mode, 0, 3] * y3)
        else:  # sliding: the velocity and the acceleration
            vb0 = y0
            db0 = (((0.0 + VD[mode, 0, 0] * y0) + VD[mode, 0, 1] * y1) + VD[mode, 0, 3] * y3)
        if not crossed(mode, T, va0, da0, vb0, db0, sg0, bound0):
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            va0 = vb0
            da0 = db0
            pos += size
            continue
        stats[1] += 1
        # bisect [0, size] ticks from z for the first crossing: c moves up to the last
        # tick before it, y ends one tick after it
        tick = h / FULL
        advanced = np.int64(0)
        c0 = z0
        c1 = z1
        c2 = z2
        c3 = z3
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            va0 = ((0.0 + R[0, 0] * c0) + R[0, 1] * c1)
            da0 = ((((0.0 + RD[mode, 0, 0] * c0) + RD[mode, 0, 1] * c1) + RD[mode, 0, 2] * c2) + RD[mode, 0, 3] * c3)
        else:  # sliding: the velocity and the acceleration
            va0 = c0
            da0 = (((0.0 + VD[mode, 0, 0] * c0) + VD[mode, 0, 1] * c1) + VD[mode, 0, 3] * c3)
        while size > 1:
            size >>= 1
            level += 1
            T = tick * size
            w0 = ((((c0 + F[mode, level, 0, 0] * c0) + F[mode, level, 0, 1] * c1) + F[mode, level, 0, 2] * c2) + F[mode, level, 0, 3] * c3)
            w1 = c1
            w2 = c2
            w3 = c3
            w1 = c1 + T * c2
            if (mode >> 0) & 1:  # stuck: the holding force and its rate
                vb0 = ((0.0 + R[0, 0] * w0) + R[0, 1] * w1)
                db0 = ((((0.0 + RD[mode, 0, 0] * w0) + RD[mode, 0, 1] * w1) + RD[mode, 0, 2] * w2) + RD[mode, 0, 3] * w3)
            else:  # sliding: the velocity and the acceleration
                vb0 = w0
                db0 = (((0.0 + VD[mode, 0, 0] * w0) + VD[mode, 0, 1] * w1) + VD[mode, 0, 3] * w3)
            if crossed(mode, T, va0, da0, vb0, db0, sg0, bound0):
                y0 = w0
                y1 = w1
                y2 = w2
                y3 = w3
            else:
                c0 = w0
                c1 = w1
                c2 = w2
                c3 = w3
                va0 = vb0
                da0 = db0
                advanced += size
        pos += advanced
        pos += 1
        # the contacts switch at y, and the interval goes on from there
        z0 = y0
        z1 = y1
        z2 = y2
        z3 = y3
        z[0] = z0
        z[1] = z1
        z[2] = z2
        z[3] = z3
        new_mode = switch(z, mode, np.int64(1), node, R, f0, sgn, np.int64(wcol))
        z0 = z[0]
        z1 = z[1]
        z2 = z[2]
        z3 = z[3]
        sg0 = sgn[0]
        if new_mode != mode:
            stats[0] += 1
            mode = new_mode
        # a switch, or none due (a false alarm of the cubic test, or a reversal, which
        # keeps the mode): count all, to bound the work
        count += 1
        if count > max_events:
            return mode, False
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            va0 = ((0.0 + R[0, 0] * z0) + R[0, 1] * z1)
            da0 = ((((0.0 + RD[mode, 0, 0] * z0) + RD[mode, 0, 1] * z1) + RD[mode, 0, 2] * z2) + RD[mode, 0, 3] * z3)
        else:  # sliding: the velocity and the acceleration
            va0 = z0
            da0 = (((0.0 + VD[mode, 0, 0] * z0) + VD[mode, 0, 1] * z1) + VD[mode, 0, 3] * z3)
    z[0] = z0
    z[1] = z1
    z[2] = z2
    z[3] = z3
    va[0] = va0
    da[0] = da0
    return mode, True


@_jit
def kernel(Abar, n_, n_in_, node, f0, mass, inputs, h, z_init, out_node_, store, max_events):
    n = 1
    n_in = 1
    m = 4
    K = inputs.shape[0]
    J, F, VD, RD, OUT, R = setup(Abar, np.int64(n), np.int64(n_in), node, mass, h, out_node_)
    accel = np.full(K, np.nan)
    vel = np.full(K, np.nan)
    stats = np.zeros(2, dtype=np.int64)
    states = np.zeros((K if store else 0, n))
    z, sgn, mode = start(z_init, inputs, np.int64(n), np.int64(n_in), np.int64(m), node, R, f0)
    z0 = z[0]
    z1 = z[1]
    z2 = z[2]
    z3 = z[3]
    accel[0] = (((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3)
    vel[0] = z0
    if store:
        for i in range(n):
            states[0, i] = z[i]
    va = np.empty(1)
    da = np.empty(1)
    bound0 = f0[0]
    sg0 = sgn[0]
    va0 = 0.0
    da0 = 0.0
    r0_0 = R[0, 0]
    r0_1 = R[0, 1]
    vd0_0 = 0.0
    vd0_1 = 0.0
    vd0_3 = 0.0
    rd0_0 = 0.0
    rd0_1 = 0.0
    rd0_2 = 0.0
    rd0_3 = 0.0
    f0_0 = 0.0
    f0_1 = 0.0
    f0_2 = 0.0
    f0_3 = 0.0
    cur = -1
    acon = -1
    for k in range(K - 1):
        if mode != cur:
            # a new mode: its table's first level and its guards' rows into locals; a
            # sliding contact at the output node gives the output as its guard's rate
            cur = mode
            acon = -1
            if not (mode >> 0) & 1:
                acon = 0
            f0_0 = F[mode, 0, 0, 0]
            f0_1 = F[mode, 0, 0, 1]
            f0_2 = F[mode, 0, 0, 2]
            f0_3 = F[mode, 0, 0, 3]
            vd0_0 = VD[mode, 0, 0]
            vd0_1 = VD[mode, 0, 1]
            vd0_3 = VD[mode, 0, 3]
            rd0_0 = RD[mode, 0, 0]
            rd0_1 = RD[mode, 0, 1]
            rd0_2 = RD[mode, 0, 2]
            rd0_3 = RD[mode, 0, 3]
        z1 = inputs[k, 0]
        z2 = (inputs[k + 1, 0] - inputs[k, 0]) / h
        if k == 0:
            if (mode >> 0) & 1:  # stuck: the holding force and its rate
                va0 = ((0.0 + r0_0 * z0) + r0_1 * z1)
                da0 = ((((0.0 + rd0_0 * z0) + rd0_1 * z1) + rd0_2 * z2) + rd0_3 * z3)
            else:  # sliding: the velocity and the acceleration
                va0 = z0
                da0 = (((0.0 + vd0_0 * z0) + vd0_1 * z1) + vd0_3 * z3)
        else:
            # the guards at the start are those at the last interval's end, but for a
            # stuck contact's holding-force rate, which sees the new input slope
            if (mode >> 0) & 1:
                da0 = ((((0.0 + rd0_0 * z0) + rd0_1 * z1) + rd0_2 * z2) + rd0_3 * z3)
        # the common case: the whole interval in one step, its guards, and the cheap
        # Hermite bound; events takes over only where that bound fails
        y0 = ((((z0 + f0_0 * z0) + f0_1 * z1) + f0_2 * z2) + f0_3 * z3)
        y1 = z1
        y2 = z2
        y3 = z3
        y1 = z1 + h * z2
        clear = True
        if (mode >> 0) & 1:
            vb0 = ((0.0 + r0_0 * y0) + r0_1 * y1)
            db0 = ((((0.0 + rd0_0 * y0) + rd0_1 * y1) + rd0_2 * y2) + rd0_3 * y3)
            slack = HERMITE_SLACK * h * (abs(da0) + abs(db0))
            if max(abs(va0), abs(vb0)) + slack > bound0:
                clear = False
        else:
            vb0 = y0
            db0 = (((0.0 + vd0_0 * y0) + vd0_1 * y1) + vd0_3 * y3)
            slack = HERMITE_SLACK * h * (abs(da0) + abs(db0))
            if min(sg0 * va0, sg0 * vb0) - slack <= 0.0:
                clear = False
        if clear:
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            va0 = vb0
            da0 = db0
        else:
            z[0] = z0
            z[1] = z1
            z[2] = z2
            z[3] = z3
            va[0] = va0
            da[0] = da0
            mode, ok = events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events)
            if not ok:
                return accel, vel, states, STATUS_TOO_MANY_EVENTS, stats
            z0 = z[0]
            z1 = z[1]
            z2 = z[2]
            z3 = z[3]
            va0 = va[0]
            da0 = da[0]
            sg0 = sgn[0]
        if acon == 0 and mode == cur:
            accel[k + 1] = da0
        else:
            accel[k + 1] = (((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3)
        vel[k + 1] = z0
        if store:
            states[k + 1, 0] = z0
    return accel, vel, states, STATUS_OK, stats
