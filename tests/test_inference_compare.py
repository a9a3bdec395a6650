"""Tests of the model comparison (bayes_inerter.inference.compare) and ``fit --model compare``."""

import csv
import json
import math

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.cli import main
from bayes_inerter.inference import LikelihoodSettings
from bayes_inerter.inference.compare import COMPARE_FILE, compare_models, stack_draws
from bayes_inerter.records import GeneratorSettings, generate_record, write_record

#: Three whole steady drive periods after the first at 1.5 Hz (the default likelihood's need).
PERIODIC = GeneratorSettings(duration=4.0, ramp=0.8)


@pytest.fixture(scope="module")
def record():
    return generate_record(paper_parameters("A4"), 1.5, settings=PERIODIC, rng=11, setting_name="A4")


def test_stacked_draws_are_the_weighted_mixture():
    rng = np.random.default_rng(0)
    draws = {"a": rng.normal(0.0, 1.0, (4, 500)), "b": rng.normal(100.0, 1.0, (4, 500))}
    only_a = stack_draws(draws, {"a": 1.0, "b": 0.0}, np.random.default_rng(1))
    assert only_a.size == 4000 and np.all(np.isin(only_a, draws["a"]))
    mixed = stack_draws(draws, {"a": 0.3, "b": 0.7}, np.random.default_rng(1), n=20000)
    # the share from b's draws: 0.7, within 5 binomial sd (0.0032 each)
    assert np.mean(mixed > 50.0) == pytest.approx(0.7, abs=5 * math.sqrt(0.7 * 0.3 / 20000))
    with pytest.raises(ValueError, match="positive weight"):
        stack_draws(draws, {"a": 0.0, "b": 0.0}, np.random.default_rng(1))


def _refusing(monkeypatch, refused):
    """``compare``'s refusal, as a likelihood that does not know the models ``refused``
    would give it (every model of the package is known to every likelihood today)."""
    from bayes_inerter.inference import compare as compare_module

    monkeypatch.setattr(compare_module, "refusal",
                        lambda m, lk: f"the {lk.residual} likelihood does not know the {m} model" if m in refused
                        else None)


def test_a_likelihood_that_knows_none_of_the_models_is_refused(record, tmp_path, monkeypatch):
    _refusing(monkeypatch, ("two-port-stribeck",))
    with pytest.raises(ValueError, match="no model of two-port-stribeck can be fitted under the motion"):
        compare_models(record, tmp_path / "c", models=("two-port-stribeck",))
    with pytest.raises(ValueError, match="unknown model"):
        compare_models(record, tmp_path / "c", models=("two-port", "quadratic"))
    assert not (tmp_path / "c").exists()  # refused before any work


def test_each_model_is_fitted_compared_and_stacked(record, tmp_path, monkeypatch):
    """The nested limits under the default likelihood, a model the likelihood does not
    know left out with the reason: one row a model, weights that sum to one, and the
    stacked median between the models' medians (a mixture's median lies between its
    components')."""
    _refusing(monkeypatch, ("two-port-rich",))
    said = []
    c = compare_models(record, tmp_path / "c", models=("rigid", "linear", "two-port-rich"), steps=20,
                       plots=False, processes=1, on_model=lambda m, why: said.append((m, why)))
    assert [m for m, _ in said] == ["rigid", "linear", "two-port-rich"]
    assert said[2][1] and "motion likelihood" in said[2][1] and not said[0][1]
    fitted = c.fitted
    assert [f.model for f in fitted] == ["rigid", "linear"]
    assert sum(f.weight for f in fitted) == pytest.approx(1.0)
    assert all(0.0 <= f.weight <= 1.0 and f.b_lo < f.b_median < f.b_hi and f.steps == 20 for f in fitted)
    assert min(f.b_median for f in fitted) * 0.999 <= c.b_median <= max(f.b_median for f in fitted) * 1.001
    assert c.b_lo < c.b_median < c.b_hi
    rows = list(csv.DictReader((tmp_path / "c" / COMPARE_FILE).open()))
    assert [r["model"] for r in rows] == ["rigid", "linear", "two-port-rich", "stacked"]
    assert rows[2]["skipped"] and float(rows[3]["b_median"]) == pytest.approx(c.b_median)
    info = json.loads((tmp_path / "c" / "compare.json").read_text())
    assert info["likelihood"] == "motion" and info["models"][2]["b_median"] is None  # NaN written as null
    for m, f in zip(("rigid", "linear"), fitted):
        assert (tmp_path / "c" / m / "fit.json").is_file()
        kept = json.loads((tmp_path / "c" / m / "loo.json").read_text())  # each fit's own LOO, as compared
        assert (f.elpd_loo, f.elpd_se, f.pareto_k_max) == (kept["elpd_loo"], kept["elpd_se"], kept["pareto_k_max"])


@pytest.mark.slow  # a fit of each of two models under the default likelihood
def test_the_richer_models_are_compared_under_the_default_likelihood(record, tmp_path):
    c = compare_models(record, tmp_path / "c", models=("two-port", "two-port-rich"), steps=20, plots=False,
                       processes=1)
    assert [f.model for f in c.fitted] == ["two-port", "two-port-rich"]
    assert sum(f.weight for f in c.fitted) == pytest.approx(1.0)
    rich = json.loads((tmp_path / "c" / "two-port-rich" / "fit.json").read_text())
    assert rich["model"] == "two-port-rich"


@pytest.mark.slow  # a fit of each of three models from the command line
def test_fit_compare_prints_each_model_and_the_stacked_b(record, tmp_path, capsys):
    path, _ = write_record(tmp_path / "a4.csv", record)
    out = tmp_path / "cmp"
    code = main(["fit", str(path), "--out", str(out), "--model", "compare", "--steps", "20",
                 "--processes", "1", "--no-plots", "--residual", "harmonic"])
    assert code == 0
    text = capsys.readouterr().out
    assert "models compared by PSIS-LOO under the harmonic likelihood" in text
    for m in ("two-port", "rigid", "linear", "two-port-stribeck", "two-port-backlash", "two-port-rich"):
        assert f"  {m} " in text or f"{m}: left out" in text
    assert "stacked: b = " in text and (out / COMPARE_FILE).is_file()


def test_fit_compare_says_which_models_it_left_out(record, tmp_path, capsys, monkeypatch):
    """The command line's lines, with the fits themselves replaced (their own tests fit)."""
    from bayes_inerter.inference import compare as compare_module
    from bayes_inerter.inference.compare import Comparison, ModelFit

    def fake(rec, out, *, on_model=None, progress_for=None, likelihood=None, **options):
        on_model("two-port-rich", "the motion-in likelihood knows the two-port network and its limits")
        progress_for("two-port")
        fits = (ModelFit("two-port", 4500.0, 4400.0, 4600.0, -100.0, 5.0, 9.0, 0.9, 1.0, False, 20),
                ModelFit("two-port-rich", skipped="the motion-in likelihood knows the two-port network"))
        assert isinstance(likelihood, LikelihoodSettings)
        return Comparison(fits, 4500.0, 4400.0, 4600.0, out)

    monkeypatch.setattr(compare_module, "compare_models", fake)
    path, _ = write_record(tmp_path / "a4.csv", record)
    assert main(["fit", str(path), "--out", str(tmp_path / "cmp"), "--model", "compare", "--steps", "20"]) == 0
    text = capsys.readouterr().out
    assert "two-port-rich: left out (the motion-in likelihood knows" in text
    assert ("two-port  b = 4500 kg (94 % HDI 4400 to 4600), elpd_loo -100.0 (se 5.0), weight 1.00; Pareto k 0.90 > "
            "0.7: its LOO is unreliable; not converged after 20 steps") in text
    assert "stacked: b = 4500 kg (94 % HDI 4400 to 4600)" in text
    assert "warning: 1 of 1 models' LOO is unreliable or their chain unconverged (two-port)" in text
