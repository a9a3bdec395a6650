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
    assert f"b = {info['b']:.6g} kg (least squares; 94 % interval {lo:.6g} to {hi:.6g}, hessian" in text
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
