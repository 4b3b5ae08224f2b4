"""Issue 36, output safety: no command replaces an existing file without ``overwrite=true`` (and
then it says what it replaced), none writes through a link out of its ``out=`` folder, and a
refusal leaves ``out=`` exactly as it was (every target is checked before anything moves).

One test per case of the issue, each failing on the code before the fix, plus the
``overwrite=true`` path and the symlink cases of every command that writes into ``out=``."""

from __future__ import annotations

import hashlib
import logging
import os
from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.sensors.recording import make_recording, write_recording
from tcbench import staging

SIM = ["simulate", "sensor=gyro", "protocol=static", "protocol_params.duration_s=100",
       "protocol_params.sample_rate_hz=1", "tracking.enabled=false"]
IMPORT = ["import", "sensor=gyro", "time=t:s", "temperature=T:degC", "output=w:deg/s", "tracking.enabled=false"]


@pytest.fixture(autouse=True)
def _fresh_logging(monkeypatch: pytest.MonkeyPatch) -> None:
    """Logging as in a fresh ``tcbench`` process (earlier Hydra runs can leave handlers behind)."""
    root = logging.getLogger()
    monkeypatch.setattr(root, "handlers", [])
    monkeypatch.setattr(root, "level", logging.WARNING)


def snapshot(root: Path) -> dict[str, str]:
    """Every entry under ``root`` (links not followed) with its content's digest or link target."""
    out = {}
    for p in sorted(root.rglob("*")):
        key = str(p.relative_to(root))
        if p.is_symlink():
            out[key] = f"link:{os.readlink(p)}"
        elif p.is_dir():
            out[key] = "dir"
        else:
            out[key] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def tcbench(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    """Exit code, stdout and the lines of stderr of ``tcbench <args>``, run in this process."""
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


def refused(capsys: pytest.CaptureFixture[str], root: Path, args: list[str], *names: str) -> str:
    """Run ``tcbench <args>``: exit 2, one ``tcbench: error:`` line naming each of ``names``, no
    traceback, and nothing under ``root`` changed; the line."""
    before = snapshot(root)
    code, out, err = tcbench(capsys, *args)
    assert code == 2, (code, out, err)
    assert len(err) == 1 and err[0].startswith("tcbench: error: "), err
    assert "Traceback" not in out + "\n".join(err)
    for name in names:
        assert name in err[0], (name, err[0])
    assert snapshot(root) == before
    return err[0]


def ok(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    """Run ``tcbench <args>``, which must succeed; its stdout."""
    code, out, err = tcbench(capsys, *args)
    assert code == 0, (out, err)
    return out


def gyro_recording(path: Path, seconds: int = 100, cycle: bool = False, seed: int = 0) -> Path:
    """A small gyro recording at 1 Hz warming by 10 degC (``cycle``: warming then cooling back)."""
    t_s = np.arange(float(seconds))
    ramp = np.linspace(0.0, 10.0, t_s.size)
    temp_c = 20.0 + (np.minimum(ramp, 10.0 - ramp) * 2.0 if cycle else ramp)
    rate = 0.01 * temp_c + np.random.default_rng(seed).normal(0.0, 0.01, t_s.size)
    return write_recording(make_recording(t_s, temp_c, np.zeros(t_s.size), rate, sensor="gyro", sample_rate_hz=1.0,
                                          device_id="d"), path)


def log_csv(path: Path, offset: float = 0.0) -> Path:
    """A small foreign gyro log with columns t, T and w."""
    rows = "".join(f"{i},{20.0 + 0.01 * i},{0.1 + offset + 0.001 * np.sin(i)}\n" for i in range(100))
    path.write_text("t,T,w\n" + rows)
    return path


# -- the commands that write into out=, each with a run that succeeds on a fresh folder ------------
def _calibration(work: Path, capsys: pytest.CaptureFixture[str], tracked: bool = False) -> Path:
    """A calibration folder of a small recording (axis x), for export; tracked: its run in ./mlflow.db."""
    rec = gyro_recording(work / "inputs" / "cal-rec.csv")
    folder = work / "inputs" / "cal"
    ok(capsys, "calibrate", f"recording={rec}", "methods=[raw,poly3]", "axis=x", f"out={folder}",
       f"tracking.enabled={str(tracked).lower()}")
    return folder


def command_args(name: str, work: Path, capsys: pytest.CaptureFixture[str]) -> list[str]:
    """The arguments of a ``tcbench <name>`` writing into ``work/out``, its inputs made in ``work/inputs``."""
    (work / "inputs").mkdir(exist_ok=True)
    out = f"out={work / 'out'}"
    if name == "simulate":
        return [*SIM, out, "name=r"]
    if name == "import":
        return [*IMPORT, f"csv={log_csv(work / 'inputs' / 'log.csv')}", out, "name=r"]
    if name in {"metrics", "diagnose"}:
        rec = gyro_recording(work / "inputs" / "rec.csv")
        return [name, f"recording={rec}", out, "tracking.enabled=false"]
    if name == "calibrate":
        rec = gyro_recording(work / "inputs" / "rec.csv")
        return ["calibrate", f"recording={rec}", "methods=[raw,poly3]", out, "tracking.enabled=false"]
    if name == "export":
        return ["export", f"calibrations=[{_calibration(work, capsys)}]", "formats=[ardupilot]", out]
    if name == "leaderboard":
        _calibration(work, capsys, tracked=True)
        return ["leaderboard", "experiments=calibrations", out]
    raise AssertionError(name)


WRITERS = ["simulate", "import", "metrics", "diagnose", "calibrate", "export", "leaderboard"]
# a file each command writes at the top of out=
FILE_OF = {"simulate": "r.csv", "import": "r.csv", "metrics": "metrics.json", "diagnose": "report.json",
           "calibrate": "calibration.json", "export": "ardupilot_tcal.parm", "leaderboard": None}


def first_file(out: Path) -> Path:
    """A file of a finished output folder, top level first."""
    return sorted(out.rglob("*"), key=lambda p: (len(p.parts), p.name))[0]


# -- 1. no silent replacement ------------------------------------------------------------------------
def test_import_over_an_earlier_import_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ok(capsys, *IMPORT, f"csv={log_csv(workdir / 'a.csv')}", "out=rec", "name=r")
    line = refused(capsys, workdir, [*IMPORT, f"csv={log_csv(workdir / 'b.csv', offset=1.0)}", "out=rec", "name=r"],
                   "rec/r.csv", "overwrite=true")
    assert "already exists" in line


def test_import_over_a_simulated_recording_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ok(capsys, *SIM, "out=rec", "name=r")
    refused(capsys, workdir, [*IMPORT, f"csv={log_csv(workdir / 'log.csv')}", "out=rec", "name=r"], "rec/r.csv")


def test_import_over_a_sidecar_alone_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A simulated parquet recording r.parquet shares its sidecar r.json with an imported r.csv."""
    ok(capsys, *SIM, "out=rec", "name=r", "format=parquet", "metrics=false")
    refused(capsys, workdir, [*IMPORT, f"csv={log_csv(workdir / 'log.csv')}", "out=rec", "name=r"], "rec/r.json")


def test_simulate_over_an_existing_recording_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ok(capsys, *SIM, "out=rec", "name=r")
    refused(capsys, workdir, [*SIM, "out=rec", "name=r", "seed=1"], "rec/r.csv", "overwrite=true")


def test_a_simulate_sweep_is_refused_before_its_first_job(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ok(capsys, *SIM, "out=rec", "name=r1", "metrics=false")
    refused(capsys, workdir, [*SIM, "-m", "out=rec", "name=r0,r1", "metrics=false"], "rec/r1.csv")
    assert not (workdir / "rec" / "r0.csv").exists()


@pytest.mark.parametrize("command", WRITERS)
def test_a_second_run_is_refused_unless_overwrite(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch, command: str) -> None:
    """Refused in one line naming an existing file; with overwrite=true replaced, and said in one line."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    args = command_args(command, tmp_path, capsys)
    assert "replaced" not in ok(capsys, *args)
    target = tmp_path / "out" / (FILE_OF[command] or first_file(tmp_path / "out").name)
    target.write_text("stale\n")
    refused(capsys, tmp_path, args, str(tmp_path / "out" / ""), "already exists", "overwrite=true")
    out = ok(capsys, *args, "overwrite=true")
    said = [ln for ln in out.splitlines() if "replaced" in ln]
    assert len(said) == 1 and said[0].startswith("tcbench: overwrite=true: replaced ") and str(target) in said[0], out
    assert target.read_text() != "stale\n"


# -- 2. never through a link out of out= -----------------------------------------------------------------
@pytest.mark.parametrize("command", WRITERS)
def test_a_linked_file_pointing_outside_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch, command: str) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    args = command_args(command, tmp_path, capsys)
    if not (name := FILE_OF[command]):  # a board's name: from a first run elsewhere
        ok(capsys, *[a if not a.startswith("out=") else f"out={tmp_path / 'first'}" for a in args])
        name = first_file(tmp_path / "first").name
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "keep").write_text("mine\n")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / name).symlink_to(tmp_path / "outside" / "keep")
    for extra in ([], ["overwrite=true"]):
        line = refused(capsys, tmp_path, [*args, *extra], str(tmp_path / "out" / name), "outside")
        assert "link" in line


def test_simulate_metrics_through_a_linked_folder_is_refused(workdir: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "outside").mkdir()
    (workdir / "rec").mkdir()
    (workdir / "rec" / "r_metrics").symlink_to(workdir / "outside")
    for extra in ([], ["overwrite=true"]):
        refused(capsys, workdir, [*SIM, "out=rec", "name=r", *extra], "rec/r_metrics", "outside")
    assert not list((workdir / "outside").iterdir())


def test_a_link_inside_out_is_followed(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A link to a folder inside out= keeps every write inside it: allowed."""
    (workdir / "rec" / "real").mkdir(parents=True)
    (workdir / "rec" / "r_metrics").symlink_to(workdir / "rec" / "real")
    ok(capsys, *SIM, "out=rec", "name=r")
    assert (workdir / "rec" / "real" / "metrics.json").is_file()


def test_calibrate_diagnosis_through_a_linked_folder_is_refused(workdir: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """The model method writes the diagnosis of the training parts to OUT/diagnosis/."""
    rec = gyro_recording(workdir / "cycle.csv", seconds=2600, cycle=True)
    (workdir / "outside").mkdir()
    (workdir / "cal").mkdir()
    (workdir / "cal" / "diagnosis").symlink_to(workdir / "outside")
    refused(capsys, workdir, ["calibrate", f"recording={rec}", "methods=[raw,model]", "out=cal",
                              "tracking.enabled=false"], "cal/diagnosis", "outside")
    assert not list((workdir / "outside").iterdir())


# -- 3. all or nothing ------------------------------------------------------------------------------------
def test_diagnose_with_a_folder_named_report_json_leaves_out_as_it_was(workdir: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """The issue's case: a full diagnosis whose report.json is a folder in out=."""
    rec = gyro_recording(workdir / "rec.csv", seconds=1500)
    (workdir / "d" / "report.json").mkdir(parents=True)
    line = refused(capsys, workdir, ["diagnose", f"recording={rec}", "out=d", "tracking.enabled=false"],
                   "d/report.json")
    assert "folder" in line


def test_short_diagnose_with_a_folder_named_report_md_leaves_out_as_it_was(workdir: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    rec = gyro_recording(workdir / "rec.csv")
    (workdir / "d" / "report.md").mkdir(parents=True)
    for extra in ([], ["overwrite=true"]):  # a folder is never replaced by a file
        refused(capsys, workdir, ["diagnose", f"recording={rec}", "out=d", "tracking.enabled=false", *extra],
                "d/report.md")


def test_a_file_where_an_output_folder_goes_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "rec").mkdir()
    (workdir / "rec" / "r_metrics").write_text("a file\n")
    for extra in ([], ["overwrite=true"]):
        refused(capsys, workdir, [*SIM, "out=rec", "name=r", *extra], "rec/r_metrics")


def test_staging_checks_every_target_before_moving_any(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (out / "b.txt").mkdir(parents=True)
    before = snapshot(tmp_path)
    with pytest.raises(staging.OutputRefusedError, match="b.txt"), staging.staged_dir(out, overwrite=True) as tmp:
        (tmp / "a.txt").write_text("a")
        (tmp / "b.txt").write_text("b")
    assert snapshot(tmp_path) == before


def test_staging_refuses_existing_files_and_reports_the_replaced(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.txt").write_text("old")
    with pytest.raises(staging.OutputRefusedError, match="a.txt"), staging.staged_dir(out) as tmp:
        (tmp / "a.txt").write_text("new")
        (tmp / "b.txt").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == ["a.txt"] and (out / "a.txt").read_text() == "old"
    replaced: list[Path] = []
    with staging.staged_dir(out, overwrite=True, replaced=replaced) as tmp:
        (tmp / "a.txt").write_text("new")
        (tmp / "b.txt").write_text("new")
    assert replaced == [out / "a.txt"] and (out / "a.txt").read_text() == "new"


# -- what must keep working --------------------------------------------------------------------------------
def test_a_resumed_command_sweep_skips_its_finished_jobs(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """tracking.resume=true re-runs only what did not finish: the finished jobs' files are no clash."""
    sweep = ["simulate", "-m", "sensor=gyro", "protocol=static", "protocol_params.duration_s=100",
             "protocol_params.sample_rate_hz=1", "metrics=false", "out=rec", "seed=0,1", "tracking.sweep_id=s1"]
    ok(capsys, *sweep)
    ok(capsys, *sweep, "tracking.resume=true")



@pytest.mark.slow
def test_the_quickstart_runs_again_over_its_own_files(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The README's quickstart run twice in one folder: the second replaces the first's files and says so."""
    small = ["quickstart", "seeds=2", "budget=60", "epochs=100"]
    assert "replaced" not in ok(capsys, *small)
    said = [ln for ln in ok(capsys, *small).splitlines() if ln.startswith("tcbench: overwrite=true: replaced ")]
    text = " ".join(said)  # one line per staged write: the board, the recording, the diagnosis report
    for replaced in ("leaderboard/msra_zerobias-dev0.csv", "recordings/concealed-msra-thermal_lag-0.csv",
                     "diagnosis/report.json"):
        assert f"tcbench-quickstart/{replaced}" in text, said
