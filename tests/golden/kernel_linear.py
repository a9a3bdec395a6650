@_jit
def crossed(mode, T):
    # True when some guard is (or may have been) crossed between the two ends of a step:
    # the end's value, then a cheap bound on the Hermite cubic through both ends, and
    # the cubic's exact range only where that bound fails (near the switches)
    pass
    return False


@_jit
def events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events):
    # One sample interval from z the careful way: dyadic steps, each checked by crossed;
    # where a guard is crossed, bisection for the first tick after the crossing, the
    # contacts switched there, and on in the new mode. z, va, da, sgn in and out.
    wcol = 7
    z0 = z[0]
    z1 = z[1]
    z2 = z[2]
    z3 = z[3]
    z4 = z[4]
    z5 = z[5]
    z6 = z[6]
    pass
    pass
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
        y0 = (((((((z0 + F[mode, level, 0, 0] * z0) + F[mode, level, 0, 1] * z1) + F[mode, level, 0, 2] * z2) + F[mode, level, 0, 3] * z3) + F[mode, level, 0, 4] * z4) + F[mode, level, 0, 5] * z5) + F[mode, level, 0, 6] * z6)
        y1 = (((((((z1 + F[mode, level, 1, 0] * z0) + F[mode, level, 1, 1] * z1) + F[mode, level, 1, 2] * z2) + F[mode, level, 1, 3] * z3) + F[mode, level, 1, 4] * z4) + F[mode, level, 1, 5] * z5) + F[mode, level, 1, 6] * z6)
        y2 = (((((((z2 + F[mode, level, 2, 0] * z0) + F[mode, level, 2, 1] * z1) + F[mode, level, 2, 2] * z2) + F[mode, level, 2, 3] * z3) + F[mode, level, 2, 4] * z4) + F[mode, level, 2, 5] * z5) + F[mode, level, 2, 6] * z6)
        y3 = (((((((z3 + F[mode, level, 3, 0] * z0) + F[mode, level, 3, 1] * z1) + F[mode, level, 3, 2] * z2) + F[mode, level, 3, 3] * z3) + F[mode, level, 3, 4] * z4) + F[mode, level, 3, 5] * z5) + F[mode, level, 3, 6] * z6)
        y4 = (((((((z4 + F[mode, level, 4, 0] * z0) + F[mode, level, 4, 1] * z1) + F[mode, level, 4, 2] * z2) + F[mode, level, 4, 3] * z3) + F[mode, level, 4, 4] * z4) + F[mode, level, 4, 5] * z5) + F[mode, level, 4, 6] * z6)
        y5 = z5
        y6 = z6
        y5 = z5 + T * z6
        pass
        if not crossed(mode, T):
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            z4 = y4
            z5 = y5
            z6 = y6
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
        c4 = z4
        c5 = z5
        c6 = z6
        pass
        while size > 1:
            size >>= 1
            level += 1
            T = tick * size
            w0 = (((((((c0 + F[mode, level, 0, 0] * c0) + F[mode, level, 0, 1] * c1) + F[mode, level, 0, 2] * c2) + F[mode, level, 0, 3] * c3) + F[mode, level, 0, 4] * c4) + F[mode, level, 0, 5] * c5) + F[mode, level, 0, 6] * c6)
            w1 = (((((((c1 + F[mode, level, 1, 0] * c0) + F[mode, level, 1, 1] * c1) + F[mode, level, 1, 2] * c2) + F[mode, level, 1, 3] * c3) + F[mode, level, 1, 4] * c4) + F[mode, level, 1, 5] * c5) + F[mode, level, 1, 6] * c6)
            w2 = (((((((c2 + F[mode, level, 2, 0] * c0) + F[mode, level, 2, 1] * c1) + F[mode, level, 2, 2] * c2) + F[mode, level, 2, 3] * c3) + F[mode, level, 2, 4] * c4) + F[mode, level, 2, 5] * c5) + F[mode, level, 2, 6] * c6)
            w3 = (((((((c3 + F[mode, level, 3, 0] * c0) + F[mode, level, 3, 1] * c1) + F[mode, level, 3, 2] * c2) + F[mode, level, 3, 3] * c3) + F[mode, level, 3, 4] * c4) + F[mode, level, 3, 5] * c5) + F[mode, level, 3, 6] * c6)
            w4 = (((((((c4 + F[mode, level, 4, 0] * c0) + F[mode, level, 4, 1] * c1) + F[mode, level, 4, 2] * c2) + F[mode, level, 4, 3] * c3) + F[mode, level, 4, 4] * c4) + F[mode, level, 4, 5] * c5) + F[mode, level, 4, 6] * c6)
            w5 = c5
            w6 = c6
            w5 = c5 + T * c6
            pass
            if crossed(mode, T):
                y0 = w0
                y1 = w1
                y2 = w2
                y3 = w3
                y4 = w4
                y5 = w5
                y6 = w6
            else:
                c0 = w0
                c1 = w1
                c2 = w2
                c3 = w3
                c4 = w4
                c5 = w5
                c6 = w6
                advanced += size
        pos += advanced
        pos += 1
        # the contacts switch at y, and the interval goes on from there
        z0 = y0
        z1 = y1
        z2 = y2
        z3 = y3
        z4 = y4
        z5 = y5
        z6 = y6
        z[0] = z0
        z[1] = z1
        z[2] = z2
        z[3] = z3
        z[4] = z4
        z[5] = z5
        z[6] = z6
        new_mode = switch(z, mode, np.int64(0), node, R, f0, sgn, np.int64(wcol))
        z0 = z[0]
        z1 = z[1]
        z2 = z[2]
        z3 = z[3]
        z4 = z[4]
        z5 = z[5]
        z6 = z[6]
        pass
        if new_mode != mode:
            stats[0] += 1
            mode = new_mode
        # a switch, or none due (a false alarm of the cubic test, or a reversal, which
        # keeps the mode): count all, to bound the work
        count += 1
        if count > max_events:
            return mode, False
        pass
    z[0] = z0
    z[1] = z1
    z[2] = z2
    z[3] = z3
    z[4] = z4
    z[5] = z5
    z[6] = z6
    pass
    return mode, True


@_jit
def kernel(Abar, n_, n_in_, node, f0, mass, inputs, h, z_init, out_node_, store, max_events):
    n = 5
    n_in = 1
    m = 7
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
    z4 = z[4]
    z5 = z[5]
    z6 = z[6]
    accel[0] = ((((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3) + OUT[mode, 5] * z5)
    vel[0] = z0
    if store:
        for i in range(n):
            states[0, i] = z[i]
    va = np.empty(1)
    da = np.empty(1)
    pass
    f0_0 = 0.0
    f0_1 = 0.0
    f0_2 = 0.0
    f0_3 = 0.0
    f0_4 = 0.0
    f0_5 = 0.0
    f0_6 = 0.0
    f1_0 = 0.0
    f1_1 = 0.0
    f1_2 = 0.0
    f1_3 = 0.0
    f1_4 = 0.0
    f1_5 = 0.0
    f1_6 = 0.0
    f2_0 = 0.0
    f2_1 = 0.0
    f2_2 = 0.0
    f2_3 = 0.0
    f2_4 = 0.0
    f2_5 = 0.0
    f2_6 = 0.0
    f3_0 = 0.0
    f3_1 = 0.0
    f3_2 = 0.0
    f3_3 = 0.0
    f3_4 = 0.0
    f3_5 = 0.0
    f3_6 = 0.0
    f4_0 = 0.0
    f4_1 = 0.0
    f4_2 = 0.0
    f4_3 = 0.0
    f4_4 = 0.0
    f4_5 = 0.0
    f4_6 = 0.0
    cur = -1
    acon = -1
    for k in range(K - 1):
        if mode != cur:
            # a new mode: its table's first level and its guards' rows into locals; a
            # sliding contact at the output node gives the output as its guard's rate
            cur = mode
            acon = -1
            pass
            f0_0 = F[mode, 0, 0, 0]
            f0_1 = F[mode, 0, 0, 1]
            f0_2 = F[mode, 0, 0, 2]
            f0_3 = F[mode, 0, 0, 3]
            f0_4 = F[mode, 0, 0, 4]
            f0_5 = F[mode, 0, 0, 5]
            f0_6 = F[mode, 0, 0, 6]
            f1_0 = F[mode, 0, 1, 0]
            f1_1 = F[mode, 0, 1, 1]
            f1_2 = F[mode, 0, 1, 2]
            f1_3 = F[mode, 0, 1, 3]
            f1_4 = F[mode, 0, 1, 4]
            f1_5 = F[mode, 0, 1, 5]
            f1_6 = F[mode, 0, 1, 6]
            f2_0 = F[mode, 0, 2, 0]
            f2_1 = F[mode, 0, 2, 1]
            f2_2 = F[mode, 0, 2, 2]
            f2_3 = F[mode, 0, 2, 3]
            f2_4 = F[mode, 0, 2, 4]
            f2_5 = F[mode, 0, 2, 5]
            f2_6 = F[mode, 0, 2, 6]
            f3_0 = F[mode, 0, 3, 0]
            f3_1 = F[mode, 0, 3, 1]
            f3_2 = F[mode, 0, 3, 2]
            f3_3 = F[mode, 0, 3, 3]
            f3_4 = F[mode, 0, 3, 4]
            f3_5 = F[mode, 0, 3, 5]
            f3_6 = F[mode, 0, 3, 6]
            f4_0 = F[mode, 0, 4, 0]
            f4_1 = F[mode, 0, 4, 1]
            f4_2 = F[mode, 0, 4, 2]
            f4_3 = F[mode, 0, 4, 3]
            f4_4 = F[mode, 0, 4, 4]
            f4_5 = F[mode, 0, 4, 5]
            f4_6 = F[mode, 0, 4, 6]
        z5 = inputs[k, 0]
        z6 = (inputs[k + 1, 0] - inputs[k, 0]) / h
        if k == 0:
            pass
        else:
            # the guards at the start are those at the last interval's end, but for a
            # stuck contact's holding-force rate, which sees the new input slope
            pass
        # the common case: the whole interval in one step, its guards, and the cheap
        # Hermite bound; events takes over only where that bound fails
        y0 = (((((((z0 + f0_0 * z0) + f0_1 * z1) + f0_2 * z2) + f0_3 * z3) + f0_4 * z4) + f0_5 * z5) + f0_6 * z6)
        y1 = (((((((z1 + f1_0 * z0) + f1_1 * z1) + f1_2 * z2) + f1_3 * z3) + f1_4 * z4) + f1_5 * z5) + f1_6 * z6)
        y2 = (((((((z2 + f2_0 * z0) + f2_1 * z1) + f2_2 * z2) + f2_3 * z3) + f2_4 * z4) + f2_5 * z5) + f2_6 * z6)
        y3 = (((((((z3 + f3_0 * z0) + f3_1 * z1) + f3_2 * z2) + f3_3 * z3) + f3_4 * z4) + f3_5 * z5) + f3_6 * z6)
        y4 = (((((((z4 + f4_0 * z0) + f4_1 * z1) + f4_2 * z2) + f4_3 * z3) + f4_4 * z4) + f4_5 * z5) + f4_6 * z6)
        y5 = z5
        y6 = z6
        y5 = z5 + h * z6
        clear = True
        pass
        if clear:
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            z4 = y4
            z5 = y5
            z6 = y6
        else:
            z[0] = z0
            z[1] = z1
            z[2] = z2
            z[3] = z3
            z[4] = z4
            z[5] = z5
            z[6] = z6
            pass
            mode, ok = events(F, mode, J, h, z, va, da, sgn, f0, node, R, VD, RD, stats, max_events)
            if not ok:
                return accel, vel, states, STATUS_TOO_MANY_EVENTS, stats
            z0 = z[0]
            z1 = z[1]
            z2 = z[2]
            z3 = z[3]
            z4 = z[4]
            z5 = z[5]
            z6 = z[6]
            pass
            pass
        accel[k + 1] = ((((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3) + OUT[mode, 5] * z5)
        vel[k + 1] = z0
        if store:
            states[k + 1, 0] = z0
            states[k + 1, 1] = z1
            states[k + 1, 2] = z2
            states[k + 1, 3] = z3
            states[k + 1, 4] = z4
    return accel, vel, states, STATUS_OK, stats
