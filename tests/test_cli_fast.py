"""``tcbench <command> --help`` and the common one-line errors answer without importing what is
slow (MLflow, the launchers' libraries, the plotting and data libraries, the task modules; the
help not even Hydra), an unknown key or option gets the known one it probably meant, a SLURM
sweep on a machine without SLURM is one line that creates nothing, and ``tcbench simulate``
without a protocol runs its sensor kind's default. What the answers cost in time is measured
in benchmarks/cli_latency.py."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tcbench.cli import COMMANDS, main
from tcbench.cli import help as cli_help

# what no --help and no one-line error below may import (a prefix ending in "." spares the package itself)
SLOW = ("mlflow", "matplotlib", "scipy", "pandas", "pyarrow", "torch", "sklearn", "submitit", "joblib", "ruptures",
        "pywt", "ioh", "tcbench.tasks.msra_env", "tcbench.tasks.gyro_env", "tcbench.tasks.gyro_vmd_env",
        "tcbench.tasks.bbob_env", "tcbench.sensors", "tcbench.diagnose", "tcbench.compensation",
        "tcbench.metrics.report", "tcbench.runner.kinds.", "tcbench.runner.config", "tcbench.tracking.store",
        "tcbench.leaderboard")
# and what --help does not need either: the help is built from the schemas
NOT_FOR_HELP = ("hydra", "omegaconf", "hydra_plugins")
# but the diagnosis's settings are plain dataclasses of the standard library: diagnose's schema holds them;
# and the registry of sensor kinds (the standard library too) names the default kind the schemas give
LIGHT = ("tcbench.diagnose", "tcbench.diagnose.settings", "tcbench.sensors", "tcbench.sensors.kinds")

ERRORS = [  # (command line, what its one line says)
    (["run", "bogus=1"], "bogus: no such config key"),
    (["run", "optimizer=fa"], "did you mean 'optimiser'?"),
    (["run", "seed=abc"], "seed: Value 'abc'"),
    (["run", "-m", "optimiser=fa,ifa", "budget=x"], "budget: Value 'x'"),
    (["simulate", "sede=1"], "did you mean 'seed'?"),
    (["simulate", "seed=abc"], "seed: Value 'abc'"),
    (["metrics", "nope.csv"], "nope.csv: no such file"),
    (["diagnose", "recording=nope.csv"], "nope.csv: no such file"),
    (["diagnose", "recording=nope.csv", "model=m.yaml"], "nope.csv: no such file"),
    (["calibrate", "nope.csv"], "nope.csv: no such file"),
    (["calibrate", "-m", "recording=nope.csv,nix.csv", "out=cal/${seed}"], "nope.csv: no such file"),
    (["import", "csv=nope.csv", "sensor=gyro", "time=t", "temperature=T", "output=o", "out=x"],
     "nope.csv: no such file"),
    (["leaderboard", "experiment=x"], "did you mean 'experiments'?"),
    (["list", "wat=tasks"], "did you mean 'what'?"),
    (["quickstart", "seed=3"], "did you mean 'seeds'?"),
]

PROBE = """
import contextlib, io, json, sys
from tcbench.cli import main
out = []
for argv in json.loads(sys.argv[1]):
    before = set(sys.modules)
    with contextlib.redirect_stdout(io.StringIO()) as o, contextlib.redirect_stderr(io.StringIO()) as e:
        code = main(argv)
    out.append({"code": code, "out": o.getvalue(), "err": e.getvalue(), "new": sorted(set(sys.modules) - before)})
print(json.dumps({"calls": out, "modules": sorted(sys.modules)}))
"""


def probe(argvs: list[list[str]], cwd: Path) -> dict:
    """Run ``main(argv)`` for each command line in one fresh interpreter; what each printed and
    returned, the modules each imported, and every module loaded at the end."""
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"}
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(argvs)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def slow(modules: list[str], prefixes: tuple[str, ...]) -> list[str]:
    """The modules a prefix names: the module and its submodules, or with a trailing dot only its
    submodules; the :data:`LIGHT` ones spared."""
    def named(module: str, prefix: str) -> bool:
        if prefix.endswith("."):
            return module.startswith(prefix)
        return module == prefix or module.startswith(prefix + ".")

    return [m for m in modules if any(named(m, p) for p in prefixes) and m not in LIGHT]


def test_help_of_every_command_imports_nothing_slow(tmp_path: Path) -> None:
    """``simulate --help`` imported Hydra, the runner's checks and with them SciPy, pandas and
    Matplotlib (5.6-6.6 s); every --help is now built from the schemas."""
    result = probe([[command, flag] for command in COMMANDS for flag in ("--help", "-h")], tmp_path)
    for (command, flag), call in zip([(c, f) for c in COMMANDS for f in ("--help", "-h")], result["calls"],
                                     strict=True):
        assert call["code"] == 0 and call["out"].startswith(f"usage: tcbench {command} "), (command, flag, call)
        assert slow(call["new"], SLOW + NOT_FOR_HELP) == [], (command, flag)
    assert slow(result["modules"], SLOW + NOT_FOR_HELP) == []
    assert list(tmp_path.iterdir()) == []


def test_the_common_one_line_errors_import_nothing_slow(tmp_path: Path) -> None:
    """An unknown key, a bad value and a missing input file are found before MLflow, the
    launchers' libraries or the readers of the input are imported."""
    result = probe([argv for argv, _ in ERRORS], tmp_path)
    for (argv, words), call in zip(ERRORS, result["calls"], strict=True):
        lines = call["err"].strip().splitlines()
        assert call["code"] == 2 and len(lines) == 1 and lines[0].startswith("tcbench: error:"), (argv, call["err"])
        assert words in lines[0], (argv, lines[0])
        assert slow(call["new"], SLOW) == [], argv
    assert slow(result["modules"], SLOW) == []
    assert list(tmp_path.iterdir()) == []


def test_run_help_lists_every_key_of_its_schema_and_every_group_option() -> None:
    from tcbench.config_dir import group_options
    from tcbench.runner.schema import JobConfig

    text = cli_help.run_usage()
    for key, _ in cli_help.parameters(JobConfig):
        assert f"  {key}=" in text, key
    for group in ("task", "optimiser", "learner", "experiment"):
        line = next(ln for ln in text.splitlines() if ln.startswith(f"{group}: "))
        assert line.split(": ", 1)[1].split(", ") == group_options(group) and len(group_options(group)) > 2
    assert "  task=rastrigin " in text and "    task.dim=2" in text and "  optimiser=ifa " in text
    assert "    optimiser.population=10" in text and "  seed=0 " in text and "  tracking.experiment=tcbench " in text


@pytest.mark.parametrize(("argv", "line"), [
    (["run", "optimizer=fa"], "optimizer: no such config key; did you mean 'optimiser'?"),
    (["run", "optimizer.population=3"], "optimizer: no such config key; did you mean 'optimiser'?"),
    (["run", "-m", "optimizer=fa,ifa"], "optimizer: no such config key; did you mean 'optimiser'?"),
    (["run", "tracking.experimnt=x"], "tracking.experimnt: no such config key; did you mean 'tracking.experiment'?"),
    (["run", "task.dimm=3"], "task.dimm: no such config key; did you mean 'task.dim'?"),
    (["run", "taks=sphere"], "taks: no such config key; did you mean 'task'?"),
    (["run", "bogus=1"], "bogus: no such config key"),
    (["simulate", "protocl=oven"], "protocl: no such config key; did you mean 'protocol'?"),
    (["simulate", "tracking.enabld=false"], "tracking.enabld: no such config key; did you mean 'tracking.enabled'?"),
    (["diagnose", "recordng=x.csv"], "recordng: no such config key; did you mean 'recording'?"),
    (["calibrate", "methds=[raw]"], "methds: no such config key; did you mean 'methods'?"),
    (["leaderboard", "experiment=x"], "experiment: no such config key; did you mean 'experiments'?"),
])
def test_an_unknown_key_names_the_key_it_probably_meant(argv: list[str], line: str,
                                                         capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert capsys.readouterr().err.strip() == f"tcbench: error: {line}"
    assert list(tmp_path.iterdir()) == []


def test_an_unknown_option_of_a_group_names_the_one_it_probably_meant(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "optimiser=ifa_yng"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("tcbench: error: unknown optimiser 'ifa_yng'; known: bas, ")
    assert err.endswith("; did you mean 'ifa_yang'?")


def test_american_spellings_are_read_as_tcbench_s() -> None:
    from tcbench.errors import british, did_you_mean

    assert [british(w) for w in ("optimizer", "normalize", "initializer", "analyze", "color", "behavior", "center")] \
        == ["optimiser", "normalise", "initialiser", "analyse", "colour", "behaviour", "centre"]
    assert british("optimiser_seed") == "optimiser_seed"
    # the British spelling wins over a closer string: difflib alone would pick "optimize"
    assert did_you_mean("optimizer", ["optimize", "optimiser"]) == "optimiser"
    assert did_you_mean("sede", ["seed", "budget"]) == "seed"
    assert did_you_mean("bogus", ["seed", "budget", "optimiser"]) is None


def slurm_free_path() -> str:
    """PATH without any folder holding SLURM's sbatch or srun."""
    return os.pathsep.join(d for d in os.environ.get("PATH", "").split(os.pathsep)
                           if d and not any(os.path.exists(os.path.join(d, c)) for c in ("sbatch", "srun")))


@pytest.mark.parametrize("argv", [
    ["run", "-m", "hydra/launcher=submitit_slurm", "task=sphere", "optimiser=fa,ifa", "budget=20"],
    ["simulate", "-m", "hydra/launcher=submitit_slurm", "seed=0,1", "sensor=gyro", "protocol=static"],
])
def test_a_slurm_sweep_without_slurm_is_one_line_and_creates_nothing(argv: list[str], tmp_path: Path) -> None:
    """It was a 45-line traceback with exit code 1, after an empty MLflow experiment was made."""
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"}
    env["PATH"] = slurm_free_path()
    assert shutil.which("sbatch", path=env["PATH"]) is None and shutil.which("srun", path=env["PATH"]) is None
    done = subprocess.run([sys.executable, "-m", "tcbench", *argv], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr + done.stdout, done.stderr
    for words in ("submitit_slurm", "sbatch and srun are not on PATH", "hydra/launcher=submitit_local",
                  "hydra/launcher=joblib"):
        assert words in lines[0], lines[0]
    assert list(tmp_path.iterdir()) == []  # no mlflow.db, no multirun/ or outputs/ folder


def test_other_launchers_need_no_slurm(monkeypatch: pytest.MonkeyPatch) -> None:
    from tcbench.cli.app import SLURM_LAUNCHER, check_launcher
    from tcbench.errors import ConfigError

    monkeypatch.setenv("PATH", slurm_free_path())
    for target in ("hydra_plugins.tcbench_launcher.launcher.GroupedLauncher",
                   "hydra_plugins.hydra_joblib_launcher.joblib_launcher.JoblibLauncher",
                   "hydra_plugins.hydra_submitit_launcher.submitit_launcher.LocalLauncher"):
        check_launcher({"_target_": target})
    with pytest.raises(ConfigError, match="submitit_slurm needs SLURM"):
        check_launcher({"_target_": SLURM_LAUNCHER})


DEFAULTS = {"msra": "fulltemp", "gyro": "oven", "accel": "chamber"}


def test_every_kind_has_a_default_protocol_of_its_own() -> None:
    from tcbench.sensors import kinds

    found = {name: kind.default_protocol for name, kind in kinds.registry().items()}
    assert {k: found[k] for k in DEFAULTS} == DEFAULTS
    assert all(protocol in kinds.get(name).protocols for name, protocol in found.items())


def test_a_default_protocol_must_be_one_of_the_kind_s() -> None:
    from tcbench.sensors import kinds

    msra = kinds.get("msra")
    with pytest.raises(ValueError, match="default_protocol 'oven' is not one of its protocols"):
        kinds.SensorKind(name="x", title="x", input_unit="g", output_unit="Hz", input_field="accel_g",
                         input_range=(-1.0, 1.0), output_range=(-1.0, 1.0), device=msra.device,
                         protocols=msra.protocols, default_protocol="oven")


@pytest.mark.parametrize("sensor", sorted(DEFAULTS))
def test_simulate_without_a_protocol_runs_the_kind_s_default(sensor: str, tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    """``simulate sensor=accel`` failed with "unknown protocol 'fulltemp' for accel"."""
    out = tmp_path / "rec"
    assert main(["simulate", f"sensor={sensor}", f"out={out}", "tracking.enabled=false", "metrics=false",
                 "protocol_params.sample_rate_hz=0.05"]) == 0, capsys.readouterr().err
    written = sorted(p.name for p in out.iterdir())
    assert written == [f"{sensor}-{DEFAULTS[sensor]}-dev0-seed0.csv", f"{sensor}-{DEFAULTS[sensor]}-dev0-seed0.json"]
    assert json.loads((out / written[1]).read_text())["extra"]["protocol"] == DEFAULTS[sensor]


def test_the_default_protocol_is_logged_as_the_run_s_parameter(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    assert main(["simulate", "sensor=accel", "out=rec", "metrics=false", "protocol_params.sample_rate_hz=0.05"]) == 0
    import mlflow

    client = mlflow.MlflowClient(f"sqlite:///{tmp_path / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("simulations").experiment_id])
    assert run.data.params["protocol"] == "chamber" and run.data.tags["tcbench.task"] == "accel-chamber"


@pytest.mark.parametrize(("sensor", "known"), [("accel", "chamber, multipos, static"), ("gyro", "oven, static"),
                                               ("msra", "roomtemp, fulltemp")])
def test_an_unknown_protocol_is_one_line_listing_the_kind_s(sensor: str, known: str, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", f"sensor={sensor}", "protocol=warm", f"out={tmp_path / 'rec'}",
                 "tracking.enabled=false"]) == 2
    assert capsys.readouterr().err.strip() == f"tcbench: error: unknown protocol 'warm' for {sensor}; known: {known}"
    assert list(tmp_path.iterdir()) == []


def test_an_optimisation_job_and_a_board_load_no_simulator_and_no_signal_library() -> None:
    """A worker of an optimisation sweep loads its job kind without the compensation stack, and a
    board's modules load without scipy.signal (about a second of CPU in every such process);
    scipy.signal comes when a filter runs."""
    probe = ("import sys; import tcbench.runner.kinds.optimisation, tcbench.runner.config; "
             "job = sorted(m for m in sys.modules if m.startswith(('tcbench.compensation', 'tcbench.sensors.simulate', "
             "'scipy.signal'))); import tcbench.leaderboard.make; "
             "board = sorted(m for m in sys.modules if m.startswith('scipy.signal')); print(job, board)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[] []"
