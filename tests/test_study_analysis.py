"""Study tables from synthetic fits (no sampling): combining records, the flywheel
regression, and the report's sentences."""

import math
from pathlib import Path

import numpy as np
import pytest

from bayes_inerter.device import DEFAULT_GEOMETRY, SETTINGS, theoretical_inertance
from bayes_inerter.study.analysis import Z94, RecordFit, flywheel_regression, inertance_table, phi_table


def fake_fit(setting, freq, b_mean, b_sd, model="two-port", converged=True, phi=0.9):
    row = lambda m, s: {"mean": m, "sd": s, "hdi_3%": m - Z94 * s, "hdi_97%": m + Z94 * s, "r_hat": 1.0}  # noqa: E731
    return RecordFit(f"{setting}_{freq:g}Hz", setting, freq, model, Path("."),
                     {"b": row(b_mean, b_sd), "phi": row(phi, 0.01)}, {"converged": converged, "iterations": 100})


def test_records_of_a_setting_combine_as_a_product_of_normals():
    fits = [fake_fit("A1", 0.5, 1000.0, 10.0), fake_fit("A1", 1.0, 1030.0, 20.0), fake_fit("A2", 1.0, 2000.0, 5.0),
            fake_fit("A1", 1.0, 0.0, 1.0, model="rigid")]
    rows = {r["setting"]: r for r in inertance_table(fits)}
    a1 = rows["A1"]
    # precisions 1/100 and 1/400: mean (1000*4 + 1030) / 5 = 1006, sd sqrt(80)
    assert a1["b_median"] == pytest.approx(1006.0)
    chi2 = 6.0**2 / 100 + 24.0**2 / 400  # 1.8 on 1 degree of freedom: they disagree
    assert a1["chi2"] == pytest.approx(chi2)
    assert a1["scale"] == pytest.approx(np.sqrt(chi2))
    assert a1["b_sd"] == pytest.approx(np.sqrt(80.0) * np.sqrt(chi2))
    assert a1["b_hdi_97%"] - a1["b_median"] == pytest.approx(Z94 * np.sqrt(80.0 * chi2))
    assert a1["records"] == 2 and rows["A2"]["records"] == 1 and rows["A2"]["scale"] == 1.0
    assert a1["b_theory"] == pytest.approx(theoretical_inertance("A1"))
    assert a1["b_paper"] == SETTINGS["A1"].b_paper


def test_records_that_agree_keep_their_combined_sd():
    # means 1000 and 1010, sds 10: chi2 = 2 * 5^2 / 100 = 0.5 < 1 degree of freedom
    a1 = inertance_table([fake_fit("A1", 0.5, 1000.0, 10.0), fake_fit("A1", 1.0, 1010.0, 10.0)])[0]
    assert a1["chi2"] == pytest.approx(0.5)
    assert a1["scale"] == 1.0
    assert a1["b_sd"] == pytest.approx(10.0 / np.sqrt(2.0))


def test_regression_recovers_the_increments_it_was_made_with():
    base, small, big = 700.0, 930.0, 10500.0
    fits = []
    for name in ("A0", "A2", "A5", "B1", "B2"):
        s = SETTINGS[name]
        fits.append(fake_fit(name, 1.0, base + s.n_small * small + s.n_big * big, 3.0))
    rows = {r["term"]: r for r in flywheel_regression(inertance_table(fits))}
    assert rows["base (A0)"]["mean"] == pytest.approx(base)
    assert rows["per small flywheel"]["mean"] == pytest.approx(small)
    assert rows["per big flywheel"]["mean"] == pytest.approx(big)
    geo = DEFAULT_GEOMETRY
    assert rows["per big flywheel"]["theory"] == pytest.approx(geo.inertance(0, 1) - geo.inertance(0, 0))
    # 10500 is far from the geometry's 11393 kg given a 3 kg sd per setting
    assert not rows["per big flywheel"]["covers_theory"]


def test_regression_needs_settings_that_separate_the_terms():
    # one setting cannot separate a base from an increment
    assert flywheel_regression(inertance_table([fake_fit("A3", 1.0, 3500.0, 5.0)])) == []
    # A0 and A1 fix base and small; no big flywheel, so no big term
    rows = flywheel_regression(inertance_table([fake_fit("A0", 1.0, 750.0, 5.0), fake_fit("A1", 1.0, 1680.0, 5.0)]))
    assert [r["term"] for r in rows] == ["base (A0)", "per small flywheel"]


def test_phi_table_sits_beside_the_paper():
    rows = phi_table([fake_fit("B2", 1.5, 20000.0, 50.0, phi=0.97)])
    assert rows[0]["phi_paper"] == pytest.approx(0.845)
    assert rows[0]["phi_mean"] == pytest.approx(0.97)


def test_regression_reports_the_generating_values():
    truth = {"A0": 750.0, "A3": 3530.0, "B2": 20300.0}
    fits = [fake_fit(n, 1.0, b + 2.0, 4.0) for n, b in truth.items()]
    rows = flywheel_regression(inertance_table(fits), truth_b=truth)
    by = {r["term"]: r for r in rows}
    assert by["base (A0)"]["truth"] == pytest.approx(750.0)
    assert by["per small flywheel"]["truth"] == pytest.approx((3530.0 - 750.0) / 3)
    assert by["per big flywheel"]["truth"] == pytest.approx((20300.0 - 750.0) / 2)
    assert all(r["covers_truth"] for r in rows)


def test_joint_table_holds_b_and_the_apparent_inertance_against_their_truths():
    from bayes_inerter.study.analysis import joint_inertance

    inert = inertance_table([fake_fit("A1", 1.0, 1000.0, 10.0), fake_fit("A2", 1.0, 2000.0, 5.0)])

    def row(name, m, s):
        return {"name": name, "mean": m, "sd": s, "hdi_3%": m - Z94 * s, "hdi_97%": m + Z94 * s, "r_hat": 1.01,
                "ess_bulk": 500.0}

    joint = [row("b_A1", 1001.0, 1.0), row("b_A2", 1990.0, 2.0), row("b_app_A1", 1003.0, 1.0),
             row("b_app_A2", 2001.0, 2.0)]
    rows = joint_inertance(joint, inert, truth_b={"A1": 1000.0, "A2": 2000.0}, truth_app={"A1": 1010.0, "A2": 2002.0})
    by = {r["setting"]: r for r in rows}
    assert by["A1"]["covers_truth"] and not by["A2"]["covers_truth"]  # 1000 in 1001 +- 1.9; 2000 not in 1990 +- 3.8
    assert not by["A1"]["covers_truth_app"] and by["A2"]["covers_truth_app"]
    assert by["A2"]["b_app_joint_mean"] == 2001.0 and by["A2"]["b_app_truth"] == 2002.0
    # a joint summary without b_app (an older run) gives the b columns only
    plain = joint_inertance(joint[:2], inert, truth_b={"A1": 1000.0, "A2": 2000.0}, truth_app={"A1": 1.0, "A2": 2.0})
    assert "b_app_joint_mean" not in plain[0] and "covers_truth" in plain[0]


def test_report_names_the_settings_whose_sd_was_widened():
    from bayes_inerter.study.report_text import how_identified

    rows = inertance_table([fake_fit("A1", 0.5, 1000.0, 10.0), fake_fit("A1", 1.0, 1030.0, 20.0),
                            fake_fit("A2", 0.5, 2000.0, 10.0), fake_fit("A2", 1.0, 2010.0, 10.0)])
    text = how_identified(rows)
    assert "Birge ratio" in text and "A1 (1.34)" in text  # sqrt(1.8)
    assert "beyond chance" not in text  # chi2 1.8 on 1 degree of freedom: p = 0.18
    assert "A2 (" not in text  # its records agree (chi2 0.5 on 1 degree of freedom)


def test_calibration_widens_b_by_the_sensors_share_of_b_plus_the_moving_mass():
    from bayes_inerter.records.sensitivity import SensorCalibration
    from bayes_inerter.study.analysis import joint_inertance

    cal = SensorCalibration(force=0.003, accel=0.004)  # u = 0.005
    fits = [fake_fit("A0", 1.0, 700.0, 2.0), fake_fit("A1", 1.0, 1000.0, 10.0), fake_fit("B1", 1.0, 10000.0, 10.0)]
    for f, m_s in zip(fits, (15.0, 20.0, 25.0)):
        f.info.update(m_s=m_s, m_B=50.0)
    rows = {r["setting"]: r for r in inertance_table(fits, calibration=cal)}
    a1 = rows["A1"]
    assert a1["moving_mass"] == 70.0
    assert a1["b_cal_sd"] == pytest.approx(np.hypot(10.0, 1070.0 * 0.005))
    assert a1["b_cal_hdi_97%"] - a1["b_median"] == pytest.approx(Z94 * a1["b_cal_sd"])
    assert a1["b_sd"] == 10.0  # the records-alone columns stay as they were
    assert "b_cal_sd" not in inertance_table(fits)[0]

    reg = {r["term"]: r for r in flywheel_regression(list(rows.values()), calibration=cal,
                                                     truth_b={"A0": 700.0, "A1": 1000.0, "B1": 10000.0})}
    small, big, base = reg["per small flywheel"], reg["per big flywheel"], reg["base (A0)"]
    # three settings, three terms: the moving masses 65, 70, 75 kg regress exactly to 65 + 5 per small flywheel
    # (A1 has one) + 10 per big one (B1 has one); each term's share is u (term + its mass term)
    assert base["cal_sd"] == pytest.approx(np.hypot(base["sd"], (base["mean"] + 65.0) * 0.005))
    assert small["cal_sd"] == pytest.approx(np.hypot(small["sd"], (small["mean"] + 5.0) * 0.005))
    assert big["cal_sd"] == pytest.approx(np.hypot(big["sd"], (big["mean"] + 10.0) * 0.005))
    assert small["covers_truth_cal"]
    # a row without a moving mass: its share is unknown, not zero
    bare = [{k: v for k, v in r.items() if k != "moving_mass"} for r in rows.values()]
    assert all(math.isnan(r["cal_sd"]) for r in flywheel_regression(bare, calibration=cal))

    joint = [{"name": "b_A1", "mean": 1030.0, "sd": 1.0, "hdi_3%": 1028.0, "hdi_97%": 1032.0, "r_hat": 1.0,
              "ess_bulk": 500.0}]
    j = joint_inertance(joint, [a1], truth_b={"A1": 1000.0}, calibration=cal)[0]
    # 30 kg off: outside both intervals (1.88 * hypot(1, 5.5) = 10.5 kg with the calibration)
    assert not j["covers_truth"] and not j["covers_truth_cal"]
    assert j["b_joint_cal_sd"] == pytest.approx(np.hypot(1.0, (1030.0 + 70.0) * 0.005))
    near = [{**joint[0], "mean": 1008.0, "hdi_3%": 1006.0, "hdi_97%": 1010.0}]
    j = joint_inertance(near, [a1], truth_b={"A1": 1000.0}, calibration=cal)[0]
    assert not j["covers_truth"] and j["covers_truth_cal"]  # 8 kg off: within 1.88 * 5.5 = 10.4 kg


def test_report_on_calibration_says_what_the_generated_records_can_check():
    from bayes_inerter.records.sensitivity import SensorCalibration
    from bayes_inerter.study.report_text import calibration_text

    fits = [fake_fit("A0", 1.0, 700.0, 2.0), fake_fit("A1", 1.0, 1000.0, 2.0)]
    for f in fits:
        f.info.update(m_s=20.0, m_B=50.0)
    rows = inertance_table(fits, calibration=SensorCalibration())
    truth = {"A0": 712.0, "A1": 1000.0}  # A0 12 kg off: 1.88 * hypot(2, 770 * 0.0056) = 8.9 kg, outside
    exact = calibration_text(rows, SensorCalibration(), truth, "b_cal_", (1.0, 1.0))
    assert "0.56 %" in exact and "records-alone intervals are the ones to hold" in exact and "of 2" not in exact
    off = calibration_text(rows, SensorCalibration(), truth, "b_cal_", (1.01, 1.0))
    assert "hold the generating b for 1 of 2 settings" in off
    assert "taken as exact" in calibration_text(rows, SensorCalibration(0.0, 0.0), truth, "b_cal_", (1.0, 1.0))
    assert calibration_text(inertance_table(fits), SensorCalibration(), truth, "b_cal_") == ""  # no b_cal columns


def test_the_calibration_is_not_added_where_every_posterior_sampled_the_gain():
    """A fit whose posterior sampled the sensors' relative gain (its summary has a gain
    row: the harmonic and motion-in likelihoods) holds the calibration already: the
    study adds it only where some two-port fit did not."""
    from bayes_inerter.records.sensitivity import SensorCalibration
    from bayes_inerter.study.analysis import added_calibration
    from bayes_inerter.study.report_text import calibration_text

    cal = SensorCalibration()
    sampled = [fake_fit("A0", 1.0, 700.0, 2.0), fake_fit("A1", 1.0, 1000.0, 2.0),
               fake_fit("A1", 1.0, 1.0, 1.0, "rigid")]
    for f in sampled[:2]:
        f.summary["gain"] = {"mean": 1.0, "sd": 0.005}
    assert added_calibration(sampled, cal) is None  # the rigid fit does not count
    assert added_calibration(sampled[:1] + [fake_fit("A1", 1.0, 1000.0, 2.0)], cal) is cal
    assert added_calibration([], cal) is cal
    rows = inertance_table(sampled, calibration=added_calibration(sampled, cal))
    assert "b_cal_sd" not in rows[0]
    text = calibration_text(rows, cal, None, "b_cal_", in_posterior=True)
    assert "samples the sensors' relative gain" in text and "0.56 %" in text and "nothing is added" in text
    assert calibration_text(rows, SensorCalibration(0.0, 0.0), None, "b_cal_", in_posterior=True) == ""


def test_report_flags_records_that_disagree_beyond_chance():
    from bayes_inerter.study.report_text import how_identified

    # 1000 +- 1 against 1010 +- 1: chi2 50 on 1 degree of freedom
    rows = inertance_table([fake_fit("A1", 0.5, 1000.0, 1.0), fake_fit("A1", 1.0, 1010.0, 1.0)])
    assert "A1 the disagreement is beyond chance" in how_identified(rows)


def test_collect_orders_fits_by_setting_and_frequency_as_numbers(tmp_path):
    import json

    from bayes_inerter.study.analysis import collect

    # folder names sort as text (A0_0.5Hz, A0_1.5Hz, A0_1Hz); the tables want 0.5, 1, 1.5 Hz
    for model, setting, freq in [("two-port", "A1", 1.0), ("two-port", "A0", 1.5), ("rigid", "A0", 1.0),
                                 ("two-port", "A0", 0.5), ("two-port", "A0", 1.0)]:
        folder = tmp_path / model / f"{setting}_{freq:g}Hz"
        folder.mkdir(parents=True)
        (folder / "summary.csv").write_text("name,mean,sd\nb,1.0,0.1\n")
        (folder / "fit.json").write_text(json.dumps(
            {"model": model, "record_metadata": {"setting": setting, "drive_frequency_hz": freq}}))
    order = [(f.model, f.name) for f in collect(tmp_path)]
    assert order == [("rigid", "A0_1Hz"), ("two-port", "A0_0.5Hz"), ("two-port", "A0_1Hz"),
                     ("two-port", "A0_1.5Hz"), ("two-port", "A1_1Hz")]


def test_report_says_how_records_were_combined_or_that_b_is_the_joint_models():
    from bayes_inerter.study.analysis import joint_estimate
    from bayes_inerter.study.report import _answer_section
    from bayes_inerter.study.report_text import combination_note

    inert = inertance_table([fake_fit("A1", 0.5, 1000.0, 10.0), fake_fit("A1", 1.0, 1010.0, 10.0),
                             fake_fit("A2", 1.0, 2000.0, 5.0)])
    alone = combination_note(inert, [])
    assert "independent normals" in alone and "--no-joint" in alone
    # one record per setting and no joint model: nothing was combined, nothing to say
    assert combination_note(inertance_table([fake_fit("A1", 1.0, 1000.0, 10.0)]), []) == ""
    rng = np.random.default_rng(1)
    draws = {"b_A1": 1004.0 + rng.normal(0, 1.0, 4000), "b_A2": 2001.0 + rng.normal(0, 1.0, 4000)}
    joint = joint_estimate(inert, draws, converged=False)
    truth = [{"setting": "A1", "b_truth": 1004.0}, {"setting": "A2", "b_truth": 2001.0}]
    text = combination_note(joint, truth)
    # the product's own list and coverage (A1 1005 +- 1.88 * 7.07: holds 1004; A2 2000 +- 9.4: holds 2001)
    assert "joint model's b's" in text and "A1 1005 kg" in text and "for 2 of 2 settings" in text
    assert "settings" not in combination_note(joint, [{"setting": "A1"}]).split("the same records give")[1]
    lead = "\n".join(_answer_section(None, joint, {}, {"A1": 1004.0, "A2": 2010.0}))
    assert "Identified: the joint model" in lead and "holds the true value for 1 of 2 settings" in lead
    assert "not converged" in lead and "Birge" not in lead


def test_joint_estimate_puts_the_joint_b_first_and_keeps_the_product_beside_it():
    from bayes_inerter.records.sensitivity import SensorCalibration
    from bayes_inerter.study.analysis import joint_estimate

    fits = [fake_fit("A1", 0.5, 1000.0, 10.0), fake_fit("A1", 1.0, 1010.0, 10.0), fake_fit("A2", 1.0, 2000.0, 5.0)]
    for f in fits:
        f.info.update(m_s=20.0, m_B=50.0)
    cal = SensorCalibration()
    inert = inertance_table(fits, calibration=cal)
    before = [dict(r) for r in inert]
    x = np.random.default_rng(2).gamma(4.0, 2.0, size=(8, 500)) + 1010.0  # skewed: median != mean
    rows = joint_estimate(inert, {"b_A1": x}, converged=True, calibration=cal)
    a1, a2 = rows
    assert inert == before  # the product's rows are left as they were
    assert a1["estimate"] == "joint" and a2["estimate"] == "records combined"
    assert a1["b_median"] == pytest.approx(np.median(x)) and a1["b_sd"] == pytest.approx(np.std(x, ddof=1))
    inside = np.mean((x >= a1["b_hdi_3%"]) & (x <= a1["b_hdi_97%"]))
    assert inside == pytest.approx(0.94, abs=0.002)
    assert a1["b_hdi_3%"] < np.quantile(x, 0.03)  # an HDI of a right-skewed posterior sits left of the central one
    assert a1["b_product_median"] == before[0]["b_median"] and a1["b_product_sd"] == before[0]["b_sd"]
    assert a1["records"] == 2 and a1["chi2"] == before[0]["chi2"]
    assert a1["b_cal_sd"] == pytest.approx(cal.inertance_sd(float(np.mean(x)), a1["b_sd"], 70.0))
    assert a2 == {**before[1], "estimate": "records combined"}


def test_regression_of_joint_draws_keeps_their_correlation():
    settings = ["A0", "A1", "A3", "B1"]
    b = np.array([750.0, 1670.0, 3530.0, 10470.0])
    rng = np.random.default_rng(3)
    n = 20000
    sd = np.array([0.5, 1.0, 2.0, 8.0])
    independent = b + sd * rng.standard_normal((n, 4))
    rows = [{"setting": s, "b_median": m, "b_sd": v} for s, m, v in zip(settings, b, sd)]
    normal = {r["term"]: r for r in flywheel_regression(rows)}
    drawn = {r["term"]: r for r in flywheel_regression(rows, draws=independent)}
    for term, r in normal.items():  # independent draws: the normal form's result, to Monte Carlo error
        assert drawn[term]["mean"] == pytest.approx(r["mean"], abs=4 * r["sd"] / np.sqrt(n))
        assert drawn[term]["sd"] == pytest.approx(r["sd"], rel=0.03)
        assert drawn[term]["hdi_97%"] - drawn[term]["hdi_3%"] == pytest.approx(2 * Z94 * r["sd"], rel=0.05)
    # one shift shared by every b (a shared nut stiffness, say): all of it is the base's, none the increments'
    shift = 3.0 * rng.standard_normal((n, 1))
    shared = b + shift + 0.01 * sd * rng.standard_normal((n, 4))
    rows = [{"setting": s, "b_median": m, "b_sd": v} for s, m, v in zip(settings, b, shared.std(axis=0))]
    normal = {r["term"]: r for r in flywheel_regression(rows)}
    drawn = {r["term"]: r for r in flywheel_regression(rows, draws=shared, truth_b=dict(zip(settings, b + 4.0)))}
    assert drawn["base (A0)"]["sd"] == pytest.approx(3.0, rel=0.03)
    assert drawn["per small flywheel"]["sd"] < 0.1 < normal["per small flywheel"]["sd"]
    # a truth shifted by 4 kg in every setting: inside the base's interval, and the increments' truth is unmoved
    assert drawn["base (A0)"]["covers_truth"]
    assert drawn["per small flywheel"]["truth"] == pytest.approx(normal["per small flywheel"]["mean"])
    with pytest.raises(ValueError, match="shape"):
        flywheel_regression(rows, draws=shared[:, :3])


def test_report_flags_a_posterior_mean_outside_its_own_interval():
    """A mean outside the 94 % HDI (the full study's A2 at 0.5 Hz: phi 0.9644 against
    0.9647-0.9652) says a few draws lie far from the rest: the report says so."""
    from bayes_inerter.study.report_text import outlying_text

    rows = [{"setting": "A2", "freq_hz": 0.5, "phi_mean": 0.9644, "phi_hdi_3%": 0.9647, "phi_hdi_97%": 0.9652},
            {"setting": "A3", "freq_hz": 1.0, "phi_mean": 0.9911, "phi_hdi_3%": 0.9911, "phi_hdi_97%": 0.9912}]
    text = outlying_text(rows)
    assert "A2 at 0.5 Hz" in text and "A3" not in text and "outside its 94 % interval" in text
    assert outlying_text(rows[1:]) == ""
