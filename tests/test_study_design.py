"""Design sensitivity and richer-truth shifts (Laplace approximations)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.executor import Serial
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.study.design import Config, Design, design_contraction, noise_at, richer_truth_shift, run

SHORT = GeneratorSettings(duration=3.0, ramp=1.0)


def test_noise_at_the_truth_is_the_low_passed_sensor_noise():
    """White accelerometer noise of sd s, low-passed to 30 Hz of a 500 Hz band, has sd
    s sqrt(30 / 500) (the residual at the truth is nearly all noise)."""
    gen = GeneratorSettings(duration=3.0, ramp=1.0, force_noise=0.0, accel_noise=0.02)
    rec = generate_record(paper_parameters("A1"), 1.0, settings=gen, rng=5, setting_name="A1")
    pm = PosteriorModel(rec, likelihood=LikelihoodSettings(residual="ar1"))  # the design study's likelihood
    sigma, rho = noise_at(pm, pm.to_theta(paper_parameters("A1"), 1.0, 0.0))
    marginal = sigma / math.sqrt(1 - rho**2)
    assert marginal == pytest.approx(0.02 * math.sqrt(30 / 500), rel=0.2)


def test_a_quieter_sensor_identifies_b_better():
    loud = design_contraction(Design("loud", accel_noise=0.04), "A1", generator=SHORT)
    quiet = design_contraction(Design("quiet", accel_noise=0.004), "A1", generator=SHORT)
    assert quiet["b_rel_sd"] < loud["b_rel_sd"]
    for row in (loud, quiet):
        assert all(row[n] <= 1.0 for n in ("b", "f_0", "k_n", "c_B"))
        assert row["force_peak"] > 0


def test_run_design_writes_tables_figure_and_report(tmp_path):
    config = Config(settings=("A1",), designs=(Design("base"), Design("2 Hz", freq=2.0)), richer=({},),
                    richer_settings=("A1",), generator=SHORT, maxiter=150)
    res = run(config, tmp_path / "design", Serial())
    assert not res.failed and {p.name for p in res.written} == {"design.csv", "richer_truth.csv", "design.png",
                                                                 "REPORT.md"}
    for name in ("design.csv", "richer_truth.csv", "design.png", "REPORT.md"):
        assert (tmp_path / "design" / name).is_file()
    (own,) = res.values["richer"]
    assert own["truth"] == "model's own"
    # the model's own device: the optimum lies within a few Laplace sd of the generating b
    assert abs(own["shift_sd"]) < 4
    assert "richer device" in (tmp_path / "design" / "REPORT.md").read_text()
    assert [r["design"] for r in res.values["design"]] == ["base", "2 Hz"]


@pytest.mark.slow
def test_a_stribeck_device_is_fitted_too():
    """The truth simulator takes minutes on a Stribeck record (small steps at each stick)."""
    row = richer_truth_shift("A1", 1.0, {"friction": "stribeck"}, generator=SHORT, maxiter=150)
    assert row["truth"] == "friction=stribeck" and np.isfinite(row["shift_sd"]) and row["b_sd"] > 0


def test_run_design_reuses_its_cases_and_refuses_other_settings(tmp_path):
    config = Config(settings=("A1",), designs=(Design("base"),), richer=(), generator=SHORT, maxiter=50)
    first = run(config, tmp_path / "d", Serial())
    (case,) = (tmp_path / "d" / "cases").glob("*.json")
    stamp = case.stat().st_mtime_ns
    again = run(config, tmp_path / "d", Serial())
    assert again.values["design"] == first.values["design"] and case.stat().st_mtime_ns == stamp  # read, not redone
    with pytest.raises(ValueError, match="other settings"):
        run(replace(config, seed=1), tmp_path / "d", Serial())


def test_a_failed_case_is_named_and_the_others_are_written(tmp_path, monkeypatch):
    import bayes_inerter.study.design as design

    def broken(what, setting, **kw):
        if what.label == "2 Hz":
            raise RuntimeError("simulator refused")
        return real(what, setting, **kw)

    real = design.design_contraction
    monkeypatch.setattr(design, "design_contraction", broken)
    config = Config(settings=("A1",), designs=(Design("base"), Design("2 Hz", freq=2.0)), richer=(),
                    generator=SHORT, maxiter=50)
    got = run(config, tmp_path / "d", Serial())
    assert [name for name, _ in got.failed] == ["design-A1-2_Hz"] and "refused" in got.failed[0][1]
    assert [r["design"] for r in got.values["design"]] == ["base"]


def test_the_configuration_refuses_an_unknown_setting():
    with pytest.raises(ValueError, match="unknown settings Z9"):
        Config(settings=("A1", "Z9"))
