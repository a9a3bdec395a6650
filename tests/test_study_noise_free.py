"""The noise-free chains study (``study.noise_free``): its configuration, its folder's
one damping ratio, and chains.csv remade from the committed records."""

import shutil
from pathlib import Path

import pytest

from bayes_inerter.device import paper_parameters
from bayes_inerter.executor import Serial
from bayes_inerter.study.noise_free import Config, device, run

COMMITTED = Path(__file__).resolve().parents[1] / "results" / "noise-free-chains-v3"


@pytest.mark.parametrize("changes, cause", [({"records": 28}, "1 to 27"), ({"zeta_B": 1.5}, "damping ratio"),
                                            ({"max_steps": 10}, "at least 100"),
                                            ({"tempering": 1}, "at least 2 temperatures"),
                                            ({"tempering": 4, "hottest_beta": 0.0}, "hottest beta"),
                                            ({"only": (3, 27)}, "0 to 26"),
                                            ({"tau_floor": 0.0}, "tau_floor"), ({"tau_floor": 1e6}, "tau_floor")])
def test_the_configuration_names_what_it_refuses(changes, cause):
    with pytest.raises(ValueError, match=cause):
        Config(**changes)


def test_the_device_takes_the_damping_ratio_asked():
    p = device("A3", 0.02)
    assert p.c_B / (2 * (p.k_B * p.m_B) ** 0.5) == pytest.approx(0.02)
    assert device("A3", None) == paper_parameters("A3")


def test_summarise_remakes_the_committed_table_and_a_folder_keeps_one_damping(tmp_path):
    shutil.copytree(COMMITTED / "records", tmp_path / "records")
    got = run(Config(zeta_B=0.02, summarise=True), tmp_path, Serial())
    assert (tmp_path / "chains.csv").read_bytes() == (COMMITTED / "chains.csv").read_bytes()
    assert len(got.lines) == 27 and not got.failed
    with pytest.raises(ValueError, match="holds records of zeta_B"):
        run(Config(summarise=True), tmp_path, Serial())
    with pytest.raises(ValueError, match="holds records of ladder"):  # untempered chains, not a tempered run's
        run(Config(zeta_B=0.02, tempering=4, summarise=True), tmp_path, Serial())


def test_summarise_of_an_empty_folder_says_what_to_do(tmp_path):
    with pytest.raises(ValueError, match="run without summarise first"):
        run(Config(summarise=True), tmp_path, Serial())


def _stand_in_fit(monkeypatch, posterior=None, **result):
    """``noise_free.fit_record`` replaced by a stand-in (the plumbing is tested, not a
    fit): it returns b's draws about A0's b, the ``posterior``'s other draws and
    ``result``'s fields; the list returned collects the options each call was given."""
    from types import SimpleNamespace

    import numpy as np

    from bayes_inerter.study import noise_free

    calls = []

    def fake_fit(record, out, **options):
        calls.append(options)
        b = np.random.default_rng(0).normal(paper_parameters("A0").b, 1.0, size=(2, 100))
        return SimpleNamespace(idata=SimpleNamespace(posterior={"b": b, **(posterior or {})}), converged=True,
                               iterations=500, tau=np.array([3.0]), b_interval=SimpleNamespace(identified=True),
                               **result)

    monkeypatch.setattr(noise_free, "fit_record", fake_fit)
    return calls


def test_a_tempered_record_is_fitted_with_the_ladder_asked_and_says_so(tmp_path, monkeypatch):
    from bayes_inerter.study import noise_free

    calls = _stand_in_fit(monkeypatch, tempering={"swap_rates": [0.4]})
    config = Config(tempering=2, hottest_beta=0.01, only=(0,))
    (tmp_path / "records").mkdir()  # as run() makes it
    row = noise_free.fit_one((0, tmp_path, config, "abc"))
    assert calls[0]["tempering"] == config.ladder() and calls[0]["tempering"].beta_min == 0.01
    assert row["tempering"] == 2 and row["hottest_beta"] == 0.01 and row["swap_rates"] == [0.4]
    assert (tmp_path / "records" / "0000.json").exists()
    with pytest.raises(ValueError, match="holds records of ladder"):  # the folder now keeps this ladder
        run(Config(summarise=True), tmp_path, Serial())


def test_a_raised_tau_floor_reaches_the_fit_and_the_folder_keeps_it(tmp_path, monkeypatch):
    import numpy as np

    from bayes_inerter.inference.posterior.priors import MOTION_DISCREPANCY_PRIORS, LogUniform
    from bayes_inerter.study import noise_free

    calls = _stand_in_fit(monkeypatch, posterior={"tau": np.full((2, 100), 0.25)})
    assert Config().priors() == {}
    config = Config(tau_floor=0.1, only=(0,))
    (tmp_path / "records").mkdir()
    row = noise_free.fit_one((0, tmp_path, config, "abc"))
    assert calls[0]["priors"] == {"tau": LogUniform(0.1, MOTION_DISCREPANCY_PRIORS["tau"].high)}
    assert row["tau_floor"] == 0.1 and row["tau_median"] == 0.25
    with pytest.raises(ValueError, match="holds records of tau_floor"):
        run(Config(summarise=True), tmp_path, Serial())


def test_the_stopping_rule_reaches_the_fit_and_the_folder_keeps_it(tmp_path, monkeypatch):
    from bayes_inerter.inference import Convergence
    from bayes_inerter.study import noise_free

    calls = _stand_in_fit(monkeypatch)
    (tmp_path / "records").mkdir()
    row = noise_free.fit_one((0, tmp_path, Config(only=(0,), max_steps=800), "abc"))
    assert calls[0]["convergence"].tau_rtol == row["tau_rtol"] == Convergence().tau_rtol
    assert calls[0]["convergence"].max_steps == 800
    with pytest.raises(ValueError, match="continue it with --tau-rtol"):
        run(Config(only=(0,), tau_rtol=0.05), tmp_path, Serial())
