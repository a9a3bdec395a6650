"""Tests of the ``identify`` command (bayes_inerter.cli.identify)."""

import json

import pytest

from bayes_inerter.cli import main
from bayes_inerter.records import read_record

SHORT = ["--duration", "4", "--ramp", "1"]


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    out = tmp_path_factory.mktemp("identify") / "A3.csv"
    assert main(["generate", "--setting", "A3", "--freq", "1.0", "--out", str(out), *SHORT]) == 0
    return out


def test_identify_prints_b_its_interval_and_phi_and_writes_json(record, tmp_path, capsys):
    capsys.readouterr()
    out = tmp_path / "fit.json"
    assert main(["identify", str(record), "--starts", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    info = json.loads(out.read_text())
    lo, hi = info["b_interval"]
    assert (f"b = {info['b']:.6g} kg (least squares; 94 % interval {lo:.6g} to {hi:.6g}, from the Jacobian over "
            f"{info['cycles']} drive cycles)") in text
    # the model's own record: no poor fit, and b itself within its prior; a parameter the
    # record leaves open (c_B, k_B) may end on a bound from one start on some processors,
    # and is then named, in the JSON as on the console
    warned = [line for line in text.splitlines() if line.startswith("warning: ")]
    assert all(line.split()[1] in info["at_bounds"] for line in warned), warned
    assert len(warned) == len(info["at_bounds"]) and "b" not in info["at_bounds"]
    assert f"phi = {info['phi']:.2%}" in text
    assert lo < info["b"] < hi and info["starts"] == 1 and info["interval"] == "hessian"
    # the model's own record: least squares lands within 2 % of the generating b
    assert info["b"] == pytest.approx(read_record(record).metadata["true_parameters"]["b"], rel=0.02)


@pytest.mark.parametrize("argv, message", [(["--bootstrap", "5"], "too few"), (["--out", "fit.txt"], ".json"),
                                            (["--m-s", "-1"], None)])
def test_identify_refuses_bad_options(record, capsys, argv, message):
    if message is None:  # argparse: usage error
        with pytest.raises(SystemExit) as exc:
            main(["identify", str(record), *argv])
        assert exc.value.code == 2
        return
    assert main(["identify", str(record), *argv]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error:") and message in err and "Traceback" not in err


def test_identify_refuses_an_out_it_cannot_write_and_a_negative_seed_before_fitting(record, tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    for argv, message in ((["--out", str(blocker / "fit.json")], "cannot make its folder"),
                          (["--seed", "-1"], "--seed -1")):
        assert main(["identify", str(record), *argv]) == 1
        captured = capsys.readouterr()
        assert message in captured.err and "least squares from" not in captured.out  # refused before the fit


def test_identify_warns_where_the_model_reproduces_little_of_the_record(tmp_path, capsys, monkeypatch):
    import bayes_inerter.inference.identify as identify_module
    from bayes_inerter.inference.identify import Identification

    out = tmp_path / "A0.csv"
    assert main(["generate", "--setting", "A0", "--freq", "1.0", "--out", str(out), *SHORT]) == 0
    poor = Identification({"b": 11000.0, "c_n": 1e8}, 0.23, 0.31, 1.0, 1, (9000.0, 13000.0), 0.94, (), "hessian", 4,
                          "", ("c_n",))
    monkeypatch.setattr(identify_module, "identify", lambda *a, **k: poor)
    capsys.readouterr()
    assert main(["identify", str(out)]) == 0
    text = capsys.readouterr().out
    assert "warning: the model reproduces 31% of the low-passed record" in text and "not identified" in text
    assert "warning: c_n ended on a bound of its prior" in text
    assert "c_n 1e+08 N s/m" in text and "b 1.1e+04 kg" in text
