"""Malformed input through the real command line: import, metrics, diagnose and simulate refuse it
in one line (exit 2, no traceback) and write or overwrite nothing.

Every case is made inside the test (sparse files for the big ones), none is stored in the repository.
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from collections.abc import Callable
from typing import Any
from pathlib import Path

import numpy as np
import pytest
from cli_refusals import fresh_logging, refused, snapshot  # noqa: F401 (fresh_logging: autouse)

from tcbench.cli import main
from tcbench.sensors.recording import make_recording, write_recording

SIM = ["simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=100",
       "protocol_params.sample_rate_hz=1", "tracking.enabled=false"]
IMPORT = ["import", "sensor=gyro", "time=t:ms", "temperature=temp:degC", "output=rate:mdps"]


def log_csv(path: Path, t_ms: np.ndarray | None = None) -> Path:
    """A small foreign gyro log: a clock in ms, temperature in degC, rate in mdps."""
    t_ms = np.arange(0.0, 100_000.0, 1000.0) if t_ms is None else t_ms
    rate = 30.0 + np.sin(np.arange(t_ms.size))
    rows = "".join(f"{t!r},{25.0 + 0.01 * i!r},{r!r}\n" for i, (t, r) in enumerate(zip(t_ms.tolist(), rate.tolist(), strict=True)))
    path.write_text("t,temp,rate\n" + rows)
    return path


def recording(path: Path, t_s: np.ndarray | None = None) -> Path:
    """A small valid gyro recording (1 Hz, 2000 s, warming by 10 degC: enough to diagnose) at ``path``."""
    t_s = np.arange(2000.0) if t_s is None else t_s
    rng = np.random.default_rng(0)
    temp_c = 20.0 + np.linspace(0.0, 10.0, t_s.size)
    rec = make_recording(t_s, temp_c, np.zeros(t_s.size), 0.01 * temp_c + rng.normal(0.0, 0.01, t_s.size),
                         sensor="gyro", sample_rate_hz=1.0, device_id="d")
    return write_recording(rec, path)


# -- point 1: never write over an input --------------------------------------------------------
def test_import_refuses_to_overwrite_its_source(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log_csv(workdir / "src.csv")
    refused(capsys, workdir, [*IMPORT, "csv=src.csv", "out=."], "src.csv", "would overwrite the input")
    (workdir / "sub").mkdir()
    refused(capsys, workdir, [*IMPORT, "csv=src.csv", "out=sub/..", "name=src"],
            "src.csv")


def test_import_refuses_a_sidecar_over_its_source(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log_csv(workdir / "log.json")  # a CSV under another suffix: the sidecar log.json would replace it
    refused(capsys, workdir, [*IMPORT, "csv=log.json", "out=."], "log.json")


def test_metrics_and_diagnose_do_not_overwrite_their_inputs(workdir: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    recording(workdir / "metrics.csv")  # its sidecar metrics.json is a name metrics writes
    refused(capsys, workdir, ["metrics", "metrics.csv", "out=.", "tracking.enabled=false"], "metrics.json")
    recording(workdir / "rec.csv")
    (workdir / "model.yaml").write_text("tcbench_model: 1\nsensor: gyro\ncore: {kind: polynomial, centre_c: 25.0, "
                                        "half_range_c: 50.0, bias: [0.0], scale_factor: [1.0]}\n")
    refused(capsys, workdir, ["diagnose", "recording=rec.csv", "model=model.yaml", "out=."], "model.yaml")


# -- point 2: names stay inside out= --------------------------------------------------------------
@pytest.mark.parametrize("name", ["{tmp}/x/ESCAPE", "../escape", "", "''", ".", "..", "a\\b", "a/b", "nul\0x"])
def test_names_stay_inside_out(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                               capsys: pytest.CaptureFixture[str], name: str) -> None:
    work = tmp_path / "work"  # its parent holds this test's files alone (the escapes land there)
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    name = name.format(tmp=tmp_path)
    log_csv(work / "log.csv")
    outside = snapshot(tmp_path)
    refused(capsys, work, [*SIM, f"name={name}", "out=o"], "name=")
    refused(capsys, work, [*IMPORT, "csv=log.csv", f"name={name}", "out=o"], "name=")
    assert snapshot(tmp_path) == outside


# -- point 8: a full disk --------------------------------------------------------------------------
def full_disk(monkeypatch: pytest.MonkeyPatch, module: object, name: str) -> None:
    """Make ``module.name`` (a writer) fail as on a full disk."""
    def no_space(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(module, name, no_space)


@pytest.mark.parametrize("writer", ["plots", "table", "json"])
def test_a_full_disk_is_one_line(workdir: Path, capsys: pytest.CaptureFixture[str],
                                 monkeypatch: pytest.MonkeyPatch, writer: str) -> None:
    import matplotlib.figure

    import tcbench.sensors.recording as recording_module

    recording(workdir / "rec.csv")
    log_csv(workdir / "log.csv")
    if writer == "plots":
        full_disk(monkeypatch, matplotlib.figure.Figure, "savefig")
    elif writer == "table":
        full_disk(monkeypatch, recording_module, "_write_table")
    else:
        full_disk(monkeypatch, Path, "write_text")
    commands: dict[str, list[str]] = {
        "simulate": [*SIM, "out=new/o"],
        "metrics": ["metrics", "rec.csv", "out=m", "tracking.enabled=false"],
        "import": [*IMPORT, "csv=log.csv", "out=i"],
        "diagnose": ["diagnose", "recording=rec.csv", "out=d"],
    }
    hit: Callable[[str], bool] = {"plots": lambda c: c in {"simulate", "metrics", "diagnose"},
                                  "table": lambda c: c in {"simulate", "import"},
                                  "json": lambda c: c in {"simulate", "metrics", "diagnose"}}[writer]
    for command, args in commands.items():
        if hit(command):
            out = args[-2] if command == "metrics" else args[-1]
            refused(capsys, workdir, args, f"{out}: cannot write", "(No space left on device)")


# -- point 7: simulate's and metrics' parameters ----------------------------------------------------
@pytest.mark.parametrize(("arg", "key"), [
    ("protocol_params.duration_s=0", "protocol_params.duration_s"),
    ("protocol_params.duration_s=-10", "protocol_params.duration_s"),
    ("protocol_params.duration_s=inf", "protocol_params.duration_s"),
    ("protocol_params.duration_s=1e12", "protocol_params"),
    ("protocol_params.sample_rate_hz=0", "protocol_params.sample_rate_hz"),
    ("protocol_params.sample_rate_hz=-5", "protocol_params.sample_rate_hz"),
    ("protocol_params.sample_rate_hz=nan", "protocol_params.sample_rate_hz"),
    ("protocol_params.sample_rate_hz=fast", "protocol_params.sample_rate_hz"),
    ("protocol_params.sample_rate_hz=true", "protocol_params.sample_rate_hz"),
    ("protocol_params.sample_rate_hz=0.001", "protocol_params"),  # 100 s at 1 mHz: not two samples
    ("without=[nosuch]", "without"),
])
def test_simulate_refuses_bad_parameters(workdir: Path, capsys: pytest.CaptureFixture[str], arg: str, key: str) -> None:
    line = refused(capsys, workdir, [*SIM, arg, "out=o"], key)
    if arg.startswith("without"):
        assert "white_noise" in line  # the known effects are listed


@pytest.mark.parametrize(("protocol", "arg"), [
    ("oven", "protocol_params.step_c=0"),
    ("oven", "protocol_params.step_c=1e-9"),
    ("oven", "protocol_params.hold_s=1e12"),
    ("oven", "protocol_params.hold_s=-1"),
    ("fulltemp", "protocol_params.nodes_c=[]"),
    ("fulltemp", "protocol_params.nodes_c=[1,x]"),
    ("fulltemp", "protocol_params.chamber=1"),
    ("roomtemp", "protocol_params.wander_tau_s=nan"),
])
def test_simulate_refuses_bad_protocol_parameters(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                  protocol: str, arg: str) -> None:
    sensor = "gyro" if protocol == "oven" else "msra"
    key = arg.split("=")[0] if "1e12" not in arg else "protocol_params"
    refused(capsys, workdir, ["simulate", f"sensor={sensor}", f"protocol={protocol}", arg, "out=o"], key)


@pytest.mark.parametrize("value", ["0", "-200", "nan", "inf", "fast"])
def test_metrics_refuses_a_bad_scale_factor(workdir: Path, capsys: pytest.CaptureFixture[str], value: str) -> None:
    recording(workdir / "rec.csv")
    refused(capsys, workdir, ["metrics", "rec.csv", f"scale_factor_hz_per_g={value}", "tracking.enabled=false"],
            "scale_factor_hz_per_g")


# -- point 3: clocks that make no sense for the rate --------------------------------------------------
def schema_csv(path: Path, t_s: np.ndarray) -> Path:
    """A gyro table in schema columns (no sidecar) with the clock ``t_s``, warming 25 -> 35 degC."""
    n = t_s.size
    temp = np.linspace(25.0, 35.0, n)
    rate = 0.01 * temp + 0.01 * np.sin(np.arange(n))
    path.write_text("time_s,temperature_c,input,output\n" + "".join(
        f"{t!r},{c!r},0.0,{r!r}\n" for t, c, r in zip(t_s.tolist(), temp.tolist(), rate.tolist(), strict=True)))
    return path


@pytest.mark.parametrize(("last_s", "words"), [(1e9, "a gap of 1e+09 s after 1 s steps"),
                                               (1e7, "a gap of 1e+07 s after 1 s steps"),
                                               (1e300, "1e+300 s is not a plausible time")])
def test_a_clock_glitch_is_refused_by_every_reader(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                   last_s: float, words: str) -> None:
    schema_csv(workdir / "glitch.csv", np.append(np.arange(100.0), last_s))
    for args in (["metrics", "glitch.csv", "tracking.enabled=false"],
                 ["diagnose", "recording=glitch.csv", "sensor=gyro", "out=d"],
                 ["import", "csv=glitch.csv", "sensor=gyro", "time=time_s:s", "temperature=temperature_c:degC",
                  "output=output:deg/s", "out=i"]):
        refused(capsys, workdir, args, "glitch.csv: row 101, column 'time_s'", words)


def test_a_logger_in_bursts_is_not_a_glitch(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Ten 30 s bursts at 1 Hz an hour apart (gaps 120 times the data), and one burst a day later."""
    bursts = [3600.0 * k + np.arange(30.0) for k in range(10)] + [86400.0 + np.arange(30.0)]
    schema_csv(workdir / "bursts.csv", np.concatenate(bursts))
    code = main(["import", "csv=bursts.csv", "sensor=gyro", "time=time_s:s", "temperature=temperature_c:degC",
                 "output=output:deg/s", "out=i"])
    assert code == 0, capsys.readouterr().err
    assert "in 11 segments" in capsys.readouterr().out


def test_diagnose_refuses_an_absurd_filter_grid(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A clock the schema accepts (bursts a day apart for 100 days) but too long for diagnose's
    1 s filter clock: refused before anything is allocated."""
    schema_csv(workdir / "long.csv", np.concatenate([86400.0 * k + np.arange(20.0) for k in range(100)]))
    refused(capsys, workdir, ["diagnose", "recording=long.csv", "sensor=gyro", "out=d"], "long.csv",
            "filter clock would hold 8.55e+06 samples")


# -- point 4: files too big to read whole, read in bounded pieces --------------------------------------
HEADER = b"time_s,temperature_c,input,output\n"
BIG_FILES: dict[str, tuple[Callable[[Path], None], tuple[str, ...]]] = {
    "cell.csv": (lambda p: p.write_bytes(HEADER + b"0,25,0,1\n1,25,0,1\n2,25,0," + b"1" * 50_000_000 + b"\n3,25,0,1\n"),
                 ("cell.csv: row 3, column 'output'", "a line longer than 1 MiB")),
    "head.csv": (lambda p: p.write_bytes(b"time_s," + b"x" * 200_000 + b"\n0,1\n"),
                 ("head.csv:", "the first line is longer than 64 KiB")),
    "sparse.csv": (lambda p: p.open("wb").truncate(2**31), ("sparse.csv:", "the header holds a NUL byte")),
    "nul.csv": (lambda p: (p.write_bytes(HEADER), p.open("ab").truncate(2**31)),
                ("nul.csv: row 1, column 'time_s'", "a NUL byte")),
}
RSS_PROBE = """
import json, resource, sys
import tcbench.cli, tcbench.diagnose.diagnosis, tcbench.diagnose.report.write, tcbench.sensors.importer
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
codes = [tcbench.cli.main(args.split()) for args in sys.argv[1:]]
print(json.dumps({"codes": codes, "growth_mb": (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) / 1024}))
"""


def _commands(name: str) -> list[str]:
    return [f"metrics {name} tracking.enabled=false", f"diagnose recording={name} sensor=gyro out=d",
            f"import csv={name} sensor=gyro time=time_s:s temperature=temperature_c:degC output=output:deg/s out=i"]


@pytest.fixture(scope="module")
def big_files_judged(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], list[str], list[str], list[str]]:
    """Every big file refused by import, metrics and diagnose in one fresh process (one start of
    the interpreter and its imports for the twelve commands): its exit codes and peak memory
    growth, its stderr lines, and the folder's files before and after."""
    workdir = tmp_path_factory.mktemp("big")
    for name, (make, _) in BIG_FILES.items():
        make(workdir / name)
    before = snapshot_names(workdir)
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"} | {"MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-c", RSS_PROBE, *(c for name in BIG_FILES for c in _commands(name))],
                          cwd=workdir, capture_output=True, text=True, timeout=300, check=False, env=env)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result, done.stderr.strip().splitlines(), before, snapshot_names(workdir)


@pytest.mark.parametrize("name", list(BIG_FILES))
def test_big_files_are_judged_from_a_bounded_read(big_files_judged, name: str) -> None:  # type: ignore[no-untyped-def]
    """Each of import, metrics and diagnose refuses the file in one line, naming it (and the row
    and column where there is one), and its peak memory grows by less than 64 MB, whatever the
    file's size (2 GiB sparse files among them): the peak over every command of every file."""
    result, lines, before, after = big_files_judged
    _, words = BIG_FILES[name]
    i = list(BIG_FILES).index(name)
    assert len(result["codes"]) == len(lines) == 3 * len(BIG_FILES), lines
    assert result["codes"][3 * i:3 * i + 3] == [2, 2, 2]
    mine = lines[3 * i:3 * i + 3]
    assert all(line.startswith("tcbench: error: ") and all(w in line for w in words) for line in mine), mine
    assert result["growth_mb"] < 64, result
    assert after == before


def snapshot_names(root: Path) -> list[str]:
    """The files under ``root`` (names only: the big files are not hashed)."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))
