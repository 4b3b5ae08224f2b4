"""One rule for every command: an unknown name says which names are known and the one it probably
meant (one helper, :func:`tcbench.errors.unknown_name`); a command that reads a recording takes
it as its first argument, and every command with ``out=`` takes ``--out DIR``."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import PAN_CSV

from tcbench.cli import main
from tcbench.cli.help import usage
from tcbench.commands.registry import SPECS
from tcbench.sensors.recording import make_recording, write_recording

LEADERBOARDS = Path(__file__).resolve().parents[1] / "leaderboards"  # the committed boards


def _gyro(path: Path, rows: int = 400) -> Path:
    """A small gyro recording with its sidecar."""
    temp_c = 20.0 + np.linspace(0.0, 10.0, rows)
    output = 0.01 * temp_c + np.random.default_rng(0).normal(0.0, 0.01, rows)
    rec = make_recording(np.arange(rows, dtype=np.float64), temp_c, np.zeros(rows), output, sensor="gyro",
                         sample_rate_hz=1.0, device_id="d")
    write_recording(rec, path)
    return path


def _refused(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize(("argv", "meant"), [
    (["run", "optimiser=fireflyy"], "fa"),  # the name its class goes by: FireflyAlgorithm
    (["run", "optimiser=improved_firefly"], "ifa"),
    (["run", "learner=elmann"], "elman"),
    (["calibrat"], "calibrate"),
    (["simulate", "sensor=gyr"], "gyro"),
    (["simulate", "sensor=gyro", "protocol=ovn"], "oven"),
    (["simulate", "effects.hysteresiss.amplitude=0.1"], "hysteresis"),
    (["simulate", "format=parqet"], "parquet"),
    (["list", "what=optimizers"], "optimisers"),
    (["quickstart", "diagnose_effect=hysteresiss"], "hysteresis"),
    (["import", f"csv={PAN_CSV}", "sensor=gyroo", "time=time_s:s", "temperature=temp_c:degC",
      "output=gyro_x_dps:deg/s", "out=rec"], "gyro"),
    (["pages", "out=pg", f"leaderboards={LEADERBOARDS}", "boards=[paper-ifa-bpp]"], "paper-ifa-bp"),
])
def test_every_unknown_name_says_the_one_it_probably_meant(argv: list[str], meant: str, workdir: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    line = _refused(capsys, argv)
    assert line.startswith("tcbench: error: ") and "; known: " in line, line
    assert f"did you mean {meant!r}?" in line, line
    assert list(workdir.iterdir()) == []


@pytest.mark.parametrize(("temperature", "meant"), [("temp:degC", "temp_c"), ("temp_c:degc", "degC")])
def test_an_unknown_column_or_unit_of_import_says_the_one_it_probably_meant(
        temperature: str, meant: str, workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    line = _refused(capsys, ["import", str(PAN_CSV), "sensor=gyro", "time=time_s:s", f"temperature={temperature}",
                             "output=gyro_x_dps:deg/s", "out=rec", "tracking.enabled=false"])
    assert f"did you mean {meant!r}?" in line, line
    assert list(workdir.iterdir()) == []


@pytest.mark.parametrize(("args", "line"), [
    (["methods=[poly33]"], "methods: unknown method 'poly33'; known: raw, poly3, poly3_rate, bp, bp_gd, elman, "
                           "model, memoriser; did you mean 'poly3'?"),
    (["settings.selection.wald_threshhold=3"], "did you mean 'settings.selection.wald_threshold'?"),
])
def test_names_of_a_recording_command(args: list[str], line: str, workdir: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    rec = _gyro(workdir / "r.csv")
    command = "calibrate" if args[0].startswith("methods") else "diagnose"
    assert line in _refused(capsys, [command, str(rec), "tracking.enabled=false", *args])
    assert sorted(p.name for p in workdir.iterdir()) == ["r.csv", "r.json"]


def test_an_unknown_format_of_export_says_the_one_it_probably_meant(workdir: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "cal").mkdir()
    line = _refused(capsys, ["export", "calibrations=[cal]", "formats=[px5]"])
    assert line.endswith("formats: unknown format 'px5'; known: px4, ardupilot, c; did you mean 'px4'?"), line


def test_an_unknown_experiment_lists_the_experiments_of_the_store(workdir: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    from tcbench.tracking import store as tracking

    uri = f"sqlite:///{workdir / 'mlflow.db'}"
    for name in ("calibrations", "diagnoses"):
        tracking.prepare_store(uri, name)
    line = _refused(capsys, ["leaderboard", "--experiment", "calibration", "--tracking-uri", uri, "--out", "lb"])
    assert line == (f"tcbench: error: unknown experiment 'calibration' in {uri}; known: Default, calibrations, "
                    "diagnoses; did you mean 'calibrations'?")
    # one of several unknown: named too, not silently left out of the board
    line = _refused(capsys, ["leaderboard", "experiments=[calibrations,diagnosis]", f"tracking.uri={uri}", "out=lb"])
    assert "unknown experiment 'diagnosis'" in line and line.endswith("did you mean 'diagnoses'?"), line
    # a sweep over experiments: refused before its first board
    line = _refused(capsys, ["leaderboard", "-m", "experiments=calibrations,diagnosis", f"tracking.uri={uri}",
                             "out=lb/${experiments}"])
    assert "unknown experiment 'diagnosis'" in line, line
    assert not (workdir / "lb").exists()


def _keys(command: str) -> set[str]:
    return {f.name for f in dataclasses.fields(SPECS[command].schema_class())}


RECORDING_COMMANDS = [name for name, spec in SPECS.items() if "recording" in spec.inputs]
OUT_COMMANDS = [name for name in SPECS if "out" in _keys(name)]


def test_the_rule_covers_the_commands_it_is_about() -> None:
    assert {"metrics", "diagnose", "calibrate"} <= set(RECORDING_COMMANDS)
    assert {"calibrate", "diagnose", "leaderboard", "export", "simulate", "import", "metrics", "pages",
            "quickstart"} <= set(OUT_COMMANDS)


@pytest.mark.parametrize("command", RECORDING_COMMANDS)
def test_every_command_reading_a_recording_takes_it_first(command: str, workdir: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    """``tcbench diagnose FILE`` was refused ("expected key=value") where ``tcbench metrics FILE`` ran."""
    rec = _gyro(workdir / "r.csv")
    assert main([command, str(rec), "--out", "there", "--cfg", "job"]) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    assert f"recording: {rec}\n" in out and "\nout: there\n" in out, out
    assert usage(command).startswith(f"usage: tcbench {command} [RECORDING] ")


@pytest.mark.parametrize("command", OUT_COMMANDS)
def test_every_command_with_out_takes_the_out_flag(command: str, workdir: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """``tcbench calibrate --out DIR`` was refused ("unknown option") where ``leaderboard --out`` ran."""
    for argv in (["--out", "my dir"], ["--out=my dir"]):
        assert main([command, *argv, "--cfg", "job"]) == 0, capsys.readouterr().err
        assert "\nout: my dir\n" in "\n" + capsys.readouterr().out
    text = usage(command)
    assert "[--out DIR]" in text.splitlines()[0] and "\n  --out DIR    out=DIR\n" in text, text
    assert main([command, "--out"]) == 2
    assert capsys.readouterr().err.strip() == (f"tcbench: error: --out needs a value (--out DIR); "
                                               f"see `tcbench {command} --help`")
    assert list(workdir.iterdir()) == []


def test_a_command_without_out_refuses_the_out_flag(capsys: pytest.CaptureFixture[str]) -> None:
    assert _refused(capsys, ["list", "--out", "x"]) == ("tcbench: error: unknown option '--out' for tcbench list; "
                                                        "see `tcbench list --help`")


def test_a_name_is_matched_across_case_and_by_the_longer_name_its_class_goes_by() -> None:
    from tcbench.errors import class_aliases, did_you_mean

    assert did_you_mean("degc", ["degF", "degC"]) == "degC"  # difflib alone ties degF with degC
    aliases = class_aliases({"fa": "m:FireflyAlgorithm", "ifa": "m:ImprovedFireflyAlgorithm", "pso": "m:ParticleSwarm"})
    assert aliases["firefly"] == "fa" and aliases["improved_firefly"] == "ifa" and aliases["particle_swarm"] == "pso"
    assert did_you_mean("fireflyy", ["fa", "ifa", "pso"], aliases) == "fa"
    assert did_you_mean("swarm", ["fa", "ifa", "pso"], aliases) is None  # a later word alone is no name
