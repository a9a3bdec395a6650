"""The numeric kernel: exact, event-driven simulation of a piecewise-linear network.

Private. A pure function of flat float arrays (cheap to pickle to workers); the only
place where speed tricks live. See :mod:`bayes_inerter.simulate` for the public entry points.

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

Piecewise-linear laws and dead zones (``_rich``, ``rich_kernel_for``): a contact whose
friction is linear in the speed between knots, sgn(v) (a_s + c_s |v|) in piece s, set-
valued at rest with a static bound f_s, and a link with a gap (no force inside +-g, its
spring and damper on d -+ g outside) keep the network linear between events, with the
piece's force a_s and the link's offset g in w and the piece's slope c_s in the matrix.
The guards become bands: a sliding contact's velocity stays within its piece's speeds
(leaving it: the next piece, or zero: stick or reverse), a stuck one's holding force
within +-f_s, a link's deflection within the gap or beyond it on its side (open, close).
Every element-state combination is a mode, so there are many; each one's tables are
made when it is first entered.

Layout: ``_compiled`` (the helpers every kernel shares: levels, tables, the Hermite
range, the Coulomb contacts' switching rules), ``_rich`` (the same for piecewise-linear
contacts and dead zones), ``templates`` and ``generate`` (the one generator of a
network's specialised kernel: the templates are the algorithm, ``generate`` writes out
their arithmetic), ``cache`` (the generated modules on disk, in a folder of each
environment, with that folder's own copies of ``_compiled`` and ``_rich``, which its
kernels call: see ``cache`` for why). The same algorithm written plainly, without speed
tricks, is ``tests/reference_kernel.py``.
"""

from __future__ import annotations

from . import cache
from ._compiled import STATUS_OK, STATUS_TOO_MANY_EVENTS
from ._rich import Net
from .generate import RichShape, Shape, kernel_source

__all__ = ["kernel_for", "rich_kernel_for", "Net", "RichShape", "STATUS_OK", "STATUS_TOO_MANY_EVENTS"]

_SPECIALISED: dict = {}


def kernel_for(n: int, n_in: int, node, out_node: int, nonzero: bytes | None = None):
    """The kernel specialised to a network: state size ``n``, ``n_in`` inputs, contacts at
    ``node`` (a sequence of node indices), the output node, and optionally the augmented
    matrix's nonzero pattern ``(Abar != 0).tobytes()`` (the kernel is then for matrices
    with zeros at least there). Compiled once per process (and kept between processes
    where a folder can be written, see ``cache``).

    The kernel takes ``(Abar, n, n_in, node, f0, mass, inputs, h, z_init, out_node, store,
    max_events)``: Abar (m, m) the augmented matrix with no contact stuck, m = n + 2 n_in +
    nc; f0 and mass the contacts' Coulomb bounds (N, > 0) and node masses (kg); inputs
    (K, n_in), linearly interpolated; h the sample interval (s); z_init (n,) the initial
    state; store whether to return the state at every sample; max_events the switches
    allowed within one sample interval. It returns (accel (K,), the output node's
    acceleration just after each sample; vel (K,), its velocity; states (K, n), or (0, n)
    unless store; status, STATUS_OK or STATUS_TOO_MANY_EVENTS (accel and vel then NaN from
    that sample on); stats (2,), the numbers of mode switches and of bisections)."""
    shape = Shape(int(n), int(n_in), tuple(int(x) for x in node), int(out_node), nonzero)
    fn = _SPECIALISED.get(shape)
    if fn is None:
        fn = _SPECIALISED[shape] = cache.load(kernel_source(shape))
    return fn


def rich_kernel_for(shape: RichShape):
    """The kernel for a network with piecewise-linear contacts and dead zones (see
    ``_rich``), specialised to ``shape``. It takes ``(net, inputs, z_init, store,
    max_events)``, net a :class:`Net`, and returns what ``kernel_for``'s kernels return."""
    fn = _SPECIALISED.get(shape)
    if fn is None:
        fn = _SPECIALISED[shape] = cache.load(kernel_source(shape), header=cache.RICH_HEADER)
    return fn
