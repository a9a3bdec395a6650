"""Compile what most of the quick subset needs, once, before its workers start (see
conftest.py's ``pytest_configure``): ``python tests/_warm.py records`` generates a short
record (the generator's servo kernel: 38 s to compile on the development machine);
``python tests/_warm.py networks`` simulates the paper's reduced, rigid and linear
networks from a force (46 s). Each worker would otherwise compile them itself, both at
once; with a warm cache each takes about two seconds."""

import sys

import numpy as np


def records():
    from bayes_inerter import paper_parameters
    from bayes_inerter.records import GeneratorSettings, generate_record

    generate_record(paper_parameters("A2"), 1.0, settings=GeneratorSettings(duration=1.0, ramp=0.5), rng=0)


def networks():
    from conftest import inverse_dynamics_force

    from bayes_inerter import paper_parameters
    from bayes_inerter.simulate import simulate

    p = paper_parameters("A2")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.3, ramp=0.1)
    for name in ("reduced", "rigid", "linear"):
        simulate(p, t, f, network=name)


if __name__ == "__main__":
    {"records": records, "networks": networks}[sys.argv[1]]()
