"""The kernel's algorithm as templates of Python source, for ``generate`` to fill.

Each template is a function of the generated kernel as it reads; a line ``$name`` or
``$name(args)`` stands for a block of written-out arithmetic that ``generate`` produces for
the network (a step of the state, the guards at a state, a copy), with the state and the
guards in local variables (``z0, z1, ...``; ``va0, da0``: contact 0's guard and its rate at
the start of a step, ``vb0, db0`` at its end); ``{name}`` is a value (a size, a node, an
argument list). ``events`` is the careful walk through an interval that the common step
leaves to it; ``crossed`` its guard test; ``kernel`` the loop over the samples.

A contact's guard is its velocity while it slides (it must keep its sign) and its holding
force while it sticks (it must stay within +-bound); the state z is the augmented one of
the package docstring, a mode the bit mask of the stuck contacts. For piecewise-linear
laws and dead zones (``_rich``) every guard, a link's deflection too, has a band
[lo, hi] instead (``CROSSED_BAND``, ``CLEAR_BAND``), and a mode numbers every element's
state; the templates above are the same for both.
"""

CROSSED = """\
@_jit
def crossed(mode, T{guard_args}):
    # True when some guard is (or may have been) crossed between the two ends of a step:
    # the end's value, then a cheap bound on the Hermite cubic through both ends, and
    # the cubic's exact range only where that bound fails (near the switches)
    $crossed_guards
    return False
"""

CROSSED_CONTACT = """\
slack = HERMITE_SLACK * T * (abs(da{i}) + abs(db{i}))
if (mode >> {i}) & 1:  # stuck: its holding force stays within +-bound
    if abs(vb{i}) > bound{i}:
        return True
    if not max(abs(va{i}), abs(vb{i})) + slack <= bound{i}:
        lo, hi = cubic_range(va{i}, T * da{i}, vb{i}, T * db{i})
        if hi > bound{i} or lo < -bound{i}:
            return True
else:  # sliding: its velocity keeps its sign
    if sg{i} * vb{i} < 0.0:
        return True
    if not min(sg{i} * va{i}, sg{i} * vb{i}) - slack > 0.0:
        lo, hi = cubic_range(sg{i} * va{i}, T * sg{i} * da{i}, sg{i} * vb{i}, T * sg{i} * db{i})
        if lo < 0.0:
            return True
"""

EVENTS = """\
@_jit
def events({events_params}):
    # One sample interval from z the careful way: dyadic steps, each checked by crossed;
    # where a guard is crossed, bisection for the first tick after the crossing, the
    # contacts switched there, and on in the new mode. z, va, da, sgn in and out.
    wcol = {wcol}
    $load(z)
    $load_switch_state
    $event_locals
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
        $step(z, y, rare, T)
        $guards(y, vb, db, rare)
        if not crossed(mode, T{guard_args}):
            $advance(y, z)
            pos += size
            continue
        stats[1] += 1
        # bisect [0, size] ticks from z for the first crossing: c moves up to the last
        # tick before it, y ends one tick after it
        tick = h / FULL
        advanced = np.int64(0)
        $copy(z, c)
        $guards(c, va, da, rare)
        while size > 1:
            size >>= 1
            level += 1
            T = tick * size
            $step(c, w, rare, T)
            $guards(w, vb, db, rare)
            if crossed(mode, T{guard_args}):
                $copy(w, y)
            else:
                $advance(w, c)
                advanced += size
        pos += advanced
        pos += 1
        # the contacts switch at y, and the interval goes on from there
        $copy(y, z)
        $store(z)
        new_mode = {switch_call}
        $load(z)
        $load_switch_state
        if new_mode != mode:
            stats[0] += 1
            mode = new_mode
        # a switch, or none due (a false alarm of the cubic test, or a reversal, which
        # keeps the mode): count all, to bound the work
        count += 1
        if count > max_events:
            return mode, False
        $guards(z, va, da, rare)
    $store(z)
    $store_guards
    return mode, True
"""

KERNEL = """\
@_jit
def kernel({kernel_params}):
    n = {n}
    n_in = {n_in}
    m = {m}
    K = inputs.shape[0]
    $setup
    accel = np.full(K, np.nan)
    vel = np.full(K, np.nan)
    stats = np.zeros(2, dtype=np.int64)
    states = np.zeros((K if store else 0, n))
    $start
    $load(z)
    accel[0] = {output}
    vel[0] = z{out_node}
    if store:
        for i in range(n):
            states[0, i] = z[i]
    va = np.empty({guards_or_1})
    da = np.empty({guards_or_1})
    $guard_locals
    $table_locals
    cur = -1
    acon = -1
    for k in range(K - 1):
        if mode != cur:
            # a new mode: its table's first level and its guards' rows into locals; a
            # sliding contact at the output node gives the output as its guard's rate
            cur = mode
            acon = -1
            $output_contact
            $mode_locals
        $inputs
        if k == 0:
            $guards(z, va, da, fast)
        else:
            # the guards at the start are those at the last interval's end, but for a
            # stuck contact's holding-force rate, which sees the new input slope
            $stuck_rates
        # the common case: the whole interval in one step, its guards, and the cheap
        # Hermite bound; events takes over only where that bound fails
        $step(z, y, fast, h)
        clear = True
        $clear_test
        if clear:
            $advance(y, z)
        else:
            $store(z)
            $store_guards
            mode, ok = events({events_args})
            if not ok:
                return accel, vel, states, STATUS_TOO_MANY_EVENTS, stats
            $load(z)
            $load_guards
            $load_switch_state
        $output_sample
        vel[k + 1] = z{out_node}
        if store:
            $store_state
    return accel, vel, states, STATUS_OK, stats
"""

CLEAR_TEST = """\
if (mode >> {i}) & 1:
    vb{i} = {r}
    db{i} = {rd}
    slack = HERMITE_SLACK * h * (abs(da{i}) + abs(db{i}))
    if max(abs(va{i}), abs(vb{i})) + slack > bound{i}:
        clear = False
else:
    vb{i} = {v}
    db{i} = {vd}
    slack = HERMITE_SLACK * h * (abs(da{i}) + abs(db{i}))
    if min(sg{i} * va{i}, sg{i} * vb{i}) - slack <= 0.0:
        clear = False
"""

GUARD = """\
if {stuck}:  # stuck: the holding force and its rate
    {val}{i} = {r}
    {der}{i} = {rd}
else:  # sliding: the velocity and the acceleration
    {val}{i} = {v}
    {der}{i} = {vd}
"""

# -- piecewise-linear laws and dead zones (see ``_rich``): every guard has a band --------

CROSSED_BAND = """\
if vb{e} < lo{e} or vb{e} > hi{e}:  # the guard has left its band
    return True
slack = HERMITE_SLACK * T * (abs(da{e}) + abs(db{e}))
if not (min(va{e}, vb{e}) - slack > lo{e} and max(va{e}, vb{e}) + slack < hi{e}):
    least, most = cubic_range(va{e}, T * da{e}, vb{e}, T * db{e})
    if least < lo{e} or most > hi{e}:
        return True
"""

CLEAR_BAND = """\
slack = HERMITE_SLACK * h * (abs(da{e}) + abs(db{e}))
if min(va{e}, vb{e}) - slack <= lo{e} or max(va{e}, vb{e}) + slack >= hi{e}:
    clear = False
"""

GUARD_LINK = """\
{val}{e} = {d}  # a link's deflection and its rate
{der}{e} = {vd}
"""
