"""The joint model: one b per setting, shared frictions and deformations, sigma marginalised."""

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy import integrate

from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.sampling.coordinates import default_coordinates
from bayes_inerter.inference import fit as fit_module
from bayes_inerter.inference.fit import ALL_DRAWS_FILE, DRAWS_FILE, fit_joint
from bayes_inerter.inference.posterior.joint import JointModel, ar1_marginal
from bayes_inerter.inference.sampling.identity import run_identity
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.records import GeneratorSettings, generate_record

SHORT = GeneratorSettings(duration=2.0, ramp=0.6)
#: The time-domain likelihood whose sigma the joint model marginalises and whose rho it
#: shares per frequency, named because it is no longer the default (the 2 s records
#: also hold too few drive periods for the harmonic ones).
AR1 = LikelihoodSettings(residual="ar1")


@pytest.fixture(scope="module")
def records():
    grid = [("A0", 1.0, 1), ("A2", 1.0, 2), ("A2", 1.5, 3)]
    return [generate_record(paper_parameters(s), f, settings=SHORT, rng=seed, setting_name=s) for s, f, seed in grid]


@pytest.mark.parametrize("rho", [0.0, 0.6, -0.3])
def test_marginal_equals_the_integral_over_sigma(rho, records):
    """The closed form against quadrature of the single-record likelihood times 1/sigma."""
    part = PosteriorModel(records[0], likelihood=AR1)
    r = np.random.default_rng(1).normal(size=60) * 0.02

    def integrand(log_sigma):  # d log sigma = d sigma / sigma: the 1/sigma prior
        return math.exp(part.pointwise_loglik(r, math.exp(log_sigma), rho).sum())

    value, _ = integrate.quad(integrand, math.log(1e-4), math.log(10.0), points=[math.log(0.02)], limit=200)
    assert ar1_marginal(r, rho) == pytest.approx(math.log(value), abs=1e-8)


def test_names_and_each_records_parameters(records):
    jm = JointModel(records, likelihood=AR1)
    assert jm.names == ["b_A0", "b_A2", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "c_B", "k_B",
                        "rho_1Hz", "rho_1.5Hz"]
    rho = {1.0: 0.3, 1.5: 0.5}
    centres = []
    for rec in records:
        pm = PosteriorModel(rec, likelihood=AR1)
        centres.append(pm.values(pm.to_theta(paper_parameters(rec.metadata["setting"]), 1.0,
                                             rho[rec.drive_frequency])))
    theta = jm.start(centres)
    for k, rec in enumerate(records):  # the joint theta gives each record its own setting's b and frequency's rho
        pm = jm.parts[k]
        expected = pm.to_theta(paper_parameters(rec.metadata["setting"]), 1.0, rho[rec.drive_frequency])
        np.testing.assert_allclose(jm.part_theta(theta, k), expected, rtol=1e-12, atol=1e-12)
    lp, phi = jm.log_prob(theta)
    by_hand = jm.log_prior(theta)
    for k, part in enumerate(jm.parts):
        _, _, sim = part.evaluate(jm.part_theta(theta, k))
        by_hand += ar1_marginal(sim[part.grid] - part.observed, jm.part_theta(theta, k)[-1])
    assert lp == pytest.approx(by_hand, rel=1e-12) and 0.9 < phi <= 1.0
    # a wrong b for one setting costs likelihood
    off = theta.copy()
    off[1] += math.log(1.1)
    assert jm.log_prob(off)[0] < lp - 10


def test_pooled_log_prob_is_the_log_prob_bit_for_bit(records):
    from bayes_inerter.inference.posterior.joint import pooled_log_prob
    from bayes_inerter.inference.sampling.optimize import local_optimum

    jm = JointModel(records, likelihood=AR1)
    parts = [PosteriorModel(r, likelihood=AR1) for r in records]
    centres = [pm.values(pm.to_theta(paper_parameters(r.metadata["setting"]), 1.0, 0.3))
               for pm, r in zip(parts, records)]
    theta = jm.start(centres)
    rng = np.random.default_rng(5)
    points = [theta, theta + 0.05 * rng.normal(size=jm.ndim), np.full(jm.ndim, 1e9)]  # the last outside the prior
    with pooled_log_prob(jm, 2) as pooled:
        got = [pooled(t) for t in points]
        searched = local_optimum(jm, theta, maxiter=40, log_prob=pooled)
    for t, (lp, phi) in zip(points, got):
        want = jm.log_prob(t)
        assert lp == want[0] and (phi == want[1] or (math.isnan(phi) and math.isnan(want[1])))
    assert got[2][0] == -math.inf
    # the search takes the same path either way
    plain = local_optimum(jm, theta, maxiter=40)
    assert np.array_equal(searched[0], plain[0]) and searched[1] == plain[1]
    with pooled_log_prob(jm, 1) as plain_lp:
        assert plain_lp == jm.log_prob


def test_refuses_what_it_cannot_use(records):
    with pytest.raises(ValueError, match="at least two"):
        JointModel(records[:1])
    bare = dataclasses.replace(records[0], metadata={k: v for k, v in records[0].metadata.items() if k != "setting"})
    with pytest.raises(ValueError, match="flywheel setting"):
        JointModel([bare, records[1]])
    with pytest.raises(ValueError, match="one median per record"):
        JointModel(records, likelihood=AR1).start([{}])


def test_checkpoint_identity_depends_on_every_record(records):
    def identity(model, coords=None):
        return run_identity(model, coords, None, [], 16)

    a, b = JointModel(records, likelihood=AR1), JointModel([records[0], records[1]], likelihood=AR1)
    assert identity(a) != identity(b)
    assert identity(a) == identity(JointModel(records, likelihood=AR1))
    # a chain walked in other coordinates is another chain
    assert identity(a, default_coordinates(a)) != identity(a)


@pytest.mark.slow
def test_fit_joint_writes_its_files_and_continues(records, tmp_path, monkeypatch):
    centres = []
    for rec in records:
        pm = PosteriorModel(rec, likelihood=AR1)
        centres.append(pm.values(pm.to_theta(paper_parameters(rec.metadata["setting"]), 1.0, 0.3)))
    res = fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=6, plots=False)
    assert res.iterations == 6 and not res.converged
    assert (tmp_path / "joint" / "summary.csv").is_file() and (tmp_path / "joint" / "fit.json").is_file()
    info = json.loads((tmp_path / "joint" / "fit.json").read_text())
    # each setting's b walked as its apparent mass at the records' median frequency
    assert info["coordinates"].startswith("impedance (M x2 at "), info["coordinates"]
    names = [r["name"] for r in res.summary]
    assert names[:2] == ["b_A0", "b_A2"] and "phi" in names
    # each record's own force ratio, and a friction-dominated one warned on its setting's b
    from bayes_inerter.inference.summaries.end_state import FRICTION_DOMINATED, FRICTION_RATIO
    from bayes_inerter.records.reactance import drive_impedance
    jm = JointModel(records, likelihood=AR1)
    ratios = {f"{s} {f:g} Hz": drive_impedance(r, f).ratio for s, f, r in zip(jm.setting_of, jm.freq_of, records)}
    assert info["records"] == list(ratios)
    assert {k: v["ratio"] for k, v in info["drive_impedance"].items()} == pytest.approx(ratios)
    warned = {w.name for w in res.warnings if w.flag == FRICTION_DOMINATED}
    assert warned == {f"b_{label.split()[0]}" for label, ratio in ratios.items() if ratio < FRICTION_RATIO}
    assert {"b_app_A0", "b_app_A2"} <= set(names)  # the inertance each setting shows through the nut
    walkers = res.draws["b_A0"].shape[0]
    monkeypatch.setattr(fit_module, "JOINT_DRAWS_KEPT", walkers)  # one draw a walker: the 9-step chain keeps more
    again = fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=9, plots=False,
                      all_draws=True)
    assert again.iterations == 9  # continued the checkpoint, not started over
    with np.load(tmp_path / "joint" / DRAWS_FILE) as saved:  # thinned evenly to the cap, every walker kept
        assert saved["b_A0"].shape == (walkers, 1)
        assert np.array_equal(saved["b_A0"], again.draws["b_A0"])
    monkeypatch.undo()
    with np.load(tmp_path / "joint" / ALL_DRAWS_FILE) as every:  # every sampled parameter, b's as b_draws.npz's
        assert set(every.files) == set(JointModel(tuple(records), likelihood=AR1).names)
        assert np.array_equal(every["b_A0"], again.draws["b_A0"])
    # the sampling time of the chain adds up over the two runs that built it
    assert again.timings["sampling_all_runs"] == pytest.approx(res.timings["sampling"] + again.timings["sampling"])
    assert again.timings["steps_timed"] == 9
    # a run killed before it wrote fit.json leaves steps in the chain that nobody timed:
    # the next run times only its own, so seconds per step stay right
    (tmp_path / "joint" / "fit.json").unlink()
    third = fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=11, plots=False)
    assert third.iterations == 11 and third.draws["b_A0"].shape[1] > 1  # the default cap keeps them all
    assert third.timings["steps_timed"] == 2
    assert third.timings["sampling_all_runs"] == third.timings["sampling"]
    # a chain started over beside the fit.json of a longer, older chain (the new chain's first
    # run killed before it wrote its own): the old fit.json's time is not this chain's
    old = json.loads((tmp_path / "joint" / "fit.json").read_text())
    for name in ("chain.h5", "chain.twin.h5"):
        (tmp_path / "joint" / name).unlink()
    fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=4, plots=False)
    (tmp_path / "joint" / "fit.json").write_text(json.dumps(old))  # as if the 4-step run had been killed
    fourth = fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=7, plots=False)
    assert fourth.iterations == 7 and fourth.timings["steps_timed"] == 3
    assert fourth.timings["sampling_all_runs"] == fourth.timings["sampling"]


def _centres(records, shares):
    out = []
    for rec, share in zip(records, shares):
        pm = PosteriorModel(rec, likelihood=AR1)
        centre = pm.values(pm.to_theta(paper_parameters(rec.metadata["setting"]), 1.0, 0.3))
        out.append({**centre, "f_share": share})
    return out


def test_start_candidates_one_per_record_up_to_record_starts(records):
    from bayes_inerter.inference.posterior import joint

    assert len(records) <= joint.RECORD_STARTS
    jm = JointModel(records, likelihood=AR1)
    i = jm.names.index("f_share")
    close = _centres(records, (0.30, 0.35, 0.38))
    first, *each = jm.start_candidates(close)
    np.testing.assert_array_equal(first, jm.start(close))
    # each record's own, but the median record's, which is the first (the records share
    # every other shared parameter here)
    assert [t[i] for t in each] == pytest.approx([0.30, 0.38])
    shared = [k for k, n in enumerate(jm.names) if n in jm.shared]
    others = [k for k in range(jm.ndim) if k not in shared]
    for t in each:
        np.testing.assert_array_equal(t[others], first[others])  # b and rho as in the first
    same = _centres(records, (0.3, 0.3, 0.3))
    assert len(jm.start_candidates(same)) == 1  # records alike give one start, not four copies


def test_start_candidates_beyond_record_starts_one_per_group_of_the_friction_split(records, monkeypatch):
    from bayes_inerter.inference.posterior import joint

    monkeypatch.setattr(joint, "RECORD_STARTS", len(records) - 1)
    jm = JointModel(records, likelihood=AR1)
    i = jm.names.index("f_share")
    close = _centres(records, (0.30, 0.35, 0.38))
    assert len(jm.start_candidates(close)) == 1
    np.testing.assert_array_equal(jm.start_candidates(close)[0], jm.start(close))
    apart = _centres(records, (0.62, 0.15, 0.2))
    first, low, high = jm.start_candidates(apart)
    np.testing.assert_array_equal(first, jm.start(apart))
    assert first[i] == pytest.approx(0.2)  # the median lies in the group of two
    assert low[i] == pytest.approx(0.175) and high[i] == pytest.approx(0.62)  # each group's own
    shared = [k for k, n in enumerate(jm.names) if n in jm.shared]
    others = [k for k in range(jm.ndim) if k not in shared]
    np.testing.assert_array_equal(low[others], first[others])
    np.testing.assert_array_equal(high[others], first[others])


@pytest.mark.slow
def test_fit_joint_starts_at_the_polished_optimum_and_only_once(records, tmp_path, monkeypatch):
    from bayes_inerter.inference.sampling import optimize

    centres = []
    for rec in records:
        pm = PosteriorModel(rec, likelihood=AR1)
        centres.append(pm.values(pm.to_theta(paper_parameters(rec.metadata["setting"]), 1.0, 0.3)))
    seen = []
    real = optimize.local_optimum

    def spy(model, theta, **kwargs):
        out = real(model, theta, **kwargs)
        seen.append((model.log_prob(theta)[0], out[1], kwargs.get("restarts")))
        return out

    monkeypatch.setattr(optimize, "local_optimum", spy)
    fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=3, plots=False)
    assert len(seen) == 1
    lp_centres, lp_start, restarts = seen[0]
    assert restarts == optimize.NM_RESTARTS and lp_start >= lp_centres
    fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=5, plots=False)
    assert len(seen) == 1  # a continued chain does not look for a start again


@pytest.mark.slow
def test_fit_joint_polishes_the_best_of_one_pass_from_each_candidate(records, tmp_path, monkeypatch):
    from bayes_inerter.inference.sampling import optimize

    centres = _centres(records, (0.7, 0.2, 0.25))
    jm = JointModel(records, likelihood=AR1)
    candidates = jm.start_candidates(centres)
    assert len(candidates) == 3  # the median (record 3's own) and records 1 and 2's own
    seen = []
    real = optimize.local_optimum

    def spy(model, theta, **kwargs):
        out = real(model, theta, **kwargs)
        seen.append((np.array(theta, dtype=float), out, kwargs.get("restarts", 0)))
        return out

    monkeypatch.setattr(optimize, "local_optimum", spy)
    fit_joint(records, tmp_path / "joint", likelihood=AR1, centres=centres, steps=3, plots=False)
    assert len(seen) == 4
    for (start, _, restarts), candidate in zip(seen[:3], candidates):
        np.testing.assert_array_equal(start, candidate)
        assert restarts == 0
    best = max(seen[:3], key=lambda s: s[1][1])[1][0]
    np.testing.assert_array_equal(seen[3][0], best)  # the best pass is polished
    assert seen[3][2] == optimize.NM_RESTARTS


def test_the_motion_likelihoods_reference_is_each_records_part_of_the_joint_one():
    """Under the motion-in likelihood (its normaliser's noise at a reference point) the
    joint model takes each record's reference at its own part of the joint theta: its
    log-likelihood is then the sum of the referenced records' (the parameters' own
    normaliser's only at the reference), and the run's identity keeps the joint reference."""
    settings = GeneratorSettings(duration=5.5, ramp=0.5)  # three steady periods after the first
    recs = [generate_record(paper_parameters(s), f, settings=settings, rng=seed, setting_name=s)
            for s, f, seed in [("A0", 1.0, 5), ("A2", 1.5, 6)]]
    # the input noise's draws, taken at the reference alone, left out: they would make
    # the two normalisers differ at the reference too
    jm = JointModel(tuple(recs), likelihood=LikelihoodSettings(input_noise=0))
    assert jm.needs_reference
    medians = []
    for part, s in zip(jm.parts, ("A0", "A2")):
        p = dataclasses.replace(paper_parameters(s), c_B=2 * 0.02 * math.sqrt(paper_parameters(s).k_B * part.m_B))
        medians.append(part.values(part.to_theta(p, hyper={"tau": 1.0})))
    theta = jm.start(medians)
    ref = jm.with_reference(theta)
    assert not ref.needs_reference and ref.reference == tuple(theta) and ref.names == jm.names
    for k, part in enumerate(ref.parts):
        assert part.reference == tuple(jm.part_theta(theta, k)) and part.reference_noise is not None
    parts = sum(part.log_likelihood(ref.part_theta(theta, k))[0] for k, part in enumerate(ref.parts))
    assert ref.log_prob(theta)[0] == pytest.approx(ref.log_prior(theta) + parts, rel=1e-12)
    # at the reference itself the two normalisers agree; away from it they differ
    assert ref.log_prob(theta)[0] == pytest.approx(jm.log_prob(theta)[0], rel=1e-12)
    moved = np.array(theta, dtype=float)
    moved[jm.names.index("b_A0")] += math.log(1.05)
    assert ref.log_prob(moved)[0] != pytest.approx(jm.log_prob(moved)[0], abs=1e-6)
    assert ref.with_reference(theta).reference == ref.reference
    identity = run_identity(ref, default_coordinates(ref), None, [], 24)
    assert identity["reference"] == list(theta)
    with pytest.raises(ValueError, match="the reference has 3 parameters"):
        JointModel(tuple(recs), reference=(1.0, 2.0, 3.0))
    ar1 = JointModel(tuple(recs), likelihood=AR1)
    assert not ar1.needs_reference and ar1.with_reference(ar1.bounds().mean(axis=1)) is ar1


@pytest.mark.slow
def test_the_joint_fit_takes_the_input_noises_draws_by_default():
    """``LikelihoodSettings.input_noise`` None: each record of a joint fit takes the
    default's draws, as a record fitted alone does; a number given holds for both."""
    from bayes_inerter.inference.posterior.likelihood import INPUT_NOISE_DRAWS

    settings = GeneratorSettings(duration=5.5, ramp=0.5)
    recs = [generate_record(paper_parameters(s), f, settings=settings, rng=seed, setting_name=s)
            for s, f, seed in [("A0", 1.0, 5), ("A2", 1.5, 6)]]
    jm = JointModel(tuple(recs))
    assert jm.likelihood.input_noise is None
    assert [p.likelihood.input_noise for p in jm.parts] == [INPUT_NOISE_DRAWS] * 2
    assert PosteriorModel(recs[0]).likelihood.input_noise_draws() == INPUT_NOISE_DRAWS
    fixed = JointModel(tuple(recs), likelihood=LikelihoodSettings(input_noise=3))
    assert [p.likelihood.input_noise for p in fixed.parts] == [3, 3]


def test_fit_joint_under_the_motion_likelihood_keeps_its_reference_and_continues(tmp_path):
    from bayes_inerter.inference.sampling.checkpoint import stored_identity

    settings = GeneratorSettings(duration=5.5, ramp=0.5)
    recs = [generate_record(paper_parameters(s), f, settings=settings, rng=seed, setting_name=s)
            for s, f, seed in [("A0", 1.0, 5), ("A2", 1.5, 6)]]
    centres = []
    for rec in recs:
        pm, s = PosteriorModel(rec), rec.metadata["setting"]
        p = dataclasses.replace(paper_parameters(s), c_B=2 * 0.02 * math.sqrt(paper_parameters(s).k_B * pm.m_B))
        centres.append(pm.values(pm.to_theta(p, hyper={"tau": 1.0})))
    first = fit_joint(recs, tmp_path / "j", centres=centres, steps=6, plots=False)
    kept = stored_identity(tmp_path / "j" / "chain.h5")["reference"]
    assert first.iterations == 6 and len(kept) == JointModel(tuple(recs)).ndim
    again = fit_joint(recs, tmp_path / "j", centres=centres, steps=9, plots=False)
    assert again.iterations == 9  # continued under the same reference
    assert stored_identity(tmp_path / "j" / "chain.h5")["reference"] == kept
