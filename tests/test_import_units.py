"""``tcbench import`` never assumes a unit (a column without one is refused unless ``units=`` or
the file's tcbench sidecar states it), prints each column's unit, and records each recording's
sensor axis (``axes=``, a PX4 log's x, y, z fields) in its sidecar as ``extra.axis``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import PX4_LOG, TOFUPILOT_CSV

from tcbench.cli import main
from tcbench.sensors.importer import import_csv
from tcbench.sensors.recording import (
    RecordingError,
    RecordingMeta,
    make_recording,
    read_recording,
    recording_axis,
    write_recording,
)

TOFU = TOFUPILOT_CSV  # tab-separated; timestamp in us, gyro in rad/s, degC
NO_AXIS = "axis unknown (axes=x|y|z to record it)"


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    """Exit code, stdout and the lines of stderr of ``tcbench <args>``."""
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


def tofu(tmp_path: Path, *args: str) -> list[str]:
    """An import of the tofupilot log into ``tmp_path/rec``, tracking off, with ``args``."""
    return ["import", f"csv={TOFU}", "sensor=gyro", f"out={tmp_path / 'rec'}", "tracking.enabled=false", *args]


# -- a unit is never assumed -------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("args", "line"),
    [
        (("time=timestamp:us", "temperature=imu.temperature:degC", "output=imu.gyro.y"),
         "output=imu.gyro.y: no unit; say it after a colon, e.g. output=imu.gyro.y:rad/s, or units={output:UNIT} "
         "(gyro output is stored in deg/s)"),
        (("time=timestamp", "temperature=imu.temperature:degC", "output=imu.gyro.y:rad/s"),
         "time=timestamp: no unit; say it after a colon, e.g. time=timestamp:us, or units={time:UNIT} "
         "(time is stored in s)"),
        (("time=timestamp:us", "temperature=imu.temperature", "output=imu.gyro.y:rad/s"),
         "temperature=imu.temperature: no unit; say it after a colon, e.g. temperature=imu.temperature:degC, "
         "or units={temperature:UNIT} (temperature is stored in degC)"),
        (("time=timestamp:us", "temperature=imu.temperature:degC", "output=imu.gyro.y:rad/s", "input=imu.gyro.x"),
         "input=imu.gyro.x: no unit; say it after a colon, e.g. input=imu.gyro.x:rad/s, or units={input:UNIT} "
         "(gyro input is stored in deg/s)"),
    ],
    ids=["output", "time", "temperature", "input"],
)
def test_a_column_without_a_unit_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            args: tuple[str, ...], line: str) -> None:
    """The reported case (rad/s data, no unit, exit 0 with deg/s in the sidecar) and its kin: one
    line with the syntax, exit 2, nothing written."""
    code, out, err = run(capsys, *tofu(tmp_path, *args))
    assert code == 2 and not out
    assert err == [f"tcbench: error: {TOFU}: {line}"], err
    assert not (tmp_path / "rec").exists()


def test_units_mapping_states_the_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``units={output:rad/s,time:us,temperature:degC}`` (and ``units.output=rad/s``) stand for the
    colons: the rad/s column becomes deg/s (x 57.2958), the microsecond clock seconds; the summary
    line names every unit."""
    raw = pd.read_csv(TOFU, sep="\t")
    code, out, err = run(capsys, *tofu(tmp_path, "time=timestamp", "temperature=imu.temperature", "output=imu.gyro.y",
                                       "units={output:rad/s,time:us,temperature:degC}", "name=mapped"))
    assert code == 0, err
    assert ("  time=timestamp [us], temperature=imu.temperature [degC], output=imu.gyro.y [rad/s] -> deg/s; "
            f"{NO_AXIS}\n") in out
    rec = read_recording(tmp_path / "rec" / "mapped.csv")
    rate_rads = raw["imu.gyro.y"].to_numpy()
    moving = rate_rads != 0.0
    np.testing.assert_allclose(rec.output[moving] / rate_rads[moving], 57.2958, rtol=1e-6)
    np.testing.assert_allclose(rec.output, np.degrees(rate_rads), rtol=1e-14)
    np.testing.assert_allclose(rec.time_s, raw["timestamp"].to_numpy() * 1e-6, rtol=1e-15)
    assert rec.meta.units["output"] == "deg/s" and rec.meta.extra["source"]["columns"]["output"] == "imu.gyro.y [rad/s]"

    code, _, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                     "output=imu.gyro.y", "units.output=rad/s", "name=dotted"))
    assert code == 0, err
    pd.testing.assert_frame_equal(read_recording(tmp_path / "rec" / "dotted.csv").data, rec.data)


def test_two_different_units_for_one_column_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                     "output=imu.gyro.y:rad/s", "units={output:deg/s}"))
    assert code == 2 and err == [f"tcbench: error: {TOFU}: output=imu.gyro.y:rad/s says 'rad/s' but "
                                 "units={output:...} says 'deg/s'; say one unit"], err
    assert not (tmp_path / "rec").exists()
    code, _, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                     "output=imu.gyro.y:rad/s", "units={output:rad/s}", "name=same"))
    assert code == 0, err  # saying the same unit twice is no conflict


def test_a_column_name_with_a_colon(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A name that exists as written wins over splitting at its colon, and still needs a unit."""
    freq_khz = 1.2 + 1e-4 * np.arange(20)
    pd.DataFrame({"t": np.arange(20) * 0.5, "temp": 25.0, "freq:khz": freq_khz}).to_csv(tmp_path / "m.csv", index=False)
    base = ["import", f"csv={tmp_path / 'm.csv'}", "sensor=msra", "time=t:s", "temperature=temp:degC",
            "tracking.enabled=false"]
    code, _, err = run(capsys, *base, "output=freq:khz", f"out={tmp_path / 'a'}")
    assert code == 2 and len(err) == 1 and "output=freq:khz: no unit; say it after a colon, e.g. output=freq:khz:kHz" \
        in err[0], err
    for name, args in (("colon", ("output=freq:khz:kHz",)), ("mapped", ("output=freq:khz", "units={output:kHz}"))):
        code, _, err = run(capsys, *base, *args, f"out={tmp_path / 'ok'}", f"name={name}")
        assert code == 0, err
        np.testing.assert_allclose(read_recording(tmp_path / "ok" / f"{name}.csv").output, freq_khz * 1e3, rtol=1e-12)
    assert not (tmp_path / "a").exists()


def test_a_tcbench_recording_states_its_own_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A recording tcbench wrote imports without units (its sidecar states them, and its axis);
    the same table without a tcbench sidecar beside it is refused, naming the file that is there."""
    t = np.arange(100) * 0.1
    rec = make_recording(t, np.linspace(20.0, 30.0, 100), np.zeros(100), 0.01 * np.arange(100), sensor="gyro",
                         sample_rate_hz=10.0, device_id="d", extra={"axis": "z"})
    (tmp_path / "src").mkdir()
    write_recording(rec, tmp_path / "src" / "r.csv")
    args = ("sensor=gyro", "time=time_s", "temperature=temperature_c", "output=output", "tracking.enabled=false")
    code, out, err = run(capsys, "import", f"csv={tmp_path / 'src' / 'r.csv'}", *args, f"out={tmp_path / 'o'}")
    assert code == 0, err
    assert "time=time_s [s], temperature=temperature_c [degC], output=output [deg/s] -> deg/s; axis z" in out
    again = read_recording(tmp_path / "o" / "r.csv")
    np.testing.assert_array_equal(again.output, rec.output)
    np.testing.assert_array_equal(again.time_s, rec.time_s)
    assert recording_axis(again.meta) == "z"

    code, _, err = run(capsys, "import", f"csv={tmp_path / 'src' / 'r.csv'}", *args, "axes=x", f"out={tmp_path / 'x'}")
    assert code == 2 and len(err) == 1 and "axis x given, but the sidecar r.json says the output is the z axis" \
        in err[0], err

    (tmp_path / "src" / "r.json").write_text(json.dumps({"about": "notes of another tool"}))
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'src' / 'r.csv'}", *args, f"out={tmp_path / 'n'}")
    assert code == 2 and err == [f"tcbench: error: {tmp_path / 'src' / 'r.csv'}: time=time_s: no unit; say it after "
                                 "a colon, e.g. time=time_s:us, or units={time:UNIT} (time is stored in s); "
                                 "r.json beside it states none: missing key 'schema_version'"], err
    assert not (tmp_path / "x").exists() and not (tmp_path / "n").exists()


def test_the_api_refuses_a_unit_less_column_too(tmp_path: Path) -> None:
    columns = {"time_s": "timestamp:us", "temperature_c": "imu.temperature:degC", "output": "imu.gyro.x"}
    with pytest.raises(RecordingError, match=r"output=imu.gyro.x: no unit"):
        import_csv(TOFU, "gyro", columns)
    rec = import_csv(TOFU, "gyro", columns, units={"output": "rad/s"}, axis="x")
    np.testing.assert_allclose(rec.output, np.degrees(pd.read_csv(TOFU, sep="\t")["imu.gyro.x"]), rtol=1e-14)
    assert recording_axis(rec.meta) == "x"


# -- the axis --------------------------------------------------------------------------------------
def test_axes_land_in_each_sidecar(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    outputs = ",".join(f"imu.gyro.{a}:rad/s" for a in "xyz")
    code, out, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                       f"output={outputs}", "axes=x,y,z", "name=imu"))
    assert code == 0, err
    for a in "xyz":
        path = tmp_path / "rec" / f"imu-imu.gyro.{a}.csv"
        assert json.loads(path.with_suffix(".json").read_text())["extra"]["axis"] == a
        assert recording_axis(read_recording(path).meta) == a
        assert (f"  time=timestamp [us], temperature=imu.temperature [degC], output=imu.gyro.{a} [rad/s] -> deg/s; "
                f"axis {a}\n") in out

    code, out, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                       "output=imu.gyro.y:rad/s", "name=bare"))
    assert code == 0, err
    assert "axis" not in read_recording(tmp_path / "rec" / "bare.csv").meta.extra  # never guessed from the name
    assert recording_axis(read_recording(tmp_path / "rec" / "bare.csv").meta) is None
    assert out.endswith(f"; {NO_AXIS}\n")


@pytest.mark.parametrize(
    ("axes", "line"),
    [
        ("x,y", "axes=x,y names 2 axes for 3 output columns (imu.gyro.x,imu.gyro.y,imu.gyro.z); "
                "give one axis per column"),
        ("x,y,z,x", "axes=x,y,z,x names 4 axes for 3 output columns"),
        ("x,w,z", "axes=x,w,z: 'w' is not an axis (x, y or z)"),
    ],
    ids=["too-few", "too-many", "not-an-axis"],
)
def test_bad_axes_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], axes: str, line: str) -> None:
    outputs = ",".join(f"imu.gyro.{a}:rad/s" for a in "xyz")
    code, out, err = run(capsys, *tofu(tmp_path, "time=timestamp:us", "temperature=imu.temperature:degC",
                                       f"output={outputs}", f"axes={axes}"))
    assert code == 2 and not out and len(err) == 1 and line in err[0], err
    assert not (tmp_path / "rec").exists()


def test_recording_axis_validates_the_sidecar() -> None:
    assert recording_axis(RecordingMeta()) is None
    assert recording_axis(RecordingMeta(extra={"axis": "y"})) == "y"
    for bad in ("X", "up", 0, None):
        with pytest.raises(RecordingError, match=r"^extra\.axis: axis must be x, y or z, got"):
            recording_axis(RecordingMeta(extra={"axis": bad}))


def test_a_px4_log_records_the_axis_of_each_field(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every instance and field x, y, z of sensor_gyro: its axis in the sidecar, the device id
    PX4 logged kept, the units printed; a field named without a unit is refused."""
    code, out, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "out=rec", "name=px4",
                         "tracking.enabled=false")
    assert code == 0, err
    for i in range(3):
        for a in "xyz":
            meta = read_recording(workdir / "rec" / f"px4-sensor_gyro-{i}-{a}.csv").meta
            assert recording_axis(meta) == a and meta.extra["axis"] == a
            assert isinstance(meta.extra["source"]["px4_device_id"], int) and meta.extra["source"]["instance"] == i
    assert out.count("  time=timestamp_sample [us], temperature=temperature [degC], output=x [rad/s] -> deg/s; "
                     "axis x\n") == 3

    code, _, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "time=timestamp", "out=bad",
                       "tracking.enabled=false")
    assert code == 2 and len(err) == 1 and "time=timestamp: no unit; say it after a colon" in err[0], err
    code, _, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "output=x:rad/s", "axes=y", "out=bad",
                       "tracking.enabled=false")
    assert code == 2 and err == ["tcbench: error: axes=y: the log's field x is the x axis, not y"], err
    assert not (workdir / "bad").exists()
