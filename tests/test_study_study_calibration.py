"""Simulation-based calibration in the study's configuration: the interval, the counts
(failed replicates are misses), the reports, and one real replicate (slow)."""

import dataclasses
import json

import numpy as np
import pytest

from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.study.study_calibration import (IDENTIFIED, LEVELS, STUDY_SBC_PRIORS, StudyCalibration, chains_long_enough,
                                                  coverage_by_frequency, coverage_rows, coverage_so_far, finished_replicates,
                                                  inspect_replicate, raise_cap, rank_correlations, replicate_device,
                                                  study_replicate, write_coverage_so_far, write_study_calibration)

NAMES = ["b", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "c_B", "k_B"]
#: The time-domain likelihood of the replicates below: c_B sampled, rho per frequency
#: (the 3 s records also hold too few drive periods for the default, motion in, force out).
AR1 = LikelihoodSettings(residual="ar1")


def test_the_prior_draws_the_paper_settings_inertances():
    lo, hi = np.exp(STUDY_SBC_PRIORS["b"].bounds)
    assert lo < 753.34 and 20287.0 < hi  # A0 and B2 of Table 2
    assert list(STUDY_SBC_PRIORS) == NAMES


def test_settings_are_checked():
    with pytest.raises(ValueError, match="two drive frequencies"):
        StudyCalibration(frequencies=(1.0,))
    with pytest.raises(ValueError, match="steps"):
        StudyCalibration(steps=5)
    assert StudyCalibration(frequencies=[0.5, 1]).frequencies == (0.5, 1.0)
    with pytest.raises(ValueError, match="interval_draws"):
        StudyCalibration(interval_draws="all")


@pytest.mark.parametrize("option", ["replica_rule", "adapt_hot"])
def test_a_ladder_option_without_a_ladder_is_refused(option):
    from bayes_inerter.study.study_calibration import Config

    with pytest.raises(ValueError, match="act on a tempering ladder: give --tempering TEMPS too"):
        Config(**{option: True})
    got = Config(tempering=4, **{option: True}).settings()
    assert got.replica_rule == (option == "replica_rule") and got.tempering.adapt_hot == (option == "adapt_hot")


def _fake(k, held: bool, rank=5, tau=10.0):
    inside = {n: held for n in NAMES}
    return {"replicate": k, "redraws": 0, "iterations": 600, "tau_max": tau, "L": 9, "kept": 100,
            "truth": {n: 1.0 for n in NAMES}, "ranks": {n: rank for n in NAMES},
            "hdi": {str(round(100 * q)): inside for q in LEVELS}, "central": {str(round(100 * q)): inside for q in LEVELS}}


def test_a_failed_replicate_counts_as_a_miss():
    results = [_fake(0, True), _fake(1, True), _fake(2, False), {"replicate": 3, "error": "RuntimeError: no"}]
    rows = coverage_rows(results)
    assert [r["parameter"] for r in rows] == NAMES
    b = rows[0]
    assert b["replicates"] == 4 and b["failed"] == 1
    assert b["hdi_94"] == b["central_50"] == 0.5  # two of four: the failed one is not dropped
    assert b["se_94"] == pytest.approx(np.sqrt(0.94 * 0.06 / 4))


def test_coverage_so_far_counts_every_chain_and_the_converged_apart(tmp_path):
    results = [_fake(0, True), _fake(1, False), _fake(2, True), {"replicate": 3, "error": "RuntimeError: no"}]
    results[0]["converged"], results[1]["converged"], results[2]["converged"] = True, True, False
    rows = {(r["chains"], r["parameter"]): r for r in coverage_so_far(results)}
    b = rows["all", "b"]
    assert (b["replicates"], b["held_94"], b["held_50"]) == (4, 2, 2)  # the failed one a miss
    assert b["expected_94"] == pytest.approx(0.94 * 4, abs=0.05)
    pooled = rows["all", "all parameters"]
    assert pooled["intervals"] == 4 * len(NAMES) and pooled["held_94"] == 2 * len(NAMES)
    conv = rows["converged", "b"]
    assert (conv["replicates"], conv["held_94"]) == (2, 1)
    (tmp_path / "replicates").mkdir()
    for r in reversed(results):  # written in any order, read in the replicates' order
        (tmp_path / "replicates" / f"{r['replicate']:04d}.json").write_text(json.dumps(r))
    assert [r["replicate"] for r in finished_replicates(tmp_path)] == [0, 1, 2, 3]
    assert write_coverage_so_far(tmp_path) == coverage_so_far(results)
    assert (tmp_path / "coverage_so_far.csv").read_text().count("\n") == 1 + len(rows)
    assert not (tmp_path / "coverage_by_frequency.csv").exists()  # not a single-record calibration's folder


def test_the_identified_combination_is_counted_over_the_replicates_that_rank_it():
    """b / gain is what a record identifies where the gain is sampled; replicates written
    before it was ranked carry none, and the pooled row leaves it out."""
    results = [_fake(k, True) for k in range(4)]
    for k, r in enumerate(results[1:], start=1):
        r["converged"] = True
        r["identified"] = {IDENTIFIED: {"truth": 1.0, "rank": 4, "hdi": {"94": True, "50": k == 1},
                                        "central": {"94": True, "50": k == 1}}}
    rows = {(r["chains"], r["parameter"]): r for r in coverage_so_far(results)}
    got = rows["all", f"{IDENTIFIED} (identified)"]
    assert (got["replicates"], got["held_94"], got["held_50"]) == (3, 3, 1)
    assert got["expected_50"] == 1.5
    assert rows["all", "all parameters"]["intervals"] == 4 * len(NAMES)
    assert rows["converged", f"{IDENTIFIED} (identified)"]["replicates"] == 3


def test_coverage_by_frequency_splits_the_replicates_as_they_were_fitted(tmp_path):
    """Replicate k of a single-record calibration is fitted at frequencies[k % 3]."""
    results = [_fake(k, k % 3 != 1) for k in range(6)]  # the 1 Hz ones miss
    for r in results:
        r["converged"] = True
    rows = {(r["freq_hz"], r["chains"], r["parameter"]): r for r in coverage_by_frequency(results, (0.5, 1, 1.5))}
    assert [rows[f, "all", "b"]["held_94"] for f in (0.5, 1.0, 1.5)] == [2, 0, 2]
    assert rows[1.0, "all", "b"]["replicates"] == 2
    (tmp_path / "replicates").mkdir()
    for r in results:
        (tmp_path / "replicates" / f"{r['replicate']:04d}.json").write_text(json.dumps(r))
    (tmp_path / "settings.json").write_text(json.dumps({"single": True, "frequencies": [0.5, 1.0, 1.5]}))
    write_coverage_so_far(tmp_path)
    assert (tmp_path / "coverage_by_frequency.csv").read_text().count("\n") == 1 + len(rows)


def test_rank_correlations_finds_parameters_whose_ranks_move_together(tmp_path):
    rng = np.random.default_rng(1)
    gain = rng.integers(0, 10, 40)
    results = []
    for k, g in enumerate(gain):
        r = _fake(k, True)
        r["ranks"] = {n: int(rng.integers(0, 10)) for n in NAMES}
        r["ranks"]["b"] = int(g)  # b's rank follows another's, as b follows the gain's
        r["ranks"]["k_B"] = int(g)
        r["ranks"]["c_f"] = 9 - r["ranks"]["f_0"]  # and one trades against another
        results.append(r)
    pairs = rank_correlations(results)
    found = {(p["parameter"], p["with"]): p["r"] for p in pairs}
    assert found[("b", "k_B")] == 1.0 and found[("f_0", "c_f")] == -1.0
    assert all(abs(r) >= 0.5 for r in found.values()) and len(found) < 6  # independent ranks stay out
    assert rank_correlations(results[:2]) == [] and rank_correlations(results, threshold=1.01) == []
    (tmp_path / "replicates").mkdir()
    for r in results:
        (tmp_path / "replicates" / f"{r['replicate']:04d}.json").write_text(json.dumps(r))
    write_coverage_so_far(tmp_path)
    lines = (tmp_path / "rank_correlations.csv").read_text().splitlines()
    assert lines[0] == "parameter,with,r,replicates" and len(lines) == 1 + len(pairs)


def test_raising_the_cap_moves_only_the_capped_chains_aside(tmp_path):
    settings = {"steps": None, "max_steps": 600, "seed": 3}
    (tmp_path / "settings.json").write_text(json.dumps(settings))
    (tmp_path / "replicates").mkdir()
    results = [_fake(0, True), _fake(1, True), _fake(2, True), {"replicate": 3, "error": "RuntimeError: no"}]
    results[0]["converged"], results[1]["converged"], results[2]["converged"] = True, False, False
    results[2]["iterations"] = 250  # stopped early, not at the cap (an old fixed-length chain): left alone
    for r in results:
        (tmp_path / "replicates" / f"{r['replicate']:04d}.json").write_text(json.dumps(r))
    assert raise_cap(tmp_path, 1200) == [1]
    assert [r["replicate"] for r in finished_replicates(tmp_path)] == [0, 2, 3]
    assert json.loads((tmp_path / "capped-600" / "0001.json").read_text()) == results[1]
    assert json.loads((tmp_path / "settings.json").read_text()) == {**settings, "max_steps": 1200}
    with pytest.raises(ValueError, match="above the folder's 1200"):
        raise_cap(tmp_path, 1200)
    (tmp_path / "settings.json").write_text(json.dumps({**settings, "steps": 600}))
    with pytest.raises(ValueError, match="no cap to raise"):
        raise_cap(tmp_path, 2400)
    with pytest.raises(ValueError, match="no settings.json"):
        raise_cap(tmp_path / "elsewhere", 2400)


def test_chains_long_enough_counts_fifty_taus():
    results = [_fake(0, True, tau=10.0), _fake(1, True, tau=13.0), {"replicate": 2, "error": "x"}]
    assert chains_long_enough(results) == 1  # 600 >= 50 * 10, 600 < 50 * 13


def test_reports_say_what_failed_and_what_missed(tmp_path):
    results = [_fake(k, k % 5 != 0, rank=k % 10) for k in range(20)] + [{"replicate": 20, "error": "RuntimeError: boom"}]
    got = write_study_calibration(tmp_path, StudyCalibration(), results, {"numpy": np.__version__})
    for name in ("coverage.csv", "ranks.csv", "coverage.png", "ranks.png", "REPORT.md", "SECTION.md"):
        assert (tmp_path / name).is_file()
    text = got["report"].read_text()
    assert "1 failed (20: RuntimeError: boom)" in text
    assert "0.762 of the replicates at 94 %" in text  # 16 of 21 held b
    assert "b (low, 0.76)" in text
    assert got["section"].read_text().startswith("## Calibration in the study's configuration")
    assert "prior draws were drawn again (refused by the simulator)" in text
    # a selection of the draws is named as a reason they were drawn again
    selected = write_study_calibration(tmp_path, StudyCalibration(single=True, domain=True, min_ratio=1.0),
                                       results, {"numpy": np.__version__})["report"].read_text()
    assert ("drawn again (refused by the simulator, outside the impedance coordinates' domain or a record's "
            "force ratio below 1)") in selected


@pytest.mark.slow
def test_one_replicate_ranks_every_physical_parameter(tmp_path):
    cs = StudyCalibration(steps=40, draws=9, generator=GeneratorSettings(duration=3.0, ramp=1.0), likelihood=AR1)
    rep = study_replicate(cs, 0)
    # a work folder a stopped run would continue from: the same replicate, its fit kept there
    # (the caller, calibration.run_replicates, removes it once the replicate is written)
    work = tmp_path / "work"
    assert study_replicate(cs, 0, work) == rep and (work / "fit").is_dir()
    assert list(rep["ranks"]) == NAMES
    assert all(0 <= r <= cs.draws for r in rep["ranks"].values())
    assert all(rep["central"]["50"][n] <= rep["central"]["94"][n] for n in NAMES)  # nested by construction
    assert rep["iterations"] == 40
    assert rep["coordinates"].startswith(("impedance", "unconstrained"))  # the sampler's, for diagnosis
    taus = rep["tau_by_parameter"]  # the joint fit's b is named by its setting
    assert {"b" if n.startswith("b_") else n for n in taus} >= set(NAMES)
    assert rep["tau_max"] == pytest.approx(max(taus.values()))
    assert json.loads(json.dumps(rep)) == rep
    lo, hi = np.exp(STUDY_SBC_PRIORS["b"].bounds)
    assert lo <= rep["truth"]["b"] <= hi
    # replicate_device gives the device the replicate fitted: the same truth, its network's
    # parameters behind it, the same records again for the same seed
    device = replicate_device(cs, 0)
    assert device.truth == rep["truth"]
    assert device.params.b == pytest.approx(device.truth["b"])
    assert device.params.f1_0 + device.params.f2_0 == pytest.approx(device.truth["f_0"])
    # the drawn vector behind them, in the fits' coordinates, gives the same truth back
    model = PosteriorModel(device.records[0], priors=STUDY_SBC_PRIORS, likelihood=cs.likelihood)
    assert len(device.theta) == model.ndim
    back = model.values(np.array(device.theta))
    assert {n: pytest.approx(back[n]) for n in device.truth} == device.truth
    again = replicate_device(cs, 0)
    assert len(device.records) == len(cs.frequencies)
    for a, b in zip(device.records, again.records):
        np.testing.assert_array_equal(a.accel, b.accel)
        np.testing.assert_array_equal(a.force, b.force)


@pytest.mark.slow
def test_inspecting_a_replicate_remakes_its_device(tmp_path):
    cs = StudyCalibration(steps=30, draws=9, generator=GeneratorSettings(duration=3.0, ramp=1.0), likelihood=AR1)
    got = inspect_replicate(cs, 1, tmp_path / "fit")
    by = {r["parameter"]: r for r in got["parameters"]}
    assert list(by) == ["b_A3", *NAMES[1:], "rho_0.5Hz", "rho_1.5Hz"]
    assert by["rho_0.5Hz"]["truth"] is None  # the generator's noise has no AR(1) coefficient
    assert np.isfinite(got["log_posterior_truth"]) and np.isfinite(got["log_posterior_median"])
    rep = study_replicate(cs, 1)
    assert by["b_A3"]["truth"] == rep["truth"]["b"]  # the same seed, the same device
    assert all(r["q3"] <= r["median"] <= r["q97"] for r in got["parameters"])


def test_inspecting_a_single_record_replicate_uses_its_one_record(tmp_path):
    cs = StudyCalibration(steps=30, draws=9, generator=GeneratorSettings(duration=3.0, ramp=1.0), likelihood=AR1,
                          single=True)
    got = inspect_replicate(cs, 2, tmp_path / "fit")
    by = {r["parameter"]: r for r in got["parameters"]}
    assert list(by) == [*NAMES, "sigma", "rho"]  # one record: its own b, noise and AR(1) coefficient
    assert by["rho"]["truth"] is None and by["b"]["truth"] == replicate_device(cs, 2).truth["b"]
    assert np.isfinite(got["log_posterior_truth"]) and np.isfinite(got["log_posterior_median"])
    q = got["log_posterior_draws"]
    assert np.isfinite(q["q5"]) and q["q5"] <= q["q50"] <= q["q95"]
    # the share of draws below the truth agrees with where the truth falls among the quantiles
    below, truth = got["draws_below_truth"], got["log_posterior_truth_profiled"]
    assert truth >= got["log_posterior_truth"]  # maximised from the medians: never lower
    assert 0.0 <= below <= 1.0
    assert below >= 0.9 if truth > q["q95"] else below <= 0.1 if truth < q["q5"] else 0.04 <= below <= 0.96


def test_the_scripts_config_makes_the_settings_a_committed_folder_was_run_with():
    """results/coverage-sbc-v6's command, read as the script reads it, gives the settings
    that folder's settings.json holds (an option added since, absent there, at its
    default, or for the likelihood's at the value in effect before: how the study reads
    a folder it continues)."""
    from pathlib import Path

    from bayes_inerter.study.calibration import _saved_settings, _stored_settings, _with_defaults
    from bayes_inerter.study.study_calibration import Config

    folder = Path(__file__).resolve().parents[1] / "results" / "coverage-sbc-v6"
    saved = json.loads((folder / "settings.json").read_text())
    config = Config(replicates=150, seed=11, single=True, residual="motion", converge=True, max_steps=40000,
                    freqs=(0.5, 1.0, 1.5))
    mine = _stored_settings(config.settings())
    assert _with_defaults(_saved_settings(folder / "settings.json"), mine) == mine
    # fitted before the model-form terms existed, so without them: refused by a run that takes them
    formed = _stored_settings(dataclasses.replace(config, form_sd=0.005).settings())
    assert _with_defaults(_saved_settings(folder / "settings.json"), formed) != formed
    assert dataclasses.replace(config, form_sd=0.005, form_friction=0.01).settings().likelihood.form_friction == 0.01
    assert "law_sampled" not in saved["likelihood"]  # the case above: an option newer than the folder,
    assert mine["likelihood"]["law_sampled"] is False  # which the command leaves at its default
    with pytest.raises(ValueError, match="replicates must be"):
        Config(replicates=0)
    with pytest.raises(ValueError):
        Config(residual="no-such-likelihood")
    assert config.settings().likelihood.normaliser == "reference"  # the library's, unless asked
    asked = Config(single=True, residual="motion", normaliser="full", deviation_scale="parameters",
                   likelihood_force=True).settings()
    assert asked.likelihood.normaliser == "full" and asked.likelihood_force
    assert asked.likelihood.deviation_scale == "parameters"
    with pytest.raises(ValueError, match="normaliser must be one of"):
        Config(residual="motion", normaliser="no-such-normaliser")


def test_summarising_an_empty_folder_says_what_to_do(tmp_path):
    from bayes_inerter.executor import Serial
    from bayes_inerter.study.study_calibration import Config, run

    (tmp_path / "replicates").mkdir()
    with pytest.raises(ValueError, match="run the study into it first"):
        run(Config(summarise=True), tmp_path, Serial())


def test_a_raised_tau_floor_is_checked_and_reaches_the_fit(tmp_path, monkeypatch):
    """``tau_floor`` (a probe of the discrepancy's floor): refused outside the motion-in
    likelihood and outside the prior; the fit gets the study's priors with tau's floor
    raised, the devices drawn stay the same, and the script's option makes it."""
    from bayes_inerter.inference.posterior.priors import MOTION_DISCREPANCY_PRIORS, LogUniform
    from bayes_inerter.study import study_calibration
    from bayes_inerter.study.study_calibration import Config

    motion = LikelihoodSettings(residual="motion")
    with pytest.raises(ValueError, match="motion-in likelihood"):
        StudyCalibration(tau_floor=0.1)
    with pytest.raises(ValueError, match="tau_floor must lie"):
        StudyCalibration(tau_floor=0.0, likelihood=motion)
    assert StudyCalibration(likelihood=motion).priors() is STUDY_SBC_PRIORS
    cs = StudyCalibration(tau_floor=0.1, likelihood=motion, single=True, frequencies=(1.0,), steps=30)
    assert cs.priors() == {**STUDY_SBC_PRIORS, "tau": LogUniform(0.1, MOTION_DISCREPANCY_PRIORS["tau"].high)}
    assert "tau's prior floor 0.1 N" in cs.describe()
    assert Config(residual="motion", tau_floor=0.1, single=True).settings().tau_floor == 0.1

    class Stop(Exception):
        pass

    seen = {}

    def fake_fit(record, out, **options):  # the plumbing is tested, not a fit
        seen.update(options)
        raise Stop

    monkeypatch.setattr(study_calibration, "fit_record", fake_fit)
    with pytest.raises(Stop):
        study_replicate(cs, 0, tmp_path / "work")
    assert seen["priors"] == cs.priors()
    plain = StudyCalibration(likelihood=motion, single=True, frequencies=(1.0,), steps=30)
    assert replicate_device(cs, 0).truth == replicate_device(plain, 0).truth  # tau is fitted, never drawn


def test_the_calibration_keeps_its_folders_stopping_rule_unless_asked(tmp_path, monkeypatch):
    """``tau_rtol``: 0.05 by default (the rule the committed folders were stopped with),
    the script's option changes it, and the fit gets it."""
    from bayes_inerter.study import study_calibration
    from bayes_inerter.study.study_calibration import Config

    assert StudyCalibration().tau_rtol == 0.05 and Config().settings().tau_rtol == 0.05
    assert Config(tau_rtol=0.2).settings().tau_rtol == 0.2

    class Stop(Exception):
        pass

    seen = {}

    def fake_fit(record, out, **options):
        seen.update(options)
        raise Stop

    monkeypatch.setattr(study_calibration, "fit_record", fake_fit)
    cs = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.0,),
                          steps=None, max_steps=900, tau_rtol=0.2)
    with pytest.raises(Stop):
        study_replicate(cs, 0, tmp_path / "work")
    assert seen["convergence"].tau_rtol == 0.2 and seen["convergence"].max_steps == 900


def test_a_replicate_that_samples_the_gain_ranks_b_over_gain_too(tmp_path, monkeypatch):
    """Where the gain is sampled the replicate ranks b / gain (what the record identifies)
    beside b: here every draw puts b / gain 1 % high while b's spread holds the truth."""
    import types

    import xarray as xr

    from bayes_inerter.study import study_calibration

    cs = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.0,),
                          steps=None, max_steps=900, draws=19)
    truth = replicate_device(cs, 0).truth
    assert "gain" in truth
    rng = np.random.default_rng(0)
    gain = truth["gain"] * np.exp(0.02 * rng.standard_normal(400))
    draws = {n: np.full(400, v) for n, v in truth.items()}
    draws["gain"], draws["b"] = gain, 1.01 * truth["b"] / truth["gain"] * gain * np.exp(1e-4 * rng.standard_normal(400))
    post = xr.Dataset({n: (("chain", "draw"), v.reshape(1, -1)) for n, v in draws.items()})

    def fake_fit(record, out, **options):
        return types.SimpleNamespace(idata=types.SimpleNamespace(posterior=post), tau=[10.0], iterations=900,
                                     converged=True, coordinates="unconstrained", tau_by_parameter={})

    monkeypatch.setattr(study_calibration, "fit_record", fake_fit)
    rep = study_replicate(cs, 0, tmp_path / "work")
    got = rep["identified"][IDENTIFIED]
    assert got["truth"] == pytest.approx(truth["b"] / truth["gain"])
    assert got["rank"] == 0 and not got["hdi"]["94"] and not got["central"]["94"]
    assert rep["hdi"]["94"]["b"]  # b's own interval, widened by the gain's, holds it
    assert json.loads(json.dumps(rep)) == rep


def test_a_single_records_intervals_come_from_the_kept_draws_where_asked(tmp_path, monkeypatch):
    """``interval_draws="kept"``: the fit is asked for its kept draws and the intervals
    and ranks come from them, not from posterior.nc's simulated draws (here put far
    from the truth, so that reading them would miss)."""
    import types

    import xarray as xr

    from bayes_inerter.inference.fit import ALL_DRAWS_FILE
    from bayes_inerter.study import study_calibration

    asked = []
    for where in ("kept", "simulated"):
        cs = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.0,),
                              steps=None, max_steps=900, draws=19, interval_draws=where)
        truth = replicate_device(cs, 0).truth
        rng = np.random.default_rng(0)
        near = {n: v * np.exp(0.01 * rng.standard_normal((4, 100))) for n, v in truth.items()}
        post = xr.Dataset({n: (("chain", "draw"), np.full((1, 400), 2.0 * v)) for n, v in truth.items()})

        def fake_fit(record, out, all_draws=False, **options):
            asked.append(all_draws)
            if all_draws:
                out.mkdir(parents=True, exist_ok=True)
                np.savez_compressed(out / ALL_DRAWS_FILE, **near)
            return types.SimpleNamespace(idata=types.SimpleNamespace(posterior=post), tau=[10.0], iterations=900,
                                         converged=True, coordinates="unconstrained", tau_by_parameter={})

        monkeypatch.setattr(study_calibration, "fit_record", fake_fit)
        rep = study_replicate(cs, 0, tmp_path / where)
        held = all(rep["hdi"]["94"].values())
        assert held if where == "kept" else not any(rep["hdi"]["94"].values())
    assert asked == [True, False]


def test_domain_draws_again_only_the_devices_outside_the_impedance_domain():
    """``domain``: a device outside the impedance coordinates' domain (the prior a fit in
    them assumes) is drawn again; one inside is the same device, records and all."""
    from bayes_inerter.inference.sampling.coordinates import default_coordinates

    box = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.5,),
                           steps=None, seed=0, generator=GeneratorSettings(duration=4.0, ramp=0.8))
    held = dataclasses.replace(box, domain=True)

    def inside(device):
        model = PosteriorModel(device.records[0], priors=box.priors(), likelihood=box.likelihood)
        return bool(np.all(np.isfinite(default_coordinates(model, "impedance").to_u(np.array(device.theta)))))

    same, redrawn = [replicate_device(c, 0) for c in (box, held)], [replicate_device(c, 1) for c in (box, held)]
    assert inside(same[0]) and same[0].theta == same[1].theta
    assert np.array_equal(same[0].records[0].force, same[1].records[0].force)
    assert not inside(redrawn[0]) and inside(redrawn[1]) and redrawn[1].redraws > redrawn[0].redraws
    # a raised floor of tau's prior is not the impedance map's domain: the same device
    floored = dataclasses.replace(held, tau_floor=5e4)
    assert same[1].theta[PosteriorModel(same[1].records[0], priors=box.priors(),
                                        likelihood=box.likelihood).names.index("tau")] < np.log(5e4)
    assert replicate_device(floored, 0).theta == same[1].theta


def test_domain_reads_the_joint_fits_own_coordinates():
    """``domain`` in a joint calibration: a device outside the joint model's impedance
    coordinates is drawn again; one inside is the same device."""
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.inference.sampling.coordinates import default_coordinates

    box = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), frequencies=(1.0, 1.5), steps=None,
                           seed=0, generator=GeneratorSettings(duration=6.0, ramp=0.8))
    held = dataclasses.replace(box, domain=True)

    def inside(device):
        jm = JointModel(tuple(device.records), priors=box.priors(), likelihood=box.likelihood)
        values = PosteriorModel(device.records[0], priors=box.priors(), likelihood=box.likelihood).values(
            np.array(device.theta))
        return bool(np.all(np.isfinite(default_coordinates(jm, "impedance").to_u(jm.start([values, values])))))

    # replicates 0 and 44 of this box: the first inside the joint domain, the second
    # outside (few are: 2 of its first 60)
    same, redrawn = [replicate_device(c, 0) for c in (box, held)], [replicate_device(c, 44) for c in (box, held)]
    assert inside(same[0]) and same[0].theta == same[1].theta
    assert not inside(redrawn[0]) and inside(redrawn[1]) and redrawn[1].redraws > redrawn[0].redraws


def test_the_report_lists_the_priors_the_fits_sample():
    """The motion-in model samples the bearing's damper as the plate mode's damping
    ratio: the report's prior list names zeta_B with the model's prior, not the c_B the
    prior dict also holds; the other physical parameters keep the dict's priors."""
    from bayes_inerter.study.study_calibration import fitted_priors

    cs = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.5,),
                          steps=None, generator=GeneratorSettings(duration=4.0, ramp=0.8))
    priors = fitted_priors(cs)
    assert "zeta_B" in priors and "c_B" not in priors
    assert all(priors[n] == STUDY_SBC_PRIORS[n] for n in priors if n in STUDY_SBC_PRIORS)
    assert set(priors) >= {"b", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "k_B"}


def test_gain_draws_counts_the_true_gains_inside_their_prior(tmp_path):
    """A gain the records leave at its prior holds the truth as often as the draws fall
    inside the prior's interval: the count says whether a shortfall is the draws'."""
    from bayes_inerter.study.study_calibration import gain_draws

    sd = 0.01
    z = [0.1, -0.5, 0.9, -1.5, 2.5]  # in units of the prior's sd: 2 inside 50 %, 4 inside 94 %
    results = [{**_fake(k, True), "truth": {"gain": float(np.exp(v * sd))}} for k, v in enumerate(z)]
    (row,) = gain_draws(results + [{"replicate": 5, "error": "RuntimeError: no"}], sd)
    assert (row["replicates"], row["inside_50"], row["inside_94"]) == (5, 2, 4)
    assert row["expected_50"] == 2.5 and gain_draws([_fake(0, True)], sd) == []
    (tmp_path / "replicates").mkdir()
    for r in results:
        (tmp_path / "replicates" / f"{r['replicate']:04d}.json").write_text(json.dumps(r))
    (tmp_path / "settings.json").write_text(json.dumps({"likelihood": {"gain_sd": sd}}))
    write_coverage_so_far(tmp_path)
    assert (tmp_path / "gain_draws.csv").read_text().splitlines()[1].startswith("gain,5,")


def test_drawn_deviations_move_the_force_harmonics_by_the_likelihoods_own_basis():
    """The added signal's harmonics, as the likelihood measures them, are U beta with
    beta drawn at the prior's sd: the record then follows the likelihood's model."""
    from bayes_inerter.device import paper_parameters
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.records import generate_record
    from bayes_inerter.study.study_calibration import drawn_deviations

    lk = LikelihoodSettings(residual="motion")
    params = paper_parameters("A3")
    gen = GeneratorSettings(duration=6.0, ramp=1.0)
    for freq in (1.0, 1.5):  # 1.5 Hz: a period is not a whole number of samples
        rec = generate_record(params, freq, settings=gen, rng=np.random.default_rng(1), setting_name="A3")
        got = drawn_deviations(rec, params, lk, np.random.default_rng(2))
        assert np.array_equal(got.accel, rec.accel) and np.array_equal(got.disp, rec.disp)
        before = PosteriorModel(rec, priors=STUDY_SBC_PRIORS, likelihood=lk).motion
        after = PosteriorModel(got, priors=STUDY_SBC_PRIORS, likelihood=lk).motion
        K = before.omega.shape[0]
        s = before.scale @ np.array([params.f1_0, params.f2_0, 1.0])
        X = before.basis @ (np.random.default_rng(2).normal(size=s.shape[0]) * s)
        want = X[:K] + 1j * X[K:]
        moved = after.harmonic.force - before.harmonic.force
        assert np.max(np.abs(want)) > 1.0  # the deviations are forces of newtons, not nothing
        assert np.allclose(moved, want, rtol=0, atol=1e-3 * np.max(np.abs(want)))
        # the motion, and with it the basis, is the record's: unchanged
        assert np.array_equal(after.basis, before.basis)


def test_drawn_deviation_groups_add_up_to_all_of_them():
    """The reversals' and the law's draws are the parts of the whole draw: each group
    alone moves the force by its own columns, and the two add up to "all"."""
    from bayes_inerter.device import paper_parameters
    from bayes_inerter.records import generate_record
    from bayes_inerter.study.study_calibration import drawn_deviations

    lk = LikelihoodSettings(residual="motion")
    params = paper_parameters("A3")
    rec = generate_record(params, 1.0, settings=GeneratorSettings(duration=6.0, ramp=1.0),
                          rng=np.random.default_rng(1), setting_name="A3")
    moved = {g: drawn_deviations(rec, params, lk, np.random.default_rng(2), groups=g).force - rec.force
             for g in ("all", "reversals", "law")}
    for g in ("reversals", "law"):
        assert np.max(np.abs(moved[g])) > 0.1 * np.max(np.abs(moved["all"]))  # each group is there
    assert np.allclose(moved["reversals"] + moved["law"], moved["all"], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="groups must be one of"):
        drawn_deviations(rec, params, lk, np.random.default_rng(2), groups="tau")


def test_drawn_deviations_need_the_motion_likelihood():
    with pytest.raises(ValueError, match="residual 'motion'"):
        StudyCalibration(single=True, draw_deviations=True, likelihood=LikelihoodSettings(residual="ar1"))


def test_likelihood_force_puts_the_likelihoods_own_draw_in_the_force_harmonics():
    """At the truth the residual the likelihood sees is exactly what was drawn: complex
    normal noise of the likelihood's variance plus the marginalised deviations at their
    prior sd; the motion and the period scatter stay the record's."""
    from bayes_inerter.device import paper_parameters
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.posterior.motion import deviation_sd, motion_variance, predicted_force
    from bayes_inerter.records import generate_record
    from bayes_inerter.study.study_calibration import likelihood_force

    lk = LikelihoodSettings(residual="motion")
    params = paper_parameters("A3")
    rec = generate_record(params, 1.5, settings=GeneratorSettings(duration=6.0, ramp=1.0),
                          rng=np.random.default_rng(1), setting_name="A3")
    model = PosteriorModel(rec, priors=STUDY_SBC_PRIORS, likelihood=lk)
    theta = model.to_theta(params, hyper={"gain": 1.002, "delay": 1e-4})
    got = likelihood_force(rec, theta, lk, np.random.default_rng(2))
    assert np.array_equal(got.accel, rec.accel) and np.array_equal(got.disp, rec.disp)
    after = PosteriorModel(got, priors=STUDY_SBC_PRIORS, likelihood=lk).with_reference(theta).motion
    before = model.with_reference(theta).motion
    assert np.array_equal(after.basis, before.basis)
    assert np.allclose(after.harmonic.var_force, before.harmonic.var_force, rtol=1e-9, atol=0)
    x, h = model.field_vector(theta), model.hyper(theta)
    F, _ = predicted_force(before, x, h["gain"], h["delay"])
    V, _ = motion_variance(before, x, 0.0, 0.0, h["gain"], h["delay"])
    rng = np.random.default_rng(2)  # the same draws in the same order
    K = V.shape[0]
    noise = (rng.normal(size=K) + 1j * rng.normal(size=K)) * np.sqrt(V / 2.0)
    X = before.basis @ (rng.normal(size=before.basis.shape[1]) * deviation_sd(before, x))
    want = noise + X[:K] + 1j * X[K:]
    residual = after.harmonic.force - F
    assert np.max(np.abs(X)) > 1.0  # the deviations are forces of newtons, not nothing
    assert np.allclose(residual, want, rtol=0, atol=1e-3 * np.sqrt(np.min(V)))


def test_likelihood_force_needs_the_motion_likelihood_and_no_drawn_deviations():
    with pytest.raises(ValueError, match="residual 'motion'"):
        StudyCalibration(single=True, likelihood_force=True, likelihood=LikelihoodSettings(residual="ar1"))
    with pytest.raises(ValueError, match="leave draw_deviations off"):
        StudyCalibration(single=True, likelihood_force=True, draw_deviations=True,
                         likelihood=LikelihoodSettings(residual="motion"))


def test_an_independent_motion_device_makes_the_motion_and_the_truth_the_force():
    """``motion_device`` "independent": the records' motion is a second device's, drawn
    apart from the truth; the truth is the same draw as with its own motion, and its
    force harmonics are the likelihood's draw at the truth on the other motion (replayed
    here from the replicate's random stream)."""
    from bayes_inerter.study.study_calibration import _base_model, _simulated_draw, likelihood_force

    own = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.5,),
                           steps=None, seed=3, generator=GeneratorSettings(duration=4.0, ramp=0.8),
                           likelihood_force=True)
    other = dataclasses.replace(own, motion_device="independent")
    a, b = replicate_device(own, 0), replicate_device(other, 0)
    assert a.theta == b.theta and a.truth == b.truth and a.redraws == b.redraws == 0
    assert not np.allclose(a.records[0].accel, b.records[0].accel)
    rng = np.random.default_rng([other.seed, 0])
    base = _base_model(other, STUDY_SBC_PRIORS)
    truth = _simulated_draw(other, base, other.frequencies, rng)
    assert tuple(truth[0]) == b.theta
    second = None
    while second is None:
        second = _simulated_draw(other, base, other.frequencies, rng)
    assert not np.allclose(second[0], truth[0])
    seen = dataclasses.replace(second[2][0], accel=second[2][0].accel * b.truth["gain"])
    want = likelihood_force(seen, np.array(b.theta), other.likelihood, rng)
    assert np.array_equal(b.records[0].accel, want.accel) and np.array_equal(b.records[0].disp, want.disp)
    assert np.array_equal(b.records[0].force, want.force)
    assert "independent device" in other.describe()
    with pytest.raises(ValueError, match="likelihood_force"):
        StudyCalibration(single=True, motion_device="independent", likelihood=LikelihoodSettings(residual="motion"))
    with pytest.raises(ValueError, match="motion_device must be one of"):
        dataclasses.replace(own, motion_device="servo")


def test_no_law_leaves_the_friction_laws_deviations_out_of_the_fits():
    from bayes_inerter.study.study_calibration import Config

    assert Config(single=True, residual="motion").settings().likelihood.law
    assert not Config(single=True, residual="motion", law=False).settings().likelihood.law


def test_no_reversals_leaves_the_reversals_deviations_out_of_the_fits():
    from bayes_inerter.study.study_calibration import Config

    assert Config(single=True, residual="motion").settings().likelihood.reversals
    settings = Config(single=True, residual="motion", reversals=False).settings().likelihood
    assert not settings.reversals and settings.law


def test_min_ratio_draws_again_only_the_records_below_it():
    """``min_ratio``: a record whose own force ratio (records.reactance) lies below it is
    drawn again, device and record; one above is the same device, records and all; a
    joint replicate is drawn again while any of its records lies below it."""
    from bayes_inerter.records.reactance import drive_impedance

    box = StudyCalibration(likelihood=LikelihoodSettings(residual="motion"), single=True, frequencies=(1.5,),
                           steps=None, seed=0, generator=GeneratorSettings(duration=4.0, ramp=0.8))
    plain = [replicate_device(box, k) for k in range(4)]
    ratios = [drive_impedance(d.records[0]).ratio for d in plain]
    level = float(np.median(ratios))  # some of these records lie below it, some above
    held = dataclasses.replace(box, min_ratio=level)
    for k, (device, ratio) in enumerate(zip(plain, ratios)):
        got = replicate_device(held, k)
        assert drive_impedance(got.records[0]).ratio >= level
        if ratio >= level:
            assert got.theta == device.theta and np.array_equal(got.records[0].force, device.records[0].force)
        else:
            assert got.theta != device.theta and got.redraws > device.redraws
    for bad in (0.0, -1.0, float("nan"), True):
        with pytest.raises(ValueError, match="min_ratio"):
            dataclasses.replace(box, min_ratio=bad)
    # a joint replicate is kept only where every one of its records reads at least the level
    joint = dataclasses.replace(box, single=False, frequencies=(1.0, 1.5),
                                generator=GeneratorSettings(duration=6.0, ramp=0.8))
    first = replicate_device(joint, 0)
    slowest = min(drive_impedance(r).ratio for r in first.records)
    assert slowest > 0
    got = replicate_device(dataclasses.replace(joint, min_ratio=slowest * 1.5), 0)
    assert got.theta != first.theta
    assert len(got.records) == 2 and min(drive_impedance(r).ratio for r in got.records) >= slowest * 1.5


def test_a_model_form_sd_records_the_device_with_b_moved_by_its_error():
    """Where the likelihood marginalises a model-form error of b (``form_sd`` s), the
    calibration's records are made with b e^eps, eps ~ N(0, s^2) drawn after the device:
    the device (theta, the truth the posterior is held against) is the one drawn
    without it, and its records' b differs from the truth's by eps. Without it the
    records' b is the truth's."""
    generator = GeneratorSettings(duration=6.0, ramp=1.0)
    plain = StudyCalibration(generator=generator, single=True, frequencies=(1.5,), likelihood=LikelihoodSettings())
    formed = dataclasses.replace(plain, likelihood=dataclasses.replace(plain.likelihood, form_sd=0.05))
    eps = []
    for k in range(4):
        a, b = replicate_device(plain, k), replicate_device(formed, k)
        assert a.theta == b.theta and a.truth == b.truth
        assert a.records[0].metadata["true_parameters"]["b"] == pytest.approx(a.truth["b"], rel=1e-12)
        eps.append(np.log(b.records[0].metadata["true_parameters"]["b"] / b.truth["b"]))
    assert all(0.0 < abs(e) < 5 * 0.05 for e in eps)


def test_the_friction_scaled_form_error_is_drawn_by_its_size_for_each_record():
    """With ``form_friction`` rho alone, each record's b is moved by eps of sd
    rho f_0 / (b w^2 X): drawn anew per record (each likelihood has its own term), so
    a joint calibration's records differ in b; the device's truth is kept."""
    generator = GeneratorSettings(duration=6.0, ramp=1.0)
    plain = StudyCalibration(generator=generator, frequencies=(1.0, 1.5), likelihood=LikelihoodSettings())
    formed = dataclasses.replace(plain, likelihood=dataclasses.replace(plain.likelihood, form_friction=0.05))
    z = []
    for k in range(3):
        a, b = replicate_device(plain, k), replicate_device(formed, k)
        assert a.theta == b.theta and a.truth == b.truth
        p = b.params
        moved = [np.log(r.metadata["true_parameters"]["b"] / p.b) for r in b.records]
        assert moved[0] != moved[1]  # each record its own draw
        for r, eps in zip(b.records, moved):
            f = r.metadata["drive_frequency_hz"]
            sd = 0.05 * (p.f1_0 + p.f2_0) / (p.b * (2 * np.pi * f) ** 2 * generator.amplitude)
            z.append(eps / sd)
    assert all(0.0 < abs(v) < 5.0 for v in z)  # of its size: a few sd at most
