"""``tcbench import``: your own CSV as a schema-v1 recording, and metrics of recordings in bursts."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import PAN_CSV, PX4_LOG

from tcbench.cli import main
from tcbench.metrics import gyro
from tcbench.metrics.report import analyse
from tcbench.sensors.importer import import_csv
from tcbench.sensors.recording import make_recording, read_recording
from tcbench.sensors.segments import segments
from tcbench.signal.allan import allan_deviation, allan_deviation_segments


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    """Exit code, stdout and the lines of stderr of ``tcbench <args>``."""
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


# -- round trips ---------------------------------------------------------------------------------
def _gyro_csv(path: Path, n: int = 200) -> dict[str, np.ndarray]:
    """A gyro log in foreign units (ms, K, mdps, rad/s) with every 7th row flagged; the values
    the recording should hold, in schema units, for the rows not flagged."""
    rng = np.random.default_rng(3)
    clock_ms = 1000 + 20 * np.arange(n)  # 50 Hz
    temp_k = 298.15 + np.linspace(0.0, 5.0, n)
    rate_mdps = rng.normal(1500.0, 30.0, n)
    applied_rads = np.full(n, 0.5)
    flag = (np.arange(n) % 7 == 3).astype(int)
    pd.DataFrame({"clock_ms": clock_ms, "temp_k": temp_k, "note": "x", "rate_mdps": rate_mdps,
                  "applied_rads": applied_rads, "bad": flag}).to_csv(path, index=False)
    keep = flag == 0
    return {"time_s": clock_ms[keep] / 1000.0, "temperature_c": temp_k[keep] - 273.15,
            "input": applied_rads[keep] * 180.0 / math.pi, "output": rate_mdps[keep] / 1000.0}


def test_round_trip_gyro_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    expected = _gyro_csv(tmp_path / "log.csv")
    code, out, err = run(capsys, "import", f"csv={tmp_path / 'log.csv'}", "sensor=gyro", "time=clock_ms:ms",
                         "temperature=temp_k:K", "output=rate_mdps:mdps", "input=applied_rads:rad/s", "drop=bad",
                         f"out={tmp_path / 'rec'}", "device_id=unit-7")
    assert code == 0 and not err, err
    assert "171 samples at 50 Hz, 29 rows dropped where bad is nonzero" in out
    rec = read_recording(tmp_path / "rec" / "log.csv")
    for column, values in expected.items():
        np.testing.assert_allclose(rec.data[column].to_numpy(), values, rtol=1e-12, atol=1e-12, err_msg=column)
    assert rec.meta.sensor == "gyro" and rec.meta.device_id == "unit-7" and rec.meta.sample_rate_hz == 50.0
    assert rec.meta.units["output"] == "deg/s"
    source = rec.meta.extra["source"]
    assert source["columns"]["time_s"] == "clock_ms [ms]" and source["rows_dropped"] == 29
    assert rec.meta.extra["segments"]["count"] == 1  # a dropped row leaves a gap of two steps, not a new segment


def test_round_trip_msra_units_and_defaults(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    t = np.arange(50) * 0.5
    temp_f = np.linspace(32.0, 50.0, 50)
    freq_khz = 1.2 + 1e-4 * np.arange(50)
    pd.DataFrame({"time_s": t, "temp_f": temp_f, "freq:khz": freq_khz}).to_csv(tmp_path / "m.csv", index=False)
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'm.csv'}", "sensor=msra", "time=time_s:s",
                       "temperature=temp_f:degF", "output=freq:khz:kHz", f"out={tmp_path / 'o'}", "name=run1")
    assert code == 0, err
    rec = read_recording(tmp_path / "o" / "run1.csv")
    np.testing.assert_array_equal(rec.time_s, t)  # in the schema unit: kept bit for bit
    np.testing.assert_allclose(rec.temperature_c, (temp_f - 32.0) * 5.0 / 9.0, atol=1e-12)
    np.testing.assert_allclose(rec.output, freq_khz * 1e3, rtol=1e-12)  # a column name with a colon in it
    np.testing.assert_array_equal(rec.input, np.zeros(50))  # no input column: 0 g
    assert rec.meta.device_id == "m" and rec.meta.sample_rate_hz == 2.0


@pytest.mark.parametrize("delimiter", ["\t", ";"])
def test_tab_and_semicolon_tables_import_as_the_comma_table(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                            delimiter: str) -> None:
    """The delimiter is read from the header (tab, ';' or ','), for the data and for the errors."""
    _gyro_csv(tmp_path / "log.csv")
    pd.read_csv(tmp_path / "log.csv").to_csv(tmp_path / "other.csv", sep=delimiter, index=False)
    args = ("sensor=gyro", "time=clock_ms:ms", "temperature=temp_k:K", "output=rate_mdps:mdps", "drop=bad")
    for name in ("log", "other"):
        code, _, err = run(capsys, "import", f"csv={tmp_path / name}.csv", *args, f"out={tmp_path / name}-rec")
        assert code == 0, err
    comma, other = read_recording(tmp_path / "log-rec" / "log.csv"), read_recording(tmp_path / "other-rec" / "other.csv")
    pd.testing.assert_frame_equal(comma.data, other.data)
    assert other.meta.extra["source"]["delimiter"] == delimiter
    bad = (tmp_path / "other.csv").read_text().replace(f"{delimiter}1500", f"{delimiter}x1500", 1)
    (tmp_path / "bad.csv").write_text(bad)
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'bad.csv'}", *args, f"out={tmp_path / 'bad-rec'}")
    assert code == 2 and len(err) == 1 and "column 'rate_mdps': 'x1500" in err[0] and "is not a number" in err[0], err


def test_any_unit_pint_knows(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """mrad/s, an epoch clock in microseconds and degF through pint; the MSRA's input in m/s^2."""
    n = 100
    clock_us = 1_700_000_000_000_000 + 500_000 * np.arange(n)  # an epoch clock at 2 Hz
    temp_f = np.linspace(-4.0, 158.0, n)
    rate_mrads = np.random.default_rng(0).normal(0.8, 0.05, n)
    pd.DataFrame({"t": clock_us, "T": temp_f, "w": rate_mrads}).to_csv(tmp_path / "g.csv", sep="\t", index=False)
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'g.csv'}", "sensor=gyro", "time=t:us", "temperature=T:degF",
                       "output=w:mrad/s", f"out={tmp_path / 'o'}")
    assert code == 0, err
    rec = read_recording(tmp_path / "o" / "g.csv")
    np.testing.assert_allclose(np.diff(rec.time_s), 0.5, rtol=1e-9)
    np.testing.assert_allclose(rec.temperature_c, (temp_f - 32.0) * 5.0 / 9.0, atol=1e-9)
    np.testing.assert_allclose(rec.output, np.degrees(rate_mrads / 1000.0), rtol=1e-12)
    assert rec.meta.sample_rate_hz == 2.0

    accel = pd.DataFrame({"t": np.arange(n) * 0.5, "T": np.full(n, 25.0), "f": np.full(n, 12_000.0),
                          "a": np.full(n, 9.80665)})
    accel.to_csv(tmp_path / "m.csv", sep=";", index=False)
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'm.csv'}", "sensor=msra", "time=t:s", "temperature=T:degC",
                       "output=f:Hz", "input=a:m/s2", f"out={tmp_path / 'o'}")
    assert code == 0, err
    np.testing.assert_allclose(read_recording(tmp_path / "o" / "m.csv").input, 1.0, rtol=1e-15)  # 1 g


def test_the_tofupilot_chamber_cycle_imports_as_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The real tab-separated IMU log, byte for byte as upstream (PROVENANCE.md: a microsecond
    clock, rad/s): imported with one command, the values tcbench's own reader of it gives."""
    from tcbench.datasets.real import TOFUPILOT_CSV, tofupilot_gyro

    code, out, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                         "temperature=imu.temperature:degC", "output=imu.gyro.y:rad/s", f"out={tmp_path / 'rec'}",
                         "name=tofupilot-gyro-y", "tracking.enabled=false")
    assert code == 0, err
    rec = read_recording(tmp_path / "rec" / "tofupilot-gyro-y.csv")
    known = tofupilot_gyro("y")  # drops the start-up sample and starts the clock at 0
    assert len(rec.data) == 8400 and len(known.data) == 8399
    np.testing.assert_allclose(rec.output[1:], known.output, rtol=1e-14)
    np.testing.assert_allclose(np.diff(rec.time_s[1:]), np.diff(known.time_s), rtol=1e-9)
    np.testing.assert_array_equal(rec.temperature_c[1:], known.temperature_c)
    assert rec.meta.extra["source"]["delimiter"] == "\t" and 1.9 < rec.meta.sample_rate_hz < 2.1


def test_several_axes_in_one_command(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``output=imu.gyro.x:rad/s,imu.gyro.y:rad/s,imu.gyro.z:rad/s`` on the real tofupilot log: one
    recording per axis sharing the clock and temperature, one MLflow run naming them all."""
    import mlflow

    from tcbench.datasets.real import TOFUPILOT_CSV

    axes = ",".join(f"imu.gyro.{a}:rad/s" for a in "xyz")
    code, out, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                         "temperature=imu.temperature:degC", f"output={axes}", "out=rec", "name=imu")
    assert code == 0, err
    recs = {a: read_recording(workdir / "rec" / f"imu-imu.gyro.{a}.csv") for a in "xyz"}
    table = pd.read_csv(TOFUPILOT_CSV, sep="\t")
    for a, rec in recs.items():
        np.testing.assert_allclose(rec.output, np.degrees(table[f"imu.gyro.{a}"].to_numpy()), rtol=1e-14)
        np.testing.assert_array_equal(rec.time_s, recs["x"].time_s)
        np.testing.assert_array_equal(rec.temperature_c, recs["x"].temperature_c)
    assert out.count("tcbench: wrote ") == 3
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (r,) = client.search_runs([client.get_experiment_by_name("recordings").experiment_id])
    assert sorted(Path(p).name for p in r.data.tags["tcbench.recordings"].split(",")) == \
        [f"imu-imu.gyro.{a}.csv" for a in "xyz"]

    # an axis that fails leaves no recording of the others
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.x:rad/s,imu.gyro.w:rad/s", "out=rec2",
                       "tracking.enabled=false")
    assert code == 2 and len(err) == 1 and "no column 'imu.gyro.w'" in err[0], err
    assert not (workdir / "rec2").exists()


def test_a_px4_log_imports_every_gyro_instance_and_axis(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The real PX4 sample log: sensor_gyro's three instances, each axis a recording with the
    topic's own sample clock (us) and temperature, in deg/s from PX4's rad/s."""
    from pyulog import ULog

    code, out, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "out=rec", "name=px4")
    assert code == 0, err
    log = ULog(str(PX4_LOG), ["sensor_gyro"])
    instances = {d.multi_id: d.data for d in log.data_list}
    assert sorted(instances) == [0, 1, 2]
    for i, data in instances.items():
        for axis in "xyz":
            rec = read_recording(workdir / "rec" / f"px4-sensor_gyro-{i}-{axis}.csv")
            np.testing.assert_allclose(rec.output, np.degrees(data[axis].astype(np.float64)), rtol=1e-6)
            np.testing.assert_allclose(rec.time_s, data["timestamp_sample"] * 1e-6, rtol=1e-15)
            np.testing.assert_array_equal(rec.temperature_c, data["temperature"].astype(np.float64))
            source = rec.meta.extra["source"]
            assert source["topic"] == "sensor_gyro" and source["instance"] == i and source["format"] == "PX4 ULog"
            assert 28.0 < rec.temperature_c.mean() < 41.0 and 0.99 < rec.meta.sample_rate_hz < 1.01
    assert out.count("tcbench: wrote ") == 9

    # one axis, another clock; a log without the topic, or a file that is no log: one line each
    code, _, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "output=z:rad/s", "time=timestamp:us",
                       "out=rec-z", "tracking.enabled=false")
    assert code == 0 and sorted(p.name for p in (workdir / "rec-z").glob("*.csv")) == \
        [f"sample_log_small-sensor_gyro-{i}-z.csv" for i in range(3)]
    (workdir / "fake.ulg").write_text("not a log\n")
    for args, words in (((f"csv={PX4_LOG}", "sensor=msra"), "no topic tcbench reads for sensor 'msra'"),
                        (("csv=fake.ulg", "sensor=gyro"), "cannot read the file as a PX4 ULog")):
        code, _, err = run(capsys, "import", *args, "out=bad", "tracking.enabled=false")
        assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (workdir / "bad").exists()


# -- bad input: one line, exit 2, nothing written --------------------------------------------------
GOOD = "clock_ms,temp_c,rate_dps,flag\n0,25.0,0.1,0\n20,25.0,0.2,0\n40,25.1,0.3,0\n60,25.1,0.2,0\n"
ARGS = ("sensor=gyro", "time=clock_ms:ms", "temperature=temp_c:degC", "output=rate_dps:deg/s")


@pytest.mark.parametrize(
    ("text", "args", "fragment"),
    [
        (GOOD, ("temperature=tempc",), "log.csv: no column 'tempc' (for temperature_c); the file has: "
                                       "clock_ms, temp_c, rate_dps, flag"),
        (GOOD.replace("20,25.0,0.2", "20,25.0,nan"), (), "log.csv: row 2, column 'rate_dps': nan is not finite"),
        (GOOD.replace("40,25.1", "10,25.1"), (), "log.csv: row 3, column 'clock_ms': time_s goes back from 0.02 "
                                                  "to 0.01 (after converting ms to s)"),
        (GOOD.replace("25.", "298."), (), "log.csv: row 1, column 'temp_c': 298 degC is not plausible for a gyro "
                                          "recording (expected -100..200 degC) (kelvin?)"),
        (GOOD, ("output=rate_dps:furlong/s",), "column 'rate_dps': unit 'furlong/s' is a unit of [length] / [time], "
                                               "not an angular rate (e.g. deg/s, rad/s"),
        (GOOD, ("output=rate_dps:wibble",), "column 'rate_dps': unknown unit 'wibble': not a unit pint knows"),
        (None, (), "log.csv: no such file"),
        (GOOD, ("sensor=imu",), "unknown sensor 'imu'; known: msra, gyro, accel"),
        (GOOD.replace("20,25.0,0.2", "20,25.0,abc"), (), "log.csv: row 2, column 'rate_dps': 'abc' is not a number"),
        (GOOD.replace("20,25.0,0.2,0\n", "20,25.0,,0\n"), (), "log.csv: row 2, column 'rate_dps': empty cell"),
        (GOOD.replace("20,25.0,0.2,0\n", "\n"), (), "log.csv: row 2: blank line"),
        (GOOD, ("drop=flags",), "log.csv: no column 'flags' (for drop)"),
        (GOOD, ("sample_rate_hz=100",), "log.csv: sample_rate_hz 100 does not match the table"),
    ],
    ids=["unknown-column", "nan", "time-back", "kelvin-as-degC", "unit-of-another-quantity", "unknown-unit", "missing-file", "unknown-sensor",
         "text", "empty-cell", "blank-line", "unknown-drop-column", "rate-mismatch"],
)
def test_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str | None, args: tuple[str, ...],
                   fragment: str) -> None:
    csv = tmp_path / "log.csv"
    if text is not None:
        csv.write_text(text)
    given = {a.split("=", 1)[0]: a for a in (*ARGS, *args)}
    code, out, err = run(capsys, "import", f"csv={csv}", *given.values(), f"out={tmp_path / 'out'}")
    assert code == 2 and not out
    assert len(err) == 1 and fragment in err[0], err
    assert not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == (["log.csv"] if text is not None else [])


def test_failed_import_leaves_earlier_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "log.csv"
    csv.write_text(GOOD)
    assert run(capsys, "import", f"csv={csv}", *ARGS, f"out={tmp_path / 'out'}")[0] == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()}
    csv.write_text(GOOD.replace("40,25.1", "10,25.1"))
    code, _, err = run(capsys, "import", f"csv={csv}", *ARGS, f"out={tmp_path / 'out'}", "overwrite=true")
    assert code == 2 and len(err) == 1 and "already exists" not in err[0]  # the bad clock, not the earlier files
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()} == before


def test_missing_argument_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "x.csv").write_text("t,temp,y\n0,20,1\n1,21,2\n")
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'x.csv'}", "sensor=gyro", "time=t:s", "output=y:deg/s",
                       f"out={tmp_path / 'out'}")
    assert code == 2 and len(err) == 1 and "missing temperature=" in err[0]


# -- bursts ----------------------------------------------------------------------------------------
FS_HZ, SIGMA_DPS, SLOPE_DPS_PER_C = 50.0, 0.015, 0.03


def _bursts(n_bursts: int = 25, per_burst: int = 250, spacing_s: float = 305.0, seed: int = 0) -> pd.DataFrame:
    """A logger's bursts: white noise on a bias linear in a cooling thermometer (24 -> 16 degC)."""
    rng = np.random.default_rng(seed)
    t = (spacing_s * np.arange(n_bursts)[:, None] + np.arange(per_burst)[None, :] / FS_HZ).ravel()
    temp = 24.0 - 8.0 * t / t[-1]
    rate = -1.0 + SLOPE_DPS_PER_C * (temp - 20.0) + rng.normal(0.0, SIGMA_DPS, t.size)
    return pd.DataFrame({"t": t, "temp": np.round(temp, 4), "rate": rate})


@pytest.mark.figures
def test_bursts_import_and_metrics(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _bursts().to_csv("bursts.csv", index=False)
    code, _, err = run(capsys, "import", "csv=bursts.csv", "sensor=gyro", "time=t:s", "temperature=temp:degC",
                       "output=rate:deg/s", "out=rec")
    assert code == 0, err
    rec = read_recording("rec/bursts.csv")
    seg = rec.meta.extra["segments"]
    assert seg["count"] == 25 and seg["samples"] == [250] * 25 and rec.meta.sample_rate_hz == FS_HZ
    assert seg["first_rows"][:3] == [1, 251, 501] and seg["start_s"][1] == 305.0

    code, _, err = run(capsys, "metrics", "rec/bursts.csv", "out=m", "tracking.enabled=false")
    assert code == 0, err
    payload = json.loads(Path("m/metrics.json").read_text())
    m = payload["metrics"]
    assert m["segments"] == 25 and m["rate_temp_points"] == 25
    assert abs(m["rate_temp_slope_dps_per_c"] - SLOPE_DPS_PER_C) < 4 * m["rate_temp_slope_se_dps_per_c"]
    assert m["rate_temp_slope_se_dps_per_c"] < 0.001 and m["rate_temp_r"] > 0.99
    assert payload["rate_vs_temperature"]["method"] == "segment means"
    # white noise: ARW = sigma / sqrt(fs) in deg/sqrt(s), x 60 in deg/sqrt(h)
    assert m["arw_deg_per_sqrt_h"] == pytest.approx(SIGMA_DPS / math.sqrt(FS_HZ) * 60.0, rel=0.1)
    assert m["allan_min_tau_s"] <= 125 / FS_HZ  # no tau reaches past half a burst
    assert Path("m/rate_vs_temperature.png").stat().st_size > 10_000


def test_allan_within_bursts_is_that_of_white_noise() -> None:
    data = _bursts(seed=1)
    seg = segments(data["t"].to_numpy())
    ad = allan_deviation_segments(data["rate"].to_numpy(), FS_HZ, seg)
    expected = SIGMA_DPS / np.sqrt(ad.tau_s * FS_HZ)  # white rate noise
    assert ad.tau_s[-1] == pytest.approx(64 / FS_HZ)  # up to half a burst (250 samples)
    np.testing.assert_allclose(ad.adev, expected, rtol=0.1)
    assert ad.n_terms[-1] == 25 * (251 - 128)
    # the same samples strung together as one record: the steps between bursts show up
    joined = allan_deviation(data["rate"].to_numpy(), FS_HZ, ad.tau_s)
    assert joined.adev[-1] > 1.3 * expected[-1]


def test_allan_of_one_segment_is_the_plain_one() -> None:
    rate = np.random.default_rng(2).normal(size=1001)
    one = allan_deviation_segments(rate, 10.0, np.zeros(rate.size, dtype=int))
    plain = allan_deviation(rate, 10.0, "octave")
    np.testing.assert_array_equal(one.tau_s, plain.tau_s)
    np.testing.assert_allclose(one.adev, plain.adev, rtol=1e-12)
    np.testing.assert_array_equal(one.n_terms, plain.n_terms)


def test_continuous_gyro_rate_vs_temperature_by_bins(tmp_path: Path) -> None:
    t = np.arange(0.0, 7200.0, 0.1)
    temp = 20.0 + 10.0 * np.sin(2 * np.pi * t / 7200.0)
    rate = 0.5 - 0.02 * temp + np.random.default_rng(4).normal(0.0, 0.01, t.size)
    rec = make_recording(t, temp, np.zeros(t.size), rate, sensor="gyro", sample_rate_hz=10.0, device_id="c")
    report = analyse(rec, tmp_path)
    m = report.metrics
    assert "segments" not in m
    assert m["rate_temp_slope_dps_per_c"] == pytest.approx(-0.02, abs=3 * m["rate_temp_slope_se_dps_per_c"])
    assert m["rate_temp_points"] == gyro.TEMPERATURE_BINS and m["rate_temp_r"] < -0.99
    assert report.files["rate_vs_temperature"].exists()
    flat = make_recording(t, np.full(t.size, 25.0), np.zeros(t.size), rate, sensor="gyro", sample_rate_hz=10.0,
                          device_id="c")
    assert "rate_temp_slope_dps_per_c" not in analyse(flat).metrics  # no temperature range: no line


# -- the real PAN recording --------------------------------------------------------------------------
def test_pan_lsm6dsm_cooling(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "import", f"csv={PAN_CSV}", "sensor=gyro", "time=time_s:s", "temperature=temp_c:degC",
                         "output=gyro_x_dps:deg/s", "drop=spike_flag", "device_id=pan-etu-lsm6dsm", "out=rec")
    assert code == 0, err
    assert "6247 samples in 25 segments at 50 Hz, 3 rows dropped where spike_flag is nonzero" in out
    code, _, err = run(capsys, "metrics", "rec/pan_lsm6dsm_tvac_cooling.csv", "out=m", "tracking.enabled=false")
    assert code == 0, err
    m = json.loads(Path("m/metrics.json").read_text())["metrics"]
    assert m["segments"] == 25
    assert m["rate_temp_slope_dps_per_c"] == pytest.approx(0.0298, abs=0.0005)  # PROVENANCE.md
    assert m["rate_temp_r"] > 0.998
    # the logged rad/s column lacks the x0.5 correction of gyro_x_dps: twice the rate after conversion
    logged = import_csv(PAN_CSV, "gyro", {"time_s": "time_s:s", "temperature_c": "temp_c:degC",
                                      "output": "gyro_x_rads_logged:rad/s"}, drop=["spike_flag"])
    dps = read_recording("rec/pan_lsm6dsm_tvac_cooling.csv")
    np.testing.assert_allclose(logged.output, 2.0 * dps.output, rtol=1e-5)


def test_metrics_say_when_the_allan_minimum_is_no_floor(tmp_path: Path) -> None:
    """White rate noise alone: the Allan deviation falls to the last tau read, so the bias
    instability is only an upper bound and the report says so; with a rate random walk the
    curve turns up and the minimum is a floor."""
    t = np.arange(0.0, 3600.0, 0.1)
    rng = np.random.default_rng(5)
    white = rng.normal(0.0, 0.05, t.size)
    walk = white + np.cumsum(rng.normal(0.0, 0.01, t.size))
    reports = {name: analyse(make_recording(t, np.full(t.size, 25.0), np.zeros(t.size), rate, sensor="gyro",
                                            sample_rate_hz=10.0, device_id="w"))
               for name, rate in (("white", white), ("walk", walk))}
    assert reports["white"].metrics["allan_min_is_interior"] == 0.0
    assert any("upper bound" in c for c in reports["white"].conventions)
    assert reports["walk"].metrics["allan_min_is_interior"] == 1.0
    assert not any("upper bound" in c for c in reports["walk"].conventions)
    msra = analyse(make_recording(t, np.full(t.size, 25.0), np.zeros(t.size), 30000.0 + white, sensor="msra",
                                  sample_rate_hz=10.0, device_id="m"))  # the zero-bias report
    assert msra.metrics["allan_min_is_interior"] == 0.0
    assert any("upper bound" in c for c in msra.conventions)


def test_msra_zero_bias_rows_that_cannot_be_computed_are_nan_with_the_reason() -> None:
    rng = np.random.default_rng(6)
    short_t = np.arange(0.0, 600.0, 1.0)  # 10 min: only the zero-start row has data
    short = analyse(make_recording(short_t, np.full(short_t.size, 25.0), np.zeros(short_t.size),
                                   30000.0 + rng.normal(0.0, 0.01, short_t.size), sensor="msra",
                                   sample_rate_hz=1.0, device_id="s"))
    assert np.isfinite(short.metrics["zero_start_ug"])
    assert np.isnan(short.metrics["after_30min_ug"]) and np.isnan(short.metrics["after_20min_ug"])
    assert sum("not computed" in c for c in short.conventions) == 2
    # 25 bursts of 5 s at 50 Hz: no 10 s window fits inside a burst, and none may span a gap
    burst_t = np.concatenate([300.0 * k + np.arange(0.0, 5.0, 0.02) for k in range(25)])
    bursts = analyse(make_recording(burst_t, np.full(burst_t.size, 25.0), np.zeros(burst_t.size),
                                    30000.0 + rng.normal(0.0, 0.01, burst_t.size), sensor="msra",
                                    sample_rate_hz=50.0, device_id="b"))
    assert np.isnan(bursts.metrics["zero_start_ug"]) and bursts.metrics["segments"] == 25
    assert np.isfinite(bursts.metrics["bias_instability_ug"])
