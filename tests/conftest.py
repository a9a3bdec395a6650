import os

import numpy as np
import pytest
from hypothesis import settings

from bayes_inerter import arviz_import

#: arviz imported once here, before the test modules that import it: conftest is imported
#: by pytest's main process before it starts the workers, and arviz's first import of
#: the day, in processes started at once, can fail on its stamp file (``arviz_import``; seen on
#: a clean clone with an empty ~/.cache, two workers collecting together).
arviz_import.module()

#: Property tests draw the same examples on every run and machine (hypothesis's examples
#: are otherwise random each run, so a rare failing example would fail CI by chance; a
#: property is still tried on many examples, the same ones everywhere).
settings.register_profile("bayes-inerter", derandomize=True, database=None)
settings.load_profile("bayes-inerter")

#: The sampler's start search in the tests, lighter than the package's default. The tests
#: check what the pipeline does with a start, not how good the start is
#: (tests/test_inference_optimize.py checks that with its own settings, and the tests of
#: the search's stages restore the defaults they test): twenty generations of the
#: evolution where the default (``optimize.DE_MAXITER``) is forty, one Nelder-Mead pass of
#: 200 iterations where the default is up to seven of 800 (``NM_RESTARTS``,
#: ``NM_MAXITER``), and no polish with the discrepancy's sd held (``TAU_CONTINUATION``)
#: nor with the viscous sum held (``HELD_MODES``).
#: Each is read at call time. With the default search a fit's start took about 22 of its
#: 28 s, and the quick subset ran over four minutes on two cores. (Ten generations left a
#: calibration replicate of tests/test_study_calibration.py without a finite start.)
TEST_SEARCH = {"DE_MAXITER": 20, "NM_MAXITER": 200, "NM_RESTARTS": 0, "TAU_CONTINUATION": (), "HELD_MODES": {}}

#: The same settings as Python source, for a command run in a process of its own (a fresh
#: interpreter does not read conftest).
SEARCH_SOURCE = "from bayes_inerter.inference.sampling import optimize; " + "; ".join(
    f"optimize.{name} = {value!r}" for name, value in TEST_SEARCH.items()) + "; "


#: The package's own values of TEST_SEARCH's settings, as imported (set at configuration).
DEFAULT_SEARCH: dict = {}


def pytest_configure(config):
    from bayes_inerter.inference.sampling import optimize

    for name, value in TEST_SEARCH.items():  # each xdist worker runs this in its own process
        DEFAULT_SEARCH.setdefault(name, getattr(optimize, name))
        setattr(optimize, name, value)
    workers = getattr(config.option, "numprocesses", None)
    if isinstance(workers, int) and workers > 1 and not hasattr(config, "workerinput"):
        _compile_before_the_workers()


def _compile_before_the_workers() -> None:
    """Compile the kernels that every worker needs (``_warm.py``), each once, in two
    processes, before pytest-xdist starts its workers: on a fresh clone each worker
    compiled the record generator's and the paper networks' kernels itself, both at
    once. Where this fails the workers compile what they need, and the tests say what
    is wrong."""
    import subprocess
    import sys
    from pathlib import Path

    here = Path(__file__).parent
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(here), os.environ.get("PYTHONPATH")]))}
    jobs = [subprocess.Popen([sys.executable, str(here / "_warm.py"), part], env=env, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL) for part in ("records", "networks")]
    for job in jobs:
        job.wait()


@pytest.fixture
def default_search(monkeypatch):
    """The package's own start search, for a test of its stages."""
    from bayes_inerter.inference.sampling import optimize

    for name, value in DEFAULT_SEARCH.items():
        monkeypatch.setattr(optimize, name, value)


def normal_posterior(duration: float = 1.5, ramp: float = 0.5):
    """A generated A2 record's posterior with its density swapped for a cheap known one:
    independent normals in theta about the generating parameters (``test_start`` holds
    the centre, to start a sampler there)."""
    from scipy import stats

    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
    from bayes_inerter.records import GeneratorSettings, generate_record

    rec = generate_record(paper_parameters("A2"), 1.0, settings=GeneratorSettings(duration=duration, ramp=ramp),
                          rng=2, setting_name="A2")
    # the time-domain likelihood's parameters (sigma, rho; c_B sampled), centred on Table
    # I's values, which the harmonic ones' damping-ratio prior leaves out
    pm = PosteriorModel(rec, likelihood=LikelihoodSettings(residual="ar1"))
    centre = pm.to_theta(paper_parameters("A2"), 3e-3, 0.2)
    lo, hi = pm.bounds().T
    sd = np.minimum(hi - centre, centre - lo) / 6
    pm.log_prob = lambda theta: (float(np.sum(stats.norm.logpdf(theta, centre, sd))), 0.0)
    pm.test_start = (centre, 0.0)
    return pm


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def with_backlash(network, gap):
    """The network with a dead zone of half-width ``gap`` (m) in its last link (the nut),
    as the record generator puts one."""
    import dataclasses

    from bayes_inerter.network import Backlash, Deformation, Network

    blocks = list(network.blocks)
    j = max(i for i, b in enumerate(blocks) if isinstance(b, Deformation))
    blocks[j] = dataclasses.replace(blocks[j], backlash=Backlash(gap))
    return Network(tuple(blocks), network.name + "+backlash")
