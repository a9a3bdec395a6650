@_jit
def crossed(mode, T, va0, da0, vb0, db0, sg0, bound0, va1, da1, vb1, db1, sg1, bound1):
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
    slack = HERMITE_SLACK * T * (abs(da1) + abs(db1))
    if (mode >> 1) & 1:  # stuck: its holding force stays within +-bound
        if abs(vb1) > bound1:
            return True
        if not max(abs(va1), abs(vb1)) + slack <= bound1:
            lo, hi = cubic_range(va1, T * da1, vb1, T * db1)
            if hi > bound1 or lo < -bound1:
                return True
    else:  # sliding: its velocity keeps its sign
        if sg1 * vb1 < 0.0:
            return True
        if not min(sg1 * va1, sg1 * vb1) - slack > 0.0:
            lo, hi = cubic_range(sg1 * va1, T * sg1 * da1, sg1 * vb1, T * sg1 * db1)
            if lo < 0.0:
                return True
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
    z7 = z[7]
    z8 = z[8]
    sg0 = sgn[0]
    sg1 = sgn[1]
    va0 = va[0]
    da0 = da[0]
    vb0 = 0.0
    db0 = 0.0
    bound0 = f0[0]
    va1 = va[1]
    da1 = da[1]
    vb1 = 0.0
    db1 = 0.0
    bound1 = f0[1]
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
        y0 = (((((((((z0 + F[mode, level, 0, 0] * z0) + F[mode, level, 0, 1] * z1) + F[mode, level, 0, 2] * z2) + F[mode, level, 0, 3] * z3) + F[mode, level, 0, 4] * z4) + F[mode, level, 0, 5] * z5) + F[mode, level, 0, 6] * z6) + F[mode, level, 0, 7] * z7) + F[mode, level, 0, 8] * z8)
        y1 = (((((((((z1 + F[mode, level, 1, 0] * z0) + F[mode, level, 1, 1] * z1) + F[mode, level, 1, 2] * z2) + F[mode, level, 1, 3] * z3) + F[mode, level, 1, 4] * z4) + F[mode, level, 1, 5] * z5) + F[mode, level, 1, 6] * z6) + F[mode, level, 1, 7] * z7) + F[mode, level, 1, 8] * z8)
        y2 = (((((((((z2 + F[mode, level, 2, 0] * z0) + F[mode, level, 2, 1] * z1) + F[mode, level, 2, 2] * z2) + F[mode, level, 2, 3] * z3) + F[mode, level, 2, 4] * z4) + F[mode, level, 2, 5] * z5) + F[mode, level, 2, 6] * z6) + F[mode, level, 2, 7] * z7) + F[mode, level, 2, 8] * z8)
        y3 = (((((((((z3 + F[mode, level, 3, 0] * z0) + F[mode, level, 3, 1] * z1) + F[mode, level, 3, 2] * z2) + F[mode, level, 3, 3] * z3) + F[mode, level, 3, 4] * z4) + F[mode, level, 3, 5] * z5) + F[mode, level, 3, 6] * z6) + F[mode, level, 3, 7] * z7) + F[mode, level, 3, 8] * z8)
        y4 = (((((((((z4 + F[mode, level, 4, 0] * z0) + F[mode, level, 4, 1] * z1) + F[mode, level, 4, 2] * z2) + F[mode, level, 4, 3] * z3) + F[mode, level, 4, 4] * z4) + F[mode, level, 4, 5] * z5) + F[mode, level, 4, 6] * z6) + F[mode, level, 4, 7] * z7) + F[mode, level, 4, 8] * z8)
        y5 = z5
        y6 = z6
        y7 = z7
        y8 = z8
        y5 = z5 + T * z6
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            vb0 = ((((0.0 + R[0, 0] * y0) + R[0, 1] * y1) + R[0, 3] * y3) + R[0, 5] * y5)
            db0 = ((((((((0.0 + RD[mode, 0, 0] * y0) + RD[mode, 0, 1] * y1) + RD[mode, 0, 2] * y2) + RD[mode, 0, 3] * y3) + RD[mode, 0, 4] * y4) + RD[mode, 0, 5] * y5) + RD[mode, 0, 6] * y6) + RD[mode, 0, 7] * y7)
        else:  # sliding: the velocity and the acceleration
            vb0 = y0
            db0 = (((((0.0 + VD[mode, 0, 0] * y0) + VD[mode, 0, 1] * y1) + VD[mode, 0, 3] * y3) + VD[mode, 0, 5] * y5) + VD[mode, 0, 7] * y7)
        if (mode >> 1) & 1:  # stuck: the holding force and its rate
            vb1 = (((0.0 + R[1, 1] * y1) + R[1, 2] * y2) + R[1, 4] * y4)
            db1 = ((((((0.0 + RD[mode, 1, 0] * y0) + RD[mode, 1, 1] * y1) + RD[mode, 1, 2] * y2) + RD[mode, 1, 3] * y3) + RD[mode, 1, 4] * y4) + RD[mode, 1, 8] * y8)
        else:  # sliding: the velocity and the acceleration
            vb1 = y2
            db1 = ((((0.0 + VD[mode, 1, 1] * y1) + VD[mode, 1, 2] * y2) + VD[mode, 1, 4] * y4) + VD[mode, 1, 8] * y8)
        if not crossed(mode, T, va0, da0, vb0, db0, sg0, bound0, va1, da1, vb1, db1, sg1, bound1):
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            z4 = y4
            z5 = y5
            z6 = y6
            z7 = y7
            z8 = y8
            va0 = vb0
            da0 = db0
            va1 = vb1
            da1 = db1
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
        c7 = z7
        c8 = z8
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            va0 = ((((0.0 + R[0, 0] * c0) + R[0, 1] * c1) + R[0, 3] * c3) + R[0, 5] * c5)
            da0 = ((((((((0.0 + RD[mode, 0, 0] * c0) + RD[mode, 0, 1] * c1) + RD[mode, 0, 2] * c2) + RD[mode, 0, 3] * c3) + RD[mode, 0, 4] * c4) + RD[mode, 0, 5] * c5) + RD[mode, 0, 6] * c6) + RD[mode, 0, 7] * c7)
        else:  # sliding: the velocity and the acceleration
            va0 = c0
            da0 = (((((0.0 + VD[mode, 0, 0] * c0) + VD[mode, 0, 1] * c1) + VD[mode, 0, 3] * c3) + VD[mode, 0, 5] * c5) + VD[mode, 0, 7] * c7)
        if (mode >> 1) & 1:  # stuck: the holding force and its rate
            va1 = (((0.0 + R[1, 1] * c1) + R[1, 2] * c2) + R[1, 4] * c4)
            da1 = ((((((0.0 + RD[mode, 1, 0] * c0) + RD[mode, 1, 1] * c1) + RD[mode, 1, 2] * c2) + RD[mode, 1, 3] * c3) + RD[mode, 1, 4] * c4) + RD[mode, 1, 8] * c8)
        else:  # sliding: the velocity and the acceleration
            va1 = c2
            da1 = ((((0.0 + VD[mode, 1, 1] * c1) + VD[mode, 1, 2] * c2) + VD[mode, 1, 4] * c4) + VD[mode, 1, 8] * c8)
        while size > 1:
            size >>= 1
            level += 1
            T = tick * size
            w0 = (((((((((c0 + F[mode, level, 0, 0] * c0) + F[mode, level, 0, 1] * c1) + F[mode, level, 0, 2] * c2) + F[mode, level, 0, 3] * c3) + F[mode, level, 0, 4] * c4) + F[mode, level, 0, 5] * c5) + F[mode, level, 0, 6] * c6) + F[mode, level, 0, 7] * c7) + F[mode, level, 0, 8] * c8)
            w1 = (((((((((c1 + F[mode, level, 1, 0] * c0) + F[mode, level, 1, 1] * c1) + F[mode, level, 1, 2] * c2) + F[mode, level, 1, 3] * c3) + F[mode, level, 1, 4] * c4) + F[mode, level, 1, 5] * c5) + F[mode, level, 1, 6] * c6) + F[mode, level, 1, 7] * c7) + F[mode, level, 1, 8] * c8)
            w2 = (((((((((c2 + F[mode, level, 2, 0] * c0) + F[mode, level, 2, 1] * c1) + F[mode, level, 2, 2] * c2) + F[mode, level, 2, 3] * c3) + F[mode, level, 2, 4] * c4) + F[mode, level, 2, 5] * c5) + F[mode, level, 2, 6] * c6) + F[mode, level, 2, 7] * c7) + F[mode, level, 2, 8] * c8)
            w3 = (((((((((c3 + F[mode, level, 3, 0] * c0) + F[mode, level, 3, 1] * c1) + F[mode, level, 3, 2] * c2) + F[mode, level, 3, 3] * c3) + F[mode, level, 3, 4] * c4) + F[mode, level, 3, 5] * c5) + F[mode, level, 3, 6] * c6) + F[mode, level, 3, 7] * c7) + F[mode, level, 3, 8] * c8)
            w4 = (((((((((c4 + F[mode, level, 4, 0] * c0) + F[mode, level, 4, 1] * c1) + F[mode, level, 4, 2] * c2) + F[mode, level, 4, 3] * c3) + F[mode, level, 4, 4] * c4) + F[mode, level, 4, 5] * c5) + F[mode, level, 4, 6] * c6) + F[mode, level, 4, 7] * c7) + F[mode, level, 4, 8] * c8)
            w5 = c5
            w6 = c6
            w7 = c7
            w8 = c8
            w5 = c5 + T * c6
            if (mode >> 0) & 1:  # stuck: the holding force and its rate
                vb0 = ((((0.0 + R[0, 0] * w0) + R[0, 1] * w1) + R[0, 3] * w3) + R[0, 5] * w5)
                db0 = ((((((((0.0 + RD[mode, 0, 0] * w0) + RD[mode, 0, 1] * w1) + RD[mode, 0, 2] * w2) + RD[mode, 0, 3] * w3) + RD[mode, 0, 4] * w4) + RD[mode, 0, 5] * w5) + RD[mode, 0, 6] * w6) + RD[mode, 0, 7] * w7)
            else:  # sliding: the velocity and the acceleration
                vb0 = w0
                db0 = (((((0.0 + VD[mode, 0, 0] * w0) + VD[mode, 0, 1] * w1) + VD[mode, 0, 3] * w3) + VD[mode, 0, 5] * w5) + VD[mode, 0, 7] * w7)
            if (mode >> 1) & 1:  # stuck: the holding force and its rate
                vb1 = (((0.0 + R[1, 1] * w1) + R[1, 2] * w2) + R[1, 4] * w4)
                db1 = ((((((0.0 + RD[mode, 1, 0] * w0) + RD[mode, 1, 1] * w1) + RD[mode, 1, 2] * w2) + RD[mode, 1, 3] * w3) + RD[mode, 1, 4] * w4) + RD[mode, 1, 8] * w8)
            else:  # sliding: the velocity and the acceleration
                vb1 = w2
                db1 = ((((0.0 + VD[mode, 1, 1] * w1) + VD[mode, 1, 2] * w2) + VD[mode, 1, 4] * w4) + VD[mode, 1, 8] * w8)
            if crossed(mode, T, va0, da0, vb0, db0, sg0, bound0, va1, da1, vb1, db1, sg1, bound1):
                y0 = w0
                y1 = w1
                y2 = w2
                y3 = w3
                y4 = w4
                y5 = w5
                y6 = w6
                y7 = w7
                y8 = w8
            else:
                c0 = w0
                c1 = w1
                c2 = w2
                c3 = w3
                c4 = w4
                c5 = w5
                c6 = w6
                c7 = w7
                c8 = w8
                va0 = vb0
                da0 = db0
                va1 = vb1
                da1 = db1
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
        z7 = y7
        z8 = y8
        z[0] = z0
        z[1] = z1
        z[2] = z2
        z[3] = z3
        z[4] = z4
        z[5] = z5
        z[6] = z6
        z[7] = z7
        z[8] = z8
        new_mode = switch(z, mode, np.int64(2), node, R, f0, sgn, np.int64(wcol))
        z0 = z[0]
        z1 = z[1]
        z2 = z[2]
        z3 = z[3]
        z4 = z[4]
        z5 = z[5]
        z6 = z[6]
        z7 = z[7]
        z8 = z[8]
        sg0 = sgn[0]
        sg1 = sgn[1]
        if new_mode != mode:
            stats[0] += 1
            mode = new_mode
        # a switch, or none due (a false alarm of the cubic test, or a reversal, which
        # keeps the mode): count all, to bound the work
        count += 1
        if count > max_events:
            return mode, False
        if (mode >> 0) & 1:  # stuck: the holding force and its rate
            va0 = ((((0.0 + R[0, 0] * z0) + R[0, 1] * z1) + R[0, 3] * z3) + R[0, 5] * z5)
            da0 = ((((((((0.0 + RD[mode, 0, 0] * z0) + RD[mode, 0, 1] * z1) + RD[mode, 0, 2] * z2) + RD[mode, 0, 3] * z3) + RD[mode, 0, 4] * z4) + RD[mode, 0, 5] * z5) + RD[mode, 0, 6] * z6) + RD[mode, 0, 7] * z7)
        else:  # sliding: the velocity and the acceleration
            va0 = z0
            da0 = (((((0.0 + VD[mode, 0, 0] * z0) + VD[mode, 0, 1] * z1) + VD[mode, 0, 3] * z3) + VD[mode, 0, 5] * z5) + VD[mode, 0, 7] * z7)
        if (mode >> 1) & 1:  # stuck: the holding force and its rate
            va1 = (((0.0 + R[1, 1] * z1) + R[1, 2] * z2) + R[1, 4] * z4)
            da1 = ((((((0.0 + RD[mode, 1, 0] * z0) + RD[mode, 1, 1] * z1) + RD[mode, 1, 2] * z2) + RD[mode, 1, 3] * z3) + RD[mode, 1, 4] * z4) + RD[mode, 1, 8] * z8)
        else:  # sliding: the velocity and the acceleration
            va1 = z2
            da1 = ((((0.0 + VD[mode, 1, 1] * z1) + VD[mode, 1, 2] * z2) + VD[mode, 1, 4] * z4) + VD[mode, 1, 8] * z8)
    z[0] = z0
    z[1] = z1
    z[2] = z2
    z[3] = z3
    z[4] = z4
    z[5] = z5
    z[6] = z6
    z[7] = z7
    z[8] = z8
    va[0] = va0
    da[0] = da0
    va[1] = va1
    da[1] = da1
    return mode, True


@_jit
def kernel(Abar, n_, n_in_, node, f0, mass, inputs, h, z_init, out_node_, store, max_events):
    n = 5
    n_in = 1
    m = 9
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
    z7 = z[7]
    z8 = z[8]
    accel[0] = (((((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3) + OUT[mode, 5] * z5) + OUT[mode, 7] * z7)
    vel[0] = z0
    if store:
        for i in range(n):
            states[0, i] = z[i]
    va = np.empty(2)
    da = np.empty(2)
    bound0 = f0[0]
    sg0 = sgn[0]
    va0 = 0.0
    da0 = 0.0
    r0_0 = R[0, 0]
    r0_1 = R[0, 1]
    r0_3 = R[0, 3]
    r0_5 = R[0, 5]
    vd0_0 = 0.0
    vd0_1 = 0.0
    vd0_3 = 0.0
    vd0_5 = 0.0
    vd0_7 = 0.0
    rd0_0 = 0.0
    rd0_1 = 0.0
    rd0_2 = 0.0
    rd0_3 = 0.0
    rd0_4 = 0.0
    rd0_5 = 0.0
    rd0_6 = 0.0
    rd0_7 = 0.0
    bound1 = f0[1]
    sg1 = sgn[1]
    va1 = 0.0
    da1 = 0.0
    r1_1 = R[1, 1]
    r1_2 = R[1, 2]
    r1_4 = R[1, 4]
    vd1_1 = 0.0
    vd1_2 = 0.0
    vd1_4 = 0.0
    vd1_8 = 0.0
    rd1_0 = 0.0
    rd1_1 = 0.0
    rd1_2 = 0.0
    rd1_3 = 0.0
    rd1_4 = 0.0
    rd1_8 = 0.0
    f0_0 = 0.0
    f0_1 = 0.0
    f0_2 = 0.0
    f0_3 = 0.0
    f0_4 = 0.0
    f0_5 = 0.0
    f0_6 = 0.0
    f0_7 = 0.0
    f0_8 = 0.0
    f1_0 = 0.0
    f1_1 = 0.0
    f1_2 = 0.0
    f1_3 = 0.0
    f1_4 = 0.0
    f1_5 = 0.0
    f1_6 = 0.0
    f1_7 = 0.0
    f1_8 = 0.0
    f2_0 = 0.0
    f2_1 = 0.0
    f2_2 = 0.0
    f2_3 = 0.0
    f2_4 = 0.0
    f2_5 = 0.0
    f2_6 = 0.0
    f2_7 = 0.0
    f2_8 = 0.0
    f3_0 = 0.0
    f3_1 = 0.0
    f3_2 = 0.0
    f3_3 = 0.0
    f3_4 = 0.0
    f3_5 = 0.0
    f3_6 = 0.0
    f3_7 = 0.0
    f3_8 = 0.0
    f4_0 = 0.0
    f4_1 = 0.0
    f4_2 = 0.0
    f4_3 = 0.0
    f4_4 = 0.0
    f4_5 = 0.0
    f4_6 = 0.0
    f4_7 = 0.0
    f4_8 = 0.0
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
            f0_4 = F[mode, 0, 0, 4]
            f0_5 = F[mode, 0, 0, 5]
            f0_6 = F[mode, 0, 0, 6]
            f0_7 = F[mode, 0, 0, 7]
            f0_8 = F[mode, 0, 0, 8]
            f1_0 = F[mode, 0, 1, 0]
            f1_1 = F[mode, 0, 1, 1]
            f1_2 = F[mode, 0, 1, 2]
            f1_3 = F[mode, 0, 1, 3]
            f1_4 = F[mode, 0, 1, 4]
            f1_5 = F[mode, 0, 1, 5]
            f1_6 = F[mode, 0, 1, 6]
            f1_7 = F[mode, 0, 1, 7]
            f1_8 = F[mode, 0, 1, 8]
            f2_0 = F[mode, 0, 2, 0]
            f2_1 = F[mode, 0, 2, 1]
            f2_2 = F[mode, 0, 2, 2]
            f2_3 = F[mode, 0, 2, 3]
            f2_4 = F[mode, 0, 2, 4]
            f2_5 = F[mode, 0, 2, 5]
            f2_6 = F[mode, 0, 2, 6]
            f2_7 = F[mode, 0, 2, 7]
            f2_8 = F[mode, 0, 2, 8]
            f3_0 = F[mode, 0, 3, 0]
            f3_1 = F[mode, 0, 3, 1]
            f3_2 = F[mode, 0, 3, 2]
            f3_3 = F[mode, 0, 3, 3]
            f3_4 = F[mode, 0, 3, 4]
            f3_5 = F[mode, 0, 3, 5]
            f3_6 = F[mode, 0, 3, 6]
            f3_7 = F[mode, 0, 3, 7]
            f3_8 = F[mode, 0, 3, 8]
            f4_0 = F[mode, 0, 4, 0]
            f4_1 = F[mode, 0, 4, 1]
            f4_2 = F[mode, 0, 4, 2]
            f4_3 = F[mode, 0, 4, 3]
            f4_4 = F[mode, 0, 4, 4]
            f4_5 = F[mode, 0, 4, 5]
            f4_6 = F[mode, 0, 4, 6]
            f4_7 = F[mode, 0, 4, 7]
            f4_8 = F[mode, 0, 4, 8]
            vd0_0 = VD[mode, 0, 0]
            vd0_1 = VD[mode, 0, 1]
            vd0_3 = VD[mode, 0, 3]
            vd0_5 = VD[mode, 0, 5]
            vd0_7 = VD[mode, 0, 7]
            rd0_0 = RD[mode, 0, 0]
            rd0_1 = RD[mode, 0, 1]
            rd0_2 = RD[mode, 0, 2]
            rd0_3 = RD[mode, 0, 3]
            rd0_4 = RD[mode, 0, 4]
            rd0_5 = RD[mode, 0, 5]
            rd0_6 = RD[mode, 0, 6]
            rd0_7 = RD[mode, 0, 7]
            vd1_1 = VD[mode, 1, 1]
            vd1_2 = VD[mode, 1, 2]
            vd1_4 = VD[mode, 1, 4]
            vd1_8 = VD[mode, 1, 8]
            rd1_0 = RD[mode, 1, 0]
            rd1_1 = RD[mode, 1, 1]
            rd1_2 = RD[mode, 1, 2]
            rd1_3 = RD[mode, 1, 3]
            rd1_4 = RD[mode, 1, 4]
            rd1_8 = RD[mode, 1, 8]
        z5 = inputs[k, 0]
        z6 = (inputs[k + 1, 0] - inputs[k, 0]) / h
        if k == 0:
            if (mode >> 0) & 1:  # stuck: the holding force and its rate
                va0 = ((((0.0 + r0_0 * z0) + r0_1 * z1) + r0_3 * z3) + r0_5 * z5)
                da0 = ((((((((0.0 + rd0_0 * z0) + rd0_1 * z1) + rd0_2 * z2) + rd0_3 * z3) + rd0_4 * z4) + rd0_5 * z5) + rd0_6 * z6) + rd0_7 * z7)
            else:  # sliding: the velocity and the acceleration
                va0 = z0
                da0 = (((((0.0 + vd0_0 * z0) + vd0_1 * z1) + vd0_3 * z3) + vd0_5 * z5) + vd0_7 * z7)
            if (mode >> 1) & 1:  # stuck: the holding force and its rate
                va1 = (((0.0 + r1_1 * z1) + r1_2 * z2) + r1_4 * z4)
                da1 = ((((((0.0 + rd1_0 * z0) + rd1_1 * z1) + rd1_2 * z2) + rd1_3 * z3) + rd1_4 * z4) + rd1_8 * z8)
            else:  # sliding: the velocity and the acceleration
                va1 = z2
                da1 = ((((0.0 + vd1_1 * z1) + vd1_2 * z2) + vd1_4 * z4) + vd1_8 * z8)
        else:
            # the guards at the start are those at the last interval's end, but for a
            # stuck contact's holding-force rate, which sees the new input slope
            if (mode >> 0) & 1:
                da0 = ((((((((0.0 + rd0_0 * z0) + rd0_1 * z1) + rd0_2 * z2) + rd0_3 * z3) + rd0_4 * z4) + rd0_5 * z5) + rd0_6 * z6) + rd0_7 * z7)
            if (mode >> 1) & 1:
                da1 = ((((((0.0 + rd1_0 * z0) + rd1_1 * z1) + rd1_2 * z2) + rd1_3 * z3) + rd1_4 * z4) + rd1_8 * z8)
        # the common case: the whole interval in one step, its guards, and the cheap
        # Hermite bound; events takes over only where that bound fails
        y0 = (((((((((z0 + f0_0 * z0) + f0_1 * z1) + f0_2 * z2) + f0_3 * z3) + f0_4 * z4) + f0_5 * z5) + f0_6 * z6) + f0_7 * z7) + f0_8 * z8)
        y1 = (((((((((z1 + f1_0 * z0) + f1_1 * z1) + f1_2 * z2) + f1_3 * z3) + f1_4 * z4) + f1_5 * z5) + f1_6 * z6) + f1_7 * z7) + f1_8 * z8)
        y2 = (((((((((z2 + f2_0 * z0) + f2_1 * z1) + f2_2 * z2) + f2_3 * z3) + f2_4 * z4) + f2_5 * z5) + f2_6 * z6) + f2_7 * z7) + f2_8 * z8)
        y3 = (((((((((z3 + f3_0 * z0) + f3_1 * z1) + f3_2 * z2) + f3_3 * z3) + f3_4 * z4) + f3_5 * z5) + f3_6 * z6) + f3_7 * z7) + f3_8 * z8)
        y4 = (((((((((z4 + f4_0 * z0) + f4_1 * z1) + f4_2 * z2) + f4_3 * z3) + f4_4 * z4) + f4_5 * z5) + f4_6 * z6) + f4_7 * z7) + f4_8 * z8)
        y5 = z5
        y6 = z6
        y7 = z7
        y8 = z8
        y5 = z5 + h * z6
        clear = True
        if (mode >> 0) & 1:
            vb0 = ((((0.0 + r0_0 * y0) + r0_1 * y1) + r0_3 * y3) + r0_5 * y5)
            db0 = ((((((((0.0 + rd0_0 * y0) + rd0_1 * y1) + rd0_2 * y2) + rd0_3 * y3) + rd0_4 * y4) + rd0_5 * y5) + rd0_6 * y6) + rd0_7 * y7)
            slack = HERMITE_SLACK * h * (abs(da0) + abs(db0))
            if max(abs(va0), abs(vb0)) + slack > bound0:
                clear = False
        else:
            vb0 = y0
            db0 = (((((0.0 + vd0_0 * y0) + vd0_1 * y1) + vd0_3 * y3) + vd0_5 * y5) + vd0_7 * y7)
            slack = HERMITE_SLACK * h * (abs(da0) + abs(db0))
            if min(sg0 * va0, sg0 * vb0) - slack <= 0.0:
                clear = False
        if (mode >> 1) & 1:
            vb1 = (((0.0 + r1_1 * y1) + r1_2 * y2) + r1_4 * y4)
            db1 = ((((((0.0 + rd1_0 * y0) + rd1_1 * y1) + rd1_2 * y2) + rd1_3 * y3) + rd1_4 * y4) + rd1_8 * y8)
            slack = HERMITE_SLACK * h * (abs(da1) + abs(db1))
            if max(abs(va1), abs(vb1)) + slack > bound1:
                clear = False
        else:
            vb1 = y2
            db1 = ((((0.0 + vd1_1 * y1) + vd1_2 * y2) + vd1_4 * y4) + vd1_8 * y8)
            slack = HERMITE_SLACK * h * (abs(da1) + abs(db1))
            if min(sg1 * va1, sg1 * vb1) - slack <= 0.0:
                clear = False
        if clear:
            z0 = y0
            z1 = y1
            z2 = y2
            z3 = y3
            z4 = y4
            z5 = y5
            z6 = y6
            z7 = y7
            z8 = y8
            va0 = vb0
            da0 = db0
            va1 = vb1
            da1 = db1
        else:
            z[0] = z0
            z[1] = z1
            z[2] = z2
            z[3] = z3
            z[4] = z4
            z[5] = z5
            z[6] = z6
            z[7] = z7
            z[8] = z8
            va[0] = va0
            da[0] = da0
            va[1] = va1
            da[1] = da1
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
            z7 = z[7]
            z8 = z[8]
            va0 = va[0]
            da0 = da[0]
            va1 = va[1]
            da1 = da[1]
            sg0 = sgn[0]
            sg1 = sgn[1]
        if acon == 0 and mode == cur:
            accel[k + 1] = da0
        else:
            accel[k + 1] = (((((0.0 + OUT[mode, 0] * z0) + OUT[mode, 1] * z1) + OUT[mode, 3] * z3) + OUT[mode, 5] * z5) + OUT[mode, 7] * z7)
        vel[k + 1] = z0
        if store:
            states[k + 1, 0] = z0
            states[k + 1, 1] = z1
            states[k + 1, 2] = z2
            states[k + 1, 3] = z3
            states[k + 1, 4] = z4
    return accel, vel, states, STATUS_OK, stats
