"""Every ``tcbench`` command answers ``--help`` and ``-h`` with its usage (exit 0), the
``key=value`` commands print their composed config for ``--cfg job`` without running, and an
unknown option is one line with exit code 2. In process, so the whole file takes seconds."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml

from tcbench.cli import help as cli_help
from tcbench.cli import COMMANDS, main
from tcbench.commands.registry import SPECS

KEYVALUE = ["simulate", "metrics", "import", "diagnose", "calibrate", "export", "leaderboard", "list", "quickstart",
            "pages"]
# what the help of the other commands must name: their parameters or settings
NAMED = {
    "run": ["usage: tcbench run", "seed", "budget", "tracking", "optimiser", "examples:", "output:"],
}
# further words a key=value command's help must hold (flags kept as aliases, the sizes it runs)
ALSO = {
    "leaderboard": ["--experiment", "--sweep", "--out", "--tracking-uri", "--ecdf"],
    "quickstart": ["budget: 510", "seed: range(5)", "thermal_lag", "one after another"],
    "list": ["one after another"],
    "pages": ["one after another", "(required)", "FOLDER/STEM", "nothing outside OUT"],
}


@pytest.fixture(autouse=True)
def in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    return tmp_path


def test_every_command_is_covered() -> None:
    assert set(COMMANDS) == set(KEYVALUE) | set(NAMED)


@pytest.mark.parametrize("flag", ["--help", "-h"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_help_exits_0_and_names_the_parameters(command: str, flag: str, capsys: pytest.CaptureFixture[str],
                                               tmp_path: Path) -> None:
    assert main([command, flag]) == 0
    out = capsys.readouterr().out
    if command in KEYVALUE:
        assert out.startswith(f"usage: tcbench {command} ")
        for key, _ in cli_help.parameters(SPECS[command].schema_class()):
            if key not in cli_help.IGNORED + cli_help.HIDDEN:
                assert f"  {key}=" in out, key
        assert "--cfg job" in out and "examples:" in out and "output:" in out
        for word in ALSO.get(command, []):
            assert word in " ".join(out.split()), word
    else:
        for word in NAMED[command]:
            assert word in out, word
    assert list(tmp_path.iterdir()) == []  # help runs nothing


def test_help_wins_after_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    """``metrics PATH --help`` used to read ``--help`` as a recording ("unsupported format")."""
    assert main(["metrics", "rec.csv", "--help"]) == 0
    assert capsys.readouterr().out.startswith("usage: tcbench metrics")


def test_help_shows_the_defaults_the_command_parses() -> None:
    text = cli_help.usage("simulate")
    assert "  sensor=null " in text and "  protocol=null " in text and "tracking.experiment=simulations" in text
    assert "  recording=(required) " in cli_help.usage("diagnose") and "  out=diagnosis " in cli_help.usage("diagnose")


@pytest.mark.parametrize("command", KEYVALUE)
def test_every_parameter_has_a_meaning(command: str) -> None:
    spec = SPECS[command]
    keys = {k for k, _ in cli_help.parameters(spec.schema_class())} - set(cli_help.IGNORED + cli_help.HIDDEN)
    assert keys == set(spec.meanings())
    assert set(spec.required) <= keys


@pytest.mark.parametrize("flag", ["--help", "-h", "help"])
def test_top_level_help_lists_every_command(flag: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([flag]) == 0
    out = capsys.readouterr().out
    listed = [ln.split()[0] for ln in out.split("commands:\n", 1)[1].split("\n\n", 1)[0].splitlines()]
    assert listed == list(COMMANDS)
    assert "--help" in out and "--cfg job" in out


def test_no_arguments_prints_the_usage_with_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 2
    assert "usage: tcbench <command>" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["simulate", "seed=7", "out=sims", "sensor=gyro", "protocol=oven", "--cfg", "job"],
         {"seed": 7, "out": "sims", "sensor": "gyro", "metrics": True}),
        (["metrics", "rec.csv", "--cfg=job", "tracking.enabled=false"],
         {"recording": "rec.csv", "out": None, "tracking": {"enabled": False}}),
        (["import", "-c", "job", "csv=log.csv", "sensor=gyro", "time=t:ms", "out=imported"],
         {"csv": "log.csv", "time": "t:ms", "out": "imported", "drop": None}),
        (["diagnose", "--cfg", "job", "recording=rec.csv", "out=diag", "sensor=msra"],
         {"recording": "rec.csv", "out": "diag", "sensor": "msra", "model": None}),
    ],
)
def test_cfg_job_prints_the_composed_config_and_writes_nothing(args: list[str], expected: dict,
                                                               capsys: pytest.CaptureFixture[str],
                                                               tmp_path: Path) -> None:
    assert main(args) == 0
    cfg = yaml.safe_load(capsys.readouterr().out)
    for key, value in expected.items():
        if isinstance(value, dict):
            assert {k: cfg[key][k] for k in value} == value
        else:
            assert cfg[key] == value, key
    defaults = dict(cli_help.parameters(SPECS[args[0]].schema_class()))
    assert set(cfg) == {k.split(".")[0] for k in defaults}  # the whole config, defaults included
    assert list(tmp_path.iterdir()) == []  # no output folder, no recording, no MLflow store


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["simulate", "seed=abc", "--cfg", "job"], ["seed", "abc"]),
        (["diagnose", "colour=red", "--cfg", "job"], ["colour"]),
        (["simulate", "--cfg", "hydra"], ["--cfg hydra", "tcbench simulate", "--cfg job"]),
        (["metrics", "--cfg"], ["--cfg without a value", "tcbench metrics"]),
    ],
)
def test_cfg_job_with_a_bad_argument_is_one_line(args: list[str], words: list[str],
                                                 capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tcbench: error:") and all(w in err[0] for w in words), err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("flag", ["--bogus", "--bogus=1", "-x"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_an_unknown_option_is_one_line_exit_2(command: str, flag: str, capsys: pytest.CaptureFixture[str],
                                              tmp_path: Path) -> None:
    assert main([command, flag]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1, captured.err
    assert f"unknown option {flag.split('=')[0]!r} for tcbench {command}" in err[0]
    assert "Traceback" not in captured.err + captured.out
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("command", "arg", "words"), [
    ("list", "seed=3", ["seed"]),
    ("list", "what=tools", ["what=tools", "tasks, optimisers, learners, sensors"]),
    ("quickstart", "seeds=0", ["seeds=0", "at least 1"]),
    ("quickstart", "diagnose_effect=glitch", ["diagnose_effect=glitch", "thermal_lag"]),
    ("leaderboard", "--ecdf=yes", ["--ecdf takes no value"]),
])
def test_a_bad_parameter_is_one_line_and_runs_nothing(command: str, arg: str, words: list[str],
                                                      capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main([command, arg]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words), err
    assert list(tmp_path.iterdir()) == []


def test_list_prints_the_list_asked_for_and_sweeps_in_turn(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list", "what=learners"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("learners:") and "optimisers:" not in out and "tasks (" not in out
    assert main(["list", "-m", "what=optimisers,learners"]) == 0
    captured = capsys.readouterr()
    assert captured.out.index("optimisers:") < captured.out.index("learners:") and "tasks (" not in captured.out
    assert "job 1/2: what=optimisers" in captured.err and "job 2/2: what=learners" in captured.err


def test_leaderboard_flags_are_aliases_of_its_keys(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["leaderboard", "--cfg", "job", "--experiment", "a", "--experiment", "b, c's", "--sweep", "s1",
                 "--out=lb", "--tracking-uri", "sqlite:///x.db", "--ecdf"]) == 0
    flagged = yaml.safe_load(capsys.readouterr().out)
    assert main(["leaderboard", "--cfg", "job", "experiments=[a,'b, c\\'s']", "sweep=s1", "out=lb",
                 "tracking.uri=sqlite:///x.db", "ecdf=true"]) == 0
    keyed = yaml.safe_load(capsys.readouterr().out)
    assert flagged == keyed
    assert flagged["experiments"] == ["a", "b, c's"] and flagged["sweep"] == "s1" and flagged["ecdf"] is True
    assert flagged["tracking"]["uri"] == "sqlite:///x.db" and flagged["tracking"]["enabled"] is False


def test_quickstart_sweep_refuses_two_quickstarts_in_one_folder(capsys: pytest.CaptureFixture[str],
                                                                 tmp_path: Path) -> None:
    assert main(["quickstart", "-m", "diagnose_effect=thermal_lag,hysteresis"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "jobs 1 and 2" in err[0] and "out=" in err[0], err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", KEYVALUE)
def test_a_sweep_with_a_bad_value_is_one_line_before_any_job(command: str, capsys: pytest.CaptureFixture[str],
                                                             tmp_path: Path) -> None:
    """``-m`` sweeps through Hydra's launcher; every job is checked before the first starts."""
    assert main([command, "-m", "colour=red,blue"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "colour" in err[0], err
    assert list(tmp_path.iterdir()) == []


def test_help_command_shows_a_command_s_usage(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["help", "diagnose"]) == 0
    assert capsys.readouterr().out.startswith("usage: tcbench diagnose")


def test_leaderboard_flag_values_keep_backslashes_and_quotes(capsys: pytest.CaptureFixture[str]) -> None:
    """Hydra's grammar escapes a backslash only before a quote: ``a\\b`` stays one backslash."""
    assert main(["leaderboard", "--cfg", "job", "--experiment", "a\\b", "--experiment", "c'd\\"]) == 0
    assert yaml.safe_load(capsys.readouterr().out)["experiments"] == ["a\\b", "c'd\\"]


class _ClosedPipe:
    """A stdout whose reader has gone (``tcbench --help | head -1``): writing raises BrokenPipeError."""

    def __init__(self, fd: int) -> None:
        self._fd = fd

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        return self._fd


@pytest.mark.parametrize("argv", [["--help"], ["list"], ["help", "run"]])
def test_output_into_a_closed_pipe_is_no_error(argv, monkeypatch, tmp_path, capfd):
    with open(tmp_path / "stdout", "w") as real:
        monkeypatch.setattr(sys, "stdout", _ClosedPipe(real.fileno()))
        assert main(argv) == 0
    assert "Traceback" not in capfd.readouterr().err
