"""The paper-like coverage study (``study.paper_like_coverage``): its configuration, a
folder's one family and likelihood, and its tables remade from committed replicates."""

import csv
import json
from pathlib import Path

import pytest

from bayes_inerter.device import grid_case
from bayes_inerter.inference import Convergence
from bayes_inerter.executor import Serial
from bayes_inerter.study.paper_like_coverage import Config, likelihood_settings, run
from bayes_inerter.study.replicate_store import finished, replicate_path

COMMITTED = Path(__file__).resolve().parents[1] / "results" / "coverage-paper-like-v5"


def _copy_committed(folder):
    """The committed replicates (loose or packed: ``study.replicate_store``) written
    loose into ``folder``."""
    (folder / "replicates").mkdir(parents=True)
    for r in finished(COMMITTED):
        replicate_path(folder, r["replicate"]).write_text(json.dumps(r))


@pytest.mark.parametrize("changes, cause", [
    ({"family": "nonsense"}, "unknown family"), ({"freq": 2.0}, "freq must be one of"),
    ({"likelihood": "input_noise"}, "name=value pairs"), ({"likelihood": "no_such=1"}, "not a likelihood setting"),
    ({"replicates": 0}, "replicates must be"), ({"parity": "first"}, "parity must be one of"), ({"tempering": 1}, "at least 2 temperatures"),
    ({"tempering": 4, "hottest_beta": 1.0}, "hottest beta")])
def test_the_configuration_names_what_it_refuses(changes, cause):
    with pytest.raises(ValueError, match=cause):
        Config(**changes)


def test_summarise_remakes_the_committed_tables(tmp_path):
    _copy_committed(tmp_path)
    got = run(Config(summarise=True), tmp_path, Serial())
    for name in ("replicates.csv", "coverage.csv"):
        assert (tmp_path / name).read_bytes() == (COMMITTED / name).read_bytes()
    assert got.values["coverage"][-1]["freq_hz"] == "all" and not got.failed


def test_a_folder_keeps_one_family_one_likelihood_and_one_sampler(tmp_path):
    (tmp_path / "replicates").mkdir()
    one = finished(COMMITTED)[0]
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(one))
    with pytest.raises(ValueError, match="family default, not backlash"):
        run(Config(family="backlash"), tmp_path, Serial())
    with pytest.raises(ValueError, match="other likelihood settings"):
        run(Config(likelihood="input_noise=3"), tmp_path, Serial())
    today = {**one, "likelihood_settings": likelihood_settings(Config().likelihood)}
    # a replicate written before form_sd existed was fitted without it: the same likelihood as form_sd=0
    before = {**today, "likelihood_settings": {k: v for k, v in today["likelihood_settings"].items() if k != "form_sd"}}
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps({**before, "tempering": [4, 0.1]}))
    with pytest.raises(ValueError, match="another sampler than the ensemble alone"):  # past the likelihood's check
        run(Config(likelihood="form_sd=0"), tmp_path, Serial())
    with pytest.raises(ValueError, match="other likelihood settings"):
        run(Config(likelihood="form_sd=0.005"), tmp_path, Serial())
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(today))
    with pytest.raises(ValueError, match="another sampler than parallel tempering, 4 temperatures"):
        run(Config(tempering=4), tmp_path, Serial())
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps({**today, "tempering": [4, 0.1]}))
    with pytest.raises(ValueError, match="another sampler than the ensemble alone"):
        run(Config(), tmp_path, Serial())
    with pytest.raises(ValueError, match="tempering, 4 temperatures, beta 1, 0.215, 0.0464, 0.01; choose"):
        run(Config(tempering=4, hottest_beta=0.01), tmp_path, Serial())  # the same temperatures, a hotter end


def test_a_folder_keeps_one_stopping_rule(tmp_path):
    """Replicates that do not name their tolerance were stopped with the old 0.05: a run
    with the package's is refused, one asking 0.05 continues them (here: summarises,
    every replicate asked being there)."""
    (tmp_path / "replicates").mkdir()
    one = finished(COMMITTED)[0]
    today = {**one, "likelihood_settings": likelihood_settings(Config().likelihood)}
    assert "tau_rtol" not in today
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(today))
    with pytest.raises(ValueError, match=f"tau_rtol 0.05, not {Convergence().tau_rtol:g}: continue it with "
                                         "--tau-rtol 0.05"):
        run(Config(replicates=1, block_partners="random"), tmp_path, Serial())
    got = run(Config(replicates=1, tau_rtol=0.05, block_partners="random"), tmp_path, Serial())
    assert (tmp_path / "coverage.csv").exists() and not got.failed


def test_a_folder_keeps_one_record_length(tmp_path):
    """Replicates that do not name a length are the paper's 10 s records: a run asking
    20 s is refused; a folder of 20 s records refuses the paper's and continues a run
    asking 20 s (here: every replicate asked being there, it only summarises)."""
    (tmp_path / "replicates").mkdir()
    one = finished(COMMITTED)[0]
    today = {**one, "likelihood_settings": likelihood_settings(Config().likelihood), "tau_rtol": 0.05}
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(today))
    with pytest.raises(ValueError, match="another length than 20 s; choose another folder"):
        run(Config(replicates=1, tau_rtol=0.05, duration=20.0, block_partners="random"), tmp_path, Serial())
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps({**today, "duration_s": 20.0}))
    with pytest.raises(ValueError, match="another length than the paper's 10 s"):
        run(Config(replicates=1, tau_rtol=0.05, block_partners="random"), tmp_path, Serial())
    got = run(Config(replicates=1, tau_rtol=0.05, duration=20.0, block_partners="random"), tmp_path, Serial())
    assert not got.failed
    with pytest.raises(ValueError, match="duration must be a positive number"):
        Config(duration=0.0)


def test_a_folder_keeps_one_choice_of_block_moves(tmp_path, monkeypatch):
    """Replicates that do not name their block moves were fitted with random blocks: a
    run asking correlated ones is refused and told how to go on with theirs; a replicate
    fitted with correlated blocks names them, and the fit is given its choice."""
    from bayes_inerter.study import paper_like_coverage as plc

    (tmp_path / "replicates").mkdir()
    one = finished(COMMITTED)[0]
    today = {**one, "likelihood_settings": likelihood_settings(Config().likelihood), "tau_rtol": 0.05}
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(today))
    with pytest.raises(ValueError, match="other block moves than 'correlated' \\(give --block-partners random"):
        run(Config(replicates=1, tau_rtol=0.05, block_partners="correlated"), tmp_path, Serial())
    assert not run(Config(replicates=1, tau_rtol=0.05), tmp_path, Serial()).failed  # the default: random
    calls = []
    monkeypatch.setattr(plc, "fit_record", _fake_fit(calls))
    got = plc.replicate(0, 6000, 500, block_partners="correlated")
    assert got["block_partners"] == "correlated" == calls[0]["adaptation"].block_partners
    assert "block_partners" not in plc.replicate(0, 6000, 500)
    assert calls[1]["adaptation"].block_partners == "random"
    with pytest.raises(ValueError, match="block_partners must be one of"):
        Config(block_partners="nearest")


def test_summarise_of_an_empty_folder_says_what_to_do(tmp_path):
    with pytest.raises(ValueError, match="run without summarise first"):
        run(Config(summarise=True), tmp_path, Serial())


def test_progress_counts_only_the_replicates_of_the_frequency_asked(tmp_path):
    (tmp_path / "replicates").mkdir()
    today = likelihood_settings(Config().likelihood)  # the committed ones were fitted under an earlier default
    for r in finished(COMMITTED):
        replicate_path(tmp_path, r["replicate"]).write_text(json.dumps({**r, "likelihood_settings": today}))
    seen = []
    run(Config(freq=0.5, replicates=100, tau_rtol=0.05, block_partners="random"), tmp_path, Serial(),  # as fitted
        progress=lambda done, total: seen.append((done, total)))
    at_half = sum(r["freq_hz"] == 0.5 for r in finished(COMMITTED))
    assert at_half < 100 and seen == [(at_half, at_half)]


def test_parity_asks_only_the_odd_or_the_even_replicates():
    odd, even_at_1hz = Config(parity="odd"), Config(parity="even", freq=1.0)
    assert [k for k in range(6) if odd.wants(k)] == [1, 3, 5]
    assert all(k % 2 == 0 and grid_case(k)[1] == 1.0 for k in range(54) if even_at_1hz.wants(k))
    assert any(even_at_1hz.wants(k) for k in range(54))


def test_pairs_set_each_replicate_beside_the_same_record_fitted_otherwise(tmp_path):
    for side in ("a", "b"):
        _copy_committed(tmp_path / side)
    first = tmp_path / "b" / "replicates" / "0000.json"
    one = json.loads(first.read_text())
    first.write_text(json.dumps({**one, "b_median": one["b_true"], "covered50": True, "width94_pct": 2 * one["width94_pct"]}))
    got = run(Config(summarise=True, against=str(tmp_path / "a")), tmp_path / "b", Serial())
    rows = list(csv.DictReader((tmp_path / "b" / "pairs.csv").open()))
    assert len(rows) == 100 and rows[0]["error_pct"] == "0.0" and rows[0]["error_pct_against"] != "0.0"
    overall = got.values["pairs"][-1]
    assert overall["pairs"] == 100 and overall["median_ratio_width94_pct"] == 1.0
    assert overall["held50"] - overall["held50_against"] == (not one["covered50"])
    first.write_text(json.dumps({**one, "seed": one["seed"] + 1}))
    with pytest.raises(ValueError, match="not the same record"):
        run(Config(summarise=True, against=str(tmp_path / "a")), tmp_path / "b", Serial())
    with pytest.raises(ValueError, match="give it with summarise"):
        Config(against=str(tmp_path / "a"))


def _fake_fit(calls):
    """A stand-in for ``fit_record`` that keeps the options it was called with and gives
    a posterior of b around the true A0's (the plumbing is tested, not a fit)."""
    from types import SimpleNamespace

    import numpy as np

    def fit(record, out, **options):
        calls.append(options)
        b = np.random.default_rng(0).normal(753.34, 5.0, size=(2, 200))
        return SimpleNamespace(idata=SimpleNamespace(posterior={"b": b}), converged=True, iterations=750,
                               tau=np.array([4.0, 6.0]), tau_by_parameter={"b": 4.0, "f_0": 6.04},
                               b_interval=SimpleNamespace(identified=True, phi=0.9),
                               tempering=None if options.get("tempering") is None else {"swap_rates": [0.3, 0.2]})
    return fit


def test_a_tempered_replicate_is_fitted_tempered_and_says_so(tmp_path, monkeypatch):
    from bayes_inerter.study import paper_like_coverage as plc

    calls = []
    monkeypatch.setattr(plc, "fit_record", _fake_fit(calls))
    got = plc.replicate(0, 6000, 500, tempering=Config(tempering=3, hottest_beta=0.2).ladder())
    assert calls[0]["tempering"].temps == 3 and calls[0]["tempering"].beta_min == 0.2
    assert got["tempering"] == [3, 0.2] and got["swap_rates"] == [0.3, 0.2]
    assert calls[0]["convergence"].tau_rtol == got["tau_rtol"] == Convergence().tau_rtol
    assert calls[0]["convergence"].max_steps == 500
    assert got["tau_by_parameter"] == {"b": 4.0, "f_0": 6.0}  # which parameters are slow
    untempered = plc.replicate(0, 6000, 500, tau_rtol=0.05)
    assert calls[1]["convergence"].tau_rtol == untempered["tau_rtol"] == 0.05
    assert calls[1]["tempering"] is None and "tempering" not in untempered and "swap_rates" not in untempered


def test_a_work_folder_holds_the_fit_while_it_runs_and_goes_when_done(tmp_path, monkeypatch):
    from pathlib import Path

    from bayes_inerter.study import paper_like_coverage as plc

    calls, seen = [], []
    fake = _fake_fit(calls)

    def fit(record, out, **options):  # the folder exists while the fit runs there
        Path(out).mkdir(parents=True)
        (Path(out) / "chain.h5").write_bytes(b"steps")
        seen.append(Path(out))
        got = fake(record, out, **options)
        got.timings = {"sampling": 2.0, "sampling_all_runs": 5.04, "steps_timed": 750}  # two runs built it
        return got

    monkeypatch.setattr(plc, "fit_record", fit)
    work = tmp_path / "work"
    config = Config(replicates=1, seed0=6000, max_steps=500, work=str(work))
    plc._run((0, tmp_path / "out", config, "abc"))
    assert seen == [work / "0000" / "fit"]  # the same path a rerun continues from
    assert not (work / "0000").exists()  # removed once the replicate is written
    (got,) = plc.finished(tmp_path / "out")
    assert got["replicate"] == 0
    assert got["sampling_s_all_runs"] == 5.0 and got["steps_timed"] == 750  # every run's, not the last one's


def test_a_work_folder_outlives_a_replicate_that_could_not_be_written(tmp_path, monkeypatch):
    from pathlib import Path

    from bayes_inerter.study import paper_like_coverage as plc

    fake = _fake_fit([])

    def fit(record, out, **options):
        Path(out).mkdir(parents=True)
        (Path(out) / "chain.h5").write_bytes(b"steps")
        return fake(record, out, **options)

    def no_disk(out, k, result, indent=None):
        raise OSError("No space left on device")

    monkeypatch.setattr(plc, "fit_record", fit)
    monkeypatch.setattr(plc, "write_replicate", no_disk)
    work = tmp_path / "work"
    with pytest.raises(OSError):
        plc._run((0, tmp_path / "out", Config(replicates=1, max_steps=500, work=str(work)), "abc"))
    assert (work / "0000" / "fit" / "chain.h5").is_file()  # the next run continues the chain


def test_a_work_folder_of_another_run_is_refused_and_one_without_a_stamp_taken(tmp_path):
    from bayes_inerter.study import paper_like_coverage as plc
    from bayes_inerter.study.calibration import WORK_STAMP

    work, out = tmp_path / "work", tmp_path / "out"
    got = plc._work_folder(Config(max_steps=80000, work=str(work)), out, 3)
    assert got == work / "0003" and (got / WORK_STAMP).is_file()
    assert plc._work_folder(Config(max_steps=80000, work=str(work)), out, 3) == got  # the same run goes on
    with pytest.raises(ValueError, match=r"max_steps 80000 there, 20000 here.*another work folder"):
        plc._work_folder(Config(max_steps=20000, work=str(work)), out, 3)
    with pytest.raises(ValueError, match="out "):
        plc._work_folder(Config(max_steps=80000, work=str(work)), tmp_path / "other", 3)
    (work / "0004" / "fit").mkdir(parents=True)  # a chain left by code before the stamp
    assert plc._work_folder(Config(max_steps=20000, work=str(work)), out, 4) == work / "0004"
    assert plc._work_folder(Config(), out, 0) is None  # no work folder: a temporary one per fit


def test_b_over_gain_is_held_against_the_laboratorys_own_gain_ratio(tmp_path, monkeypatch):
    """A posterior that samples the gain gives b / gain's intervals, which the summary
    holds against b g_F / g_a of the replicate's laboratory, not against b."""
    from types import SimpleNamespace

    import numpy as np

    from bayes_inerter.records.paper_like import laboratory
    from bayes_inerter.study import paper_like_coverage as plc
    from bayes_inerter.study.replicate_store import write_replicate

    lab = laboratory(6000)
    apparent = 753.34 * lab.force_gain / lab.accel_gain
    rng = np.random.default_rng(1)
    gain = np.exp(rng.normal(0.0, 0.005, size=(2, 400)))
    ratio = rng.normal(apparent, 0.5, size=(2, 400))  # b / gain tightly about b g_F / g_a

    def fit(record, out, **options):
        return SimpleNamespace(idata=SimpleNamespace(posterior={"b": ratio * gain, "gain": gain}), converged=True,
                               iterations=750, tau=np.array([4.0]), tau_by_parameter=None,
                               b_interval=SimpleNamespace(identified=True, phi=0.9))

    monkeypatch.setattr(plc, "fit_record", fit)
    got = plc.replicate(0, 6000, 500)
    lo, hi = got["hdi94_b_over_gain"]
    assert lo < apparent < hi and hi - lo < 3.0 < got["hdi94"][1] - got["hdi94"][0]
    write_replicate(tmp_path, 0, got)
    shifted = {**got, "replicate": 1, "hdi94_b_over_gain": [apparent + 1.0, apparent + 2.0]}  # misses
    write_replicate(tmp_path, 1, shifted)
    (row,) = [r for r in plc.summarise(tmp_path) if r["freq_hz"] == "all"]
    assert row["converged_with_b_over_gain"] == 2 and row["coverage94_b_over_gain_converged"] == 0.5
    lines = list(csv.DictReader((tmp_path / "replicates.csv").open()))
    assert [x["covered94_b_over_gain"] for x in lines] == ["True", "False"]


def test_a_replicate_fits_the_model_asked_and_a_folder_keeps_one(tmp_path, monkeypatch):
    from bayes_inerter.study import paper_like_coverage as plc

    calls = []
    monkeypatch.setattr(plc, "fit_record", _fake_fit(calls))
    richer = plc.replicate(0, 6000, 500, model="two-port-stribeck")
    assert calls[0]["model"] == "two-port-stribeck" and richer["model"] == "two-port-stribeck"
    assert "model" not in plc.replicate(0, 6000, 500) and calls[1]["model"] == "two-port"
    with pytest.raises(ValueError, match="unknown model 'three-port'"):
        Config(model="three-port")
    (tmp_path / "replicates").mkdir()
    today = {**finished(COMMITTED)[0], "likelihood_settings": likelihood_settings(Config().likelihood)}
    (tmp_path / "replicates" / "0000.json").write_text(json.dumps(today))
    with pytest.raises(ValueError, match="of the model two-port, not two-port-stribeck"):
        run(Config(model="two-port-stribeck"), tmp_path, Serial())


def test_b_with_the_model_form_error_is_drawn_from_the_same_chain_and_counted(tmp_path, monkeypatch):
    """Each replicate also keeps b's intervals with the model-form error drawn after the
    likelihood (``summaries.model_form``): about the same centre, wider by the law's sd
    (here its friction term dominates: f_0 large against b's inertial force); summarise
    counts them among the converged replicates."""
    from types import SimpleNamespace

    import math

    import numpy as np

    from bayes_inerter.device import paper_parameters
    from bayes_inerter.inference.summaries.model_form import ModelFormError, accel_amplitude
    from bayes_inerter.study import paper_like_coverage as plc
    from bayes_inerter.study.replicate_store import write_replicate

    b_true = paper_parameters(grid_case(0)[0]).b
    rng = np.random.default_rng(2)
    b = rng.normal(b_true, 1e-4 * b_true, size=(2, 2000))
    f_0 = np.full(b.shape, 800.0)

    def fit(record, out, **options):
        return SimpleNamespace(idata=SimpleNamespace(posterior={"b": b, "f_0": f_0}), converged=True,
                               iterations=750, tau=np.array([4.0]), tau_by_parameter=None,
                               b_interval=SimpleNamespace(identified=True, phi=0.9))

    monkeypatch.setattr(plc, "fit_record", fit)
    got = plc.replicate(0, 6000, 500)
    rec = plc.paper_like_record(*grid_case(0), seed=6000, device=plc.FAMILIES["default"])
    sd = float(ModelFormError().relative_sd(b_true, 800.0, accel_amplitude(rec)))
    lo, hi = got["hdi94_form"]
    width = math.log(hi / lo)
    assert width == pytest.approx(2 * 1.881 * sd, rel=0.1)  # a normal's 94 % HDI is +-1.881 sd wide
    assert math.log(math.sqrt(lo * hi) / b_true) == pytest.approx(0.0, abs=0.1 * sd)
    assert got["hdi94"][1] - got["hdi94"][0] < 0.1 * (hi - lo)
    write_replicate(tmp_path, 0, got)
    write_replicate(tmp_path, 1, {**got, "replicate": 1, "hdi94_form": [hi, 2 * hi]})  # misses
    (row,) = [r for r in plc.summarise(tmp_path) if r["freq_hz"] == "all"]
    assert row["converged_with_form"] == 2 and row["coverage94_form_converged"] == 0.5
    lines = list(csv.DictReader((tmp_path / "replicates.csv").open()))
    assert [x["covered94_form"] for x in lines] == ["True", "False"]
