"""Compile what most of the quick subset needs, once, before its workers start (see
conftest.py's ``pytest_configure``): ``python tests/_warm.py records`` generates a short
record (the generator's servo kernel: 38 s to compile on the development machine) and
evaluates the default likelihood on it (32 s more);
``python tests/_warm.py networks`` simulates the paper's reduced, rigid and linear
networks from a force (46 s), and the rigid one under Stribeck friction (the kernel for
piecewise-linear laws, about 35 s more). Each worker would otherwise compile them
itself, both at once; with a warm cache each takes about two seconds."""

import sys


def records():
    """A short record, then the default likelihood's log-probability of it (motion in,
    force out: 32 s to compile after the networks', which it shares)."""
    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.records import GeneratorSettings, generate_record

    p = paper_parameters("A2")
    # 4 s at 1.5 Hz: three whole steady drive periods after the start-up, what it needs
    rec = generate_record(p, 1.5, settings=GeneratorSettings(duration=4.0, ramp=0.8), rng=0)
    model = PosteriorModel(rec)
    lo, hi = model.bounds().T
    model.log_prob((lo + hi) / 2)


def networks():
    from bayes_inerter.simulate.reference import inverse_dynamics_force
    from bayes_inerter import paper_parameters
    from bayes_inerter.simulate import simulate

    p = paper_parameters("A2")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.3, ramp=0.1)
    for name in ("reduced", "rigid", "linear"):
        simulate(p, t, f, network=name)
    # the kernel for piecewise-linear laws on the rigid network: its helpers (about 27 s)
    # serve every such kernel, the dead zone's in test_simulate.py too
    simulate(p, t, f, network="rigid", friction="stribeck")


if __name__ == "__main__":
    {"records": records, "networks": networks}[sys.argv[1]]()
