"""A study's command line made from its Config and run (``cli.study_script``)."""

import json
import types
from dataclasses import dataclass, field

import pytest

from bayes_inerter.cli.status import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE
from bayes_inerter.cli.study_script import config_from_folder, study_main
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.study.output import StudyOutput


@dataclass(frozen=True)
class Config:
    replicates: int = field(default=3, metadata={"help": "how many"})
    freqs: tuple[float, ...] = (0.5, 1.5)
    method: str = field(default="a", metadata={"choices": ("a", "b")})
    quick: bool = False
    cap: int | None = None
    generator: GeneratorSettings = field(default_factory=GeneratorSettings)  # not on the command line

    def __post_init__(self):
        if self.replicates < 1:
            raise ValueError(f"replicates must be at least 1, got {self.replicates}")


def fake_study(behaviour=None):
    """A study module whose run records what it was given and does ``behaviour``."""
    seen = {}

    def run(config, out, executor, *, progress=None):
        seen.update(config=config, out=out, workers=getattr(executor, "workers", 1))
        for k in range(config.replicates):
            progress(k + 1, config.replicates)
        if behaviour == "interrupt":
            raise KeyboardInterrupt
        if behaviour == "refuse":
            raise ValueError(f"{out} holds another study's work; choose another folder")
        (out / "table.csv").write_text("x\n1\n")
        failed = (("replicate 2", "simulator refused"),) if behaviour == "fail" else ()
        return StudyOutput(written=(out / "table.csv",), failed=failed, lines=("mean 1.0",))

    module = types.ModuleType("bayes_inerter.study.fake")
    module.Config, module.run = Config, run
    return module, seen


def test_every_simple_field_is_an_option_and_the_config_is_built_from_them(tmp_path, capsys):
    module, seen = fake_study()
    code = study_main(module, out=tmp_path / "default", argv=[
        "--replicates", "2", "--freqs", "1", "2", "3", "--method", "b", "--quick", "--cap", "7",
        "--out", str(tmp_path / "here"), "--processes", "1"])
    assert code == EXIT_OK
    assert seen["config"] == Config(replicates=2, freqs=(1.0, 2.0, 3.0), method="b", quick=True, cap=7)
    assert seen["out"] == tmp_path / "here"
    printed = capsys.readouterr().out
    assert "mean 1.0" in printed and f"wrote {tmp_path / 'here' / 'table.csv'}" in printed
    manifest = json.loads((tmp_path / "here" / "manifest.json").read_text())
    (entry,) = manifest["runs"]
    assert entry["configuration"]["study"] == "fake" and entry["configuration"]["config"]["freqs"] == [1.0, 2.0, 3.0]


def test_a_folders_run_gives_back_the_config_it_was_given(tmp_path):
    """config_from_folder reads a run's configuration from the manifest as the command
    line gave it (lists back to tuples); a field the run predates is at its default."""
    module, seen = fake_study()
    out = tmp_path / "here"
    assert study_main(module, out=out, argv=["--freqs", "1", "2", "--method", "b", "--cap", "7", "--out", str(out),
                                             "--processes", "1"]) == EXIT_OK
    assert config_from_folder(Config, out) == seen["config"] == Config(freqs=(1.0, 2.0), method="b", cap=7)
    manifest = json.loads((out / "manifest.json").read_text())
    del manifest["runs"][0]["configuration"]["config"]["cap"]  # as if the run predated the option
    (out / "manifest.json").write_text(json.dumps(manifest))
    assert config_from_folder(Config, out) == Config(freqs=(1.0, 2.0), method="b")


def test_defaults_are_the_configs_own(tmp_path):
    module, seen = fake_study()
    assert study_main(module, out=tmp_path / "d", argv=["--processes", "1"]) == EXIT_OK
    assert seen["config"] == Config() and seen["out"] == tmp_path / "d"


def test_help_lists_the_fields_with_their_defaults_not_the_nested_ones(capsys):
    module, _ = fake_study()
    with pytest.raises(SystemExit) as end:
        study_main(module, out="x", argv=["--help"])
    assert end.value.code == 0
    text = capsys.readouterr().out
    assert "--replicates" in text and "how many (default: 3)" in text and "--no-quick" in text
    assert "--generator" not in text


@pytest.mark.parametrize("argv, cause", [
    (["--replicates", "0"], "replicates must be at least 1"),
    (["--processes", "0"], "processes must be a whole number"),
])
def test_a_bad_value_is_one_line_with_its_cause_and_exit_2(tmp_path, capsys, argv, cause):
    module, seen = fake_study()
    assert study_main(module, out=tmp_path / "o", argv=argv) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("error: ") and cause in err[-1] and "Traceback" not in "".join(err)
    assert not seen and not (tmp_path / "o").exists()  # nothing ran, nothing written


def test_a_choice_outside_the_fields_choices_is_refused_by_the_parser(tmp_path):
    module, _ = fake_study()
    with pytest.raises(SystemExit) as end:
        study_main(module, out=tmp_path, argv=["--method", "c"])
    assert end.value.code == EXIT_USAGE


@pytest.mark.parametrize("behaviour, code, said", [
    ("fail", EXIT_FAIL, "failed: replicate 2: simulator refused"),
    ("refuse", EXIT_USAGE, "error: "),
    ("interrupt", EXIT_INTERRUPTED, "interrupted: what finished is kept"),
])
def test_exit_codes_say_how_the_study_ended(tmp_path, capsys, behaviour, code, said):
    module, _ = fake_study(behaviour)
    assert study_main(module, out=tmp_path / "o", argv=["--processes", "1"]) == code
    assert said in capsys.readouterr().err


def test_a_continued_run_shows_what_it_found_done_from_its_first_line(tmp_path, capsys):
    """A study that finds 2 of 3 replicates done reports (2, 3) first: the bar's first
    line, which off a terminal stays up until the next item ends, says 2/3, not 0/3."""
    module = types.ModuleType("bayes_inerter.study.fake")

    def run(config, out, executor, *, progress=None):
        progress(2, 3)
        (out / "table.csv").write_text("x\n1\n")
        return StudyOutput(written=(out / "table.csv",), failed=(), lines=())

    module.Config, module.run = Config, run
    assert study_main(module, out=tmp_path / "here", argv=["--processes", "1"]) == EXIT_OK
    err = capsys.readouterr().err
    assert "2/3" in err and "0/3" not in err
