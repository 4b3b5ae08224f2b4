"""Inputs that exhausted the machine or crashed the commands (issue 36), through the real command
line: sizes that would take hours, windows longer than the record, recordings too small to
calibrate, sidecars that are not files, clocks before the power-on, and file names that are
names, not syntax. Each is one line and exit code 2 with nothing written, or, for a name the file
system accepts, the command's ordinary work.

Every file is made inside the test; a record of more rows than the diagnosis's budget is read (to
be diagnosed on bin means), not refused from its row count.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import threading
from dataclasses import replace

from pathlib import Path

import numpy as np
import pytest
from cli_refusals import fresh_logging, refused, snapshot  # noqa: F401 (fresh_logging: autouse)

from tcbench.cli import main
from tcbench.sensors.recording import make_recording, write_recording

OFF = "tracking.enabled=false"
FAST = "methods=[raw,poly3]"  # a calibration refused before any fit is refused whatever it fits


def ran(capsys: pytest.CaptureFixture[str], args: list[str]) -> tuple[str, str]:
    """Run ``tcbench <args>``: exit 0; its stdout and stderr."""
    code = main(args)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return captured.out, captured.err


def gyro(path: Path, rows: int = 2000, step_s: float = 1.0, start_s: float = 0.0, span_c: float = 10.0) -> Path:
    """A gyro recording with its sidecar: ``rows`` samples ``step_s`` apart from ``start_s``,
    warming by ``span_c``, the output following the temperature plus white noise (a clock
    starting before 0, which no writer writes, is shifted in the table written)."""
    t_s = step_s * np.arange(rows, dtype=np.float64)
    temp_c = 20.0 + np.linspace(0.0, span_c, rows)
    noise = np.random.default_rng(0).normal(0.0, 0.01, rows)
    rec = make_recording(t_s, temp_c, np.zeros(rows), 0.01 * temp_c + noise, sensor="gyro",
                         sample_rate_hz=1.0 / step_s, device_id="d")
    write_recording(rec, path)
    if start_s:
        table = rec.data.assign(time_s=rec.time_s + start_s)
        table.to_csv(path, index=False)
    return path


# -- 1. diagnose: a record is weighed against the time it will take, before any work -------------

def test_diagnose_reads_a_record_longer_than_its_row_budget_instead_of_refusing_it(
        workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """More rows than ``settings.rate.max_rows`` are no longer refused from their count (10^7 rows
    were): the record is read, to be diagnosed on bin means; here its clock is no clock, and the
    reader says so."""
    (workdir / "big.csv").write_bytes(b"time_s,temperature_c,input,output\n" + b"1,20,0,0\n" * 20_000)
    refused(capsys, workdir, ["diagnose", "recording=big.csv", "sensor=gyro", "out=d", "max_rows=1000",
                              "settings.rate.max_rows=1000", OFF], "big.csv", "duplicate time_s")


def test_diagnose_max_rows_is_the_limit_and_can_be_raised(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    gyro(workdir / "rec.csv", rows=1000)  # under 20 min: the short-record report, quick
    refused(capsys, workdir, ["diagnose", "recording=rec.csv", "out=d", "max_rows=400", OFF],
            "rec.csv", "1000 rows", "max_rows=400", "means of 3 samples", "max_rows=1000 to diagnose it anyway")
    ran(capsys, ["diagnose", "recording=rec.csv", "out=d", "max_rows=1000", OFF])
    assert (workdir / "d" / "report.json").is_file()
    refused(capsys, workdir, ["diagnose", "recording=rec.csv", "out=e", "max_rows=0", OFF], "max_rows must be")


def test_diagnose_says_how_long_a_long_record_will_take(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """A record estimated to take longer than ``PROGRESS_AFTER_S`` gets a line on stderr with its
    rows and the estimate before the work starts (here the bound is lowered to 0)."""
    from tcbench.commands import diagnosis

    monkeypatch.setattr(diagnosis, "PROGRESS_AFTER_S", 0.0)
    gyro(workdir / "rec.csv", rows=1500)
    _, err = ran(capsys, ["diagnose", "recording=rec.csv", "out=d", OFF])
    assert "diagnosing rec.csv: 1500 rows, about" in err, err


def test_calibrate_diagnoses_more_rows_than_the_budget_on_bin_means(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """calibrate's ``model`` method diagnoses the fitted parts: more rows than a diagnosis takes
    (the budget lowered here to 3000) are diagnosed on bin means as ``tcbench diagnose`` does (they
    left the model out before), and the diagnosis's report says so."""
    from tcbench.diagnose.rate import native_rate
    from tcbench.diagnose.settings import DEFAULTS, RateSettings

    monkeypatch.setattr(native_rate, "DEFAULTS", replace(DEFAULTS, rate=RateSettings(max_rows=3000)))
    gyro(workdir / "rec.csv", rows=216_000, step_s=0.01)  # 36 min at 100 Hz: three of five blocks fitted, 21.6 min
    out, err = ran(capsys, ["calibrate", "recording=rec.csv", "out=c", "methods=[raw,model]", OFF])
    assert "model left out" not in err and "fitting raw, model on" in out, err
    said = json.loads((workdir / "c" / "diagnosis" / "report.json").read_text())["native_rate"]
    assert 120_000 < said["rows"] <= 129_600 and said["bin_samples"] == 100  # 1 s bins at 100 Hz
    assert said["bins_diagnosed"] == math.ceil(said["rows"] / 100)


# -- 2. windows and lengths against the record ----------------------------------------------------

@pytest.mark.parametrize("window", ["1e12", "inf", "2500"])
def test_calibrate_refuses_a_drift_window_longer_than_the_record(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                                 window: str) -> None:
    """drift_window_s of 1e12 tried to allocate 7.28 TiB (MemoryError); inf overflowed; a window
    longer than the record (2000 s) scored nothing but the whole record's mean."""
    gyro(workdir / "rec.csv")
    refused(capsys, workdir, ["calibrate", "recording=rec.csv", "out=c", f"drift_window_s={window}", FAST, OFF],
            f"drift_window_s={float(window):g}", "rec.csv (1999 s)")


def test_calibrate_refuses_a_drift_window_longer_than_a_test_recording(workdir: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    gyro(workdir / "rec.csv")
    gyro(workdir / "other.csv", rows=500)
    refused(capsys, workdir, ["calibrate", "recording=rec.csv", "out=c", "drift_window_s=1000",
                              "test_recordings=[other.csv]", FAST, OFF],
            "drift_window_s=1000", "test_recordings: other.csv (499 s)")


# -- 3. the least a calibration fits, and sidecars ----------------------------------------------

@pytest.mark.parametrize(("rows", "step_s", "words"), [
    (1, 1.0, "rec.csv: 1 row; its fitted parts need at least 6 rows"),
    (5, 100.0, "rec.csv: 5 rows; its fitted parts need at least 6 rows"),
    (10, 1.0, "drift_window_s=60 is longer than rec.csv (9 s)"),
])
def test_calibrate_refuses_too_little(workdir: Path, capsys: pytest.CaptureFixture[str], rows: int, step_s: float,
                                      words: str) -> None:
    """One row crashed calibrate (ValueError, exit 1); ten rows at 1 Hz were calibrated (exit 0),
    though they hold no drift window: no more rows than poly3_rate has coefficients, and a record
    shorter than one drift window, are one line each."""
    gyro(workdir / "rec.csv", rows=rows, step_s=step_s)
    refused(capsys, workdir, ["calibrate", "recording=rec.csv", "out=c", FAST, OFF], words)


def test_calibrate_refuses_fitted_parts_too_small_for_the_cubic(workdir: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """Enough rows, but fitted on one short block: too few rows there; a constant thermometer:
    too few temperatures for a cubic."""
    gyro(workdir / "rec.csv", rows=50)
    refused(capsys, workdir, ["calibrate", "recording=rec.csv", "out=c", "blocks=10", "train_branches=[0]",
                              "drift_window_s=5", FAST, OFF], "the fitted parts (time block 0", "hold 5 rows",
            "at least 6")
    gyro(workdir / "flat.csv", span_c=0.0)
    refused(capsys, workdir, ["calibrate", "recording=flat.csv", "out=c", FAST, OFF],
            "flat.csv: the fitted parts", "1 distinct temperature", "needs at least 4")


def test_calibrate_needs_the_sidecar(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without a sidecar calibrate ran on an unknown sensor and unit (exit 0)."""
    gyro(workdir / "rec.csv").with_suffix(".json").unlink()
    refused(capsys, workdir, ["calibrate", "recording=rec.csv", "out=c", FAST, OFF], "rec.json: no such file")
    gyro(workdir / "ok.csv")
    refused(capsys, workdir, ["calibrate", "recording=ok.csv", "out=c", "test_recordings=[rec.csv]", FAST, OFF],
            "test_recordings: rec.json: no such file")


@pytest.mark.parametrize("command", [["calibrate", "recording=rec.csv", "out=c", FAST], ["metrics", "rec.csv", "out=m"],
                                     ["diagnose", "recording=rec.csv", "sensor=gyro", "out=d"]])
def test_a_directory_in_place_of_the_sidecar_is_refused(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                        command: list[str]) -> None:
    """The sidecar is optional, so a missing one is no error where the command can do without
    it; a folder in its place was silently taken for no sidecar (exit 0)."""
    side = gyro(workdir / "rec.csv").with_suffix(".json")
    side.unlink()
    side.mkdir()
    refused(capsys, workdir, [*command, OFF], "rec.json: is a directory, not a sidecar")


# -- 4. the clock, checked by the one reader every command uses ------------------------------

@pytest.mark.parametrize("command", [["diagnose", "recording=rec.csv", "out=d"], ["metrics", "rec.csv", "out=m"],
                                     ["calibrate", "recording=rec.csv", "out=c", FAST]])
def test_a_clock_before_the_power_on_is_one_line_for_every_command(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                                   command: list[str]) -> None:
    """diagnose on a clock from -5e5 s exited 1 with an internal error (its warm-up term
    overflowed); every command now refuses it where it reads the recording."""
    gyro(workdir / "rec.csv", start_s=-5e5)
    refused(capsys, workdir, [*command, OFF], "rec.csv: row 1, column 'time_s'", "-500000 s is before the power-on")


def test_import_refuses_a_clock_before_the_power_on(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "log.csv").write_text("t,temp,rate\n" + "".join(f"{t},{20 + 0.01 * t},1.0\n" for t in range(-50, 50)))
    refused(capsys, workdir, ["import", "csv=log.csv", "sensor=gyro", "time=t:s", "temperature=temp:degC",
                              "output=rate:deg/s", "out=i", OFF], "log.csv: row 1", "-50 s is before the power-on")


# -- 5. file names are names ------------------------------------------------------------------

@pytest.mark.parametrize("name", ["${HOME}.csv", "a${x}.csv", "price$.csv", "${oc.env:HOME}.csv", "a\\${x}.csv"])
def test_a_file_name_with_a_dollar_is_read_literally(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                     name: str) -> None:
    """``${HOME}.csv`` was a traceback, ``${oc.env:HOME}.csv`` read ``/root.csv``: one job reads
    the file of that name (given by key or as the first argument)."""
    gyro(workdir / name, rows=200)
    out, _ = ran(capsys, ["metrics", f"recording={name}", "out=m", OFF])
    assert f"metrics of {name}" in out and (workdir / "m" / "metrics.json").is_file()
    out, _ = ran(capsys, ["metrics", name, "out=p", OFF])
    assert f"metrics of {name}" in out


def test_a_sweep_reads_file_names_literally(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """With ``-m`` the values are still Hydra's (a comma separates two), each a literal name, and
    ``${stem:recording}`` its literal stem."""
    for name in ("${HOME}.csv", "b.csv"):
        gyro(workdir / name, rows=200)
    ran(capsys, ["metrics", "-m", "recording=${HOME}.csv,b.csv", "out=s/${stem:recording}", OFF])
    assert (workdir / "s" / "${HOME}" / "metrics.json").is_file() and (workdir / "s" / "b" / "metrics.json").is_file()


def test_a_missing_path_is_named_as_given(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    refused(capsys, workdir, ["diagnose", "recording=${oc.env:HOME}.csv", "out=d", OFF], "${oc.env:HOME}.csv: no such file")


def test_test_recordings_are_literal_paths(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    gyro(workdir / "rec.csv")
    gyro(workdir / "${HOME}.csv")
    out, _ = ran(capsys, ["calibrate", "recording=rec.csv", "test_recordings=[${HOME}.csv]", FAST, "out=c", OFF])
    assert "every part of ${HOME}.csv" in out


def test_a_long_file_name_is_accepted(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A 254-byte name (the file system takes 255) was refused by import: the temporary files'
    names were longer than the file system takes. A folder made from it that would be longer is
    one line naming it."""
    stem = "y" * 250
    (workdir / f"{stem}.csv").write_text("t,temp,rate\n" + "".join(f"{t},{20 + 0.01 * t},{t % 7}\n" for t in range(100)))
    ran(capsys, ["import", f"csv={stem}.csv", "sensor=gyro", "time=t:s", "temperature=temp:degC", "output=rate:deg/s",
                 "out=i", OFF])
    assert (workdir / "i" / f"{stem}.json").is_file()
    ran(capsys, ["metrics", f"i/{stem}.csv", "out=m", OFF])
    refused(capsys, workdir, ["metrics", f"i/{stem}.csv", OFF], f"{stem}_metrics", "give out=")
    refused(capsys, workdir, ["import", f"csv={stem}.csv", "sensor=gyro", "time=t:s", "temperature=temp:degC",
                              "output=rate:deg/s", "out=i2", f"name={stem}zz", OFF], "longer than the 255")


def test_a_positional_file_with_an_equals_sign_names_file_and_key(workdir: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    gyro(workdir / "a=b.csv", rows=200)
    refused(capsys, workdir, ["metrics", "a=b.csv", OFF], "a=b.csv", "'a' is no key", "recording=a=b.csv")
    ran(capsys, ["metrics", "recording=a=b.csv", "out=m", OFF])


# -- 6. files that are not regular files, and lines that end in CR alone ---------------------

WHAT_READS = [["diagnose", "recording=rec.csv", "out=d"], ["metrics", "rec.csv", "out=m"],
              ["import", "csv=rec.csv", "sensor=gyro", "time=time_s:s", "temperature=temperature_c:degC",
               "output=output:deg/s", "out=i"],
              ["calibrate", "recording=rec.csv", "out=c", FAST]]


class PipeWatch:
    """Opens the named pipe ``path`` for writing whenever a reader waits on it, and closes it at
    once (the reader sees an empty file): a command that opens the pipe cannot hang the test, and
    ``blocked`` says it did."""

    def __init__(self, path: Path) -> None:
        self.path, self.blocked, self.stop = path, False, threading.Event()
        self.thread = threading.Thread(target=self._watch, daemon=True)

    def _watch(self) -> None:
        while not self.stop.wait(0.05):
            try:
                fd = os.open(self.path, os.O_WRONLY | os.O_NONBLOCK)  # ENXIO while no one reads
            except OSError:
                continue
            self.blocked = True
            os.close(fd)

    def __enter__(self) -> PipeWatch:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()


@pytest.mark.parametrize("command", WHAT_READS, ids=lambda c: c[0])
def test_a_named_pipe_is_refused_by_what_it_is(workdir: Path, capsys: pytest.CaptureFixture[str],
                                               command: list[str]) -> None:
    """diagnose on a named pipe without a writer blocked for ever; metrics, import and calibrate
    called it "no such file"."""
    os.mkfifo(workdir / "rec.csv")
    with PipeWatch(workdir / "rec.csv") as watch:
        refused(capsys, workdir, [*command, OFF], "rec.csv: a named pipe, not a regular file")
    assert not watch.blocked


@pytest.mark.parametrize("command", WHAT_READS, ids=lambda c: c[0])
def test_a_symlink_loop_is_refused_by_what_it_is(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                 command: list[str]) -> None:
    (workdir / "rec.csv").symlink_to("rec.csv")
    refused(capsys, workdir, [*command, OFF], "rec.csv: a symlink loop")


@pytest.mark.parametrize("rows", [5, 5000])
@pytest.mark.parametrize("command", WHAT_READS, ids=lambda c: c[0])
def test_lines_ending_in_cr_alone_are_named(workdir: Path, capsys: pytest.CaptureFixture[str],
                                            command: list[str], rows: int) -> None:
    """A table whose lines end in CR alone was "the first line is longer than 64 KiB" (or, under
    64 KiB, a header of every row)."""
    path = gyro(workdir / "rec.csv", rows=rows)
    path.write_bytes(path.read_bytes().replace(b"\n", b"\r"))
    line = refused(capsys, workdir, [*command, OFF], "rec.csv: lines end in a carriage return (CR) alone")
    assert "64 KiB" not in line


# -- 7. messages that fit on a line ---------------------------------------------------------------

@pytest.fixture(scope="module")
def wide_parquet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 50-row gyro recording with 20 000 unknown columns of zeros, as Parquet (written once)."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    where = tmp_path_factory.mktemp("wide")
    rec = pd.read_csv(gyro(where / "rec.csv", rows=50))
    zeros = np.zeros(len(rec))
    pq.write_table(pa.table({**{c: rec[c].to_numpy() for c in rec}, **{f"c{i}": zeros for i in range(20_000)}}),
                   where / "rec.parquet")
    return where / "rec.parquet"


@pytest.mark.parametrize("command", [["metrics", "rec.parquet", "out=m"], ["diagnose", "recording=rec.parquet", "out=d"]],
                         ids=lambda c: c[0])
def test_twenty_thousand_unknown_columns_are_one_short_line(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                            command: list[str], wide_parquet: Path) -> None:
    """A recording with 20 000 unknown columns was refused in one line 87 KB long."""
    shutil.copyfile(wide_parquet, workdir / "rec.parquet")
    line = refused(capsys, workdir, [*command, OFF], "rec.parquet: unknown column 'c0', 'c1'", "20000")
    assert len(line) < 300 and "'c19999'" not in line, len(line)


@pytest.mark.parametrize("rows", [1, 10])
def test_diagnose_on_a_record_too_short_to_test_anything_is_one_line(workdir: Path, capsys: pytest.CaptureFixture[str],
                                                                     rows: int) -> None:
    """A 1-row and a 10-row record exited 0 with a short-record report in which nothing ran."""
    gyro(workdir / "rec.csv", rows=rows)
    refused(capsys, workdir, ["diagnose", "recording=rec.csv", "out=d", OFF], "rec.csv: too short to test anything",
            f"{rows} sample", "at least 30 samples")
